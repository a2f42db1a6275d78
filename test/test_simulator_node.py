"""
Tests of the simulator node over real DDS: in-process, then as a process.

In-process, the node (``SimulatorNode``) and a :class:`SimProbe` share one
rclpy context and the EventsExecutor the node runs on; messages still go
through Fast DDS. The step timer runs in real time (1 kHz by default), so
the tests compare by step count: the ``steps`` value of the diagnostics
says how many steps were integrated, and the same number of
:meth:`plant.Plant.step` calls must give the same floats.

As a process, the console script ``simulator`` is started as a user runs
it and stopped with SIGINT, as Ctrl-C does.
"""

import math
import os
import time

import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model import mujoco_plant
from orthoglide_ros.model.plant import Plant
from orthoglide_ros.cores.simulator import MAX_CATCH_UP
from orthoglide_ros.ros.simulator_node import SimulatorNode

from node_checks import needs_scripts
from orthoglide_testing.messages import header_stamp
from orthoglide_testing.probe import (matched, node_graphs, PROBE_QOS,
                                      spin_for, spin_until,
                                      wait_diagnostics as harness_wait_diagnostics)
from orthoglide_testing.processes import (node_executable, run_to_exit,
                                          start_node_process,
                                          stop_process)

pytestmark = pytest.mark.ros  # DDS and node processes

WAIT = 10.0         # s: generous, the machine is shared
START_WAIT = 40.0   # s for a process to come up and answer
ZERO = (0.0, 0.0, 0.0)
DT = 1e-3           # s: one step at the default rate_hz
STAMP_SLACK = 1e5   # ns: two clock reads per stamp, microseconds apart
JOINT_NAMES = ['slider_a', 'slider_b', 'slider_c']
HOLD = mechanics.solve(Robot(), ZERO).force     # the weight, held at home
ERROR = DiagnosticStatus.ERROR[0]   # a level as the harness's Peer keeps it
DIAGNOSTIC_NAME = 'simulator: Orthoglide simulator'


class SimProbe(Node):
    """
    Sends commands to the simulator and records its outputs.

    ``joint_states``, ``poses``, ``diagnostics``: every message received,
    in order; ``reset()`` calls ``/simulator/reset``.
    """

    def __init__(self, context):
        super().__init__('simulator_probe', context=context)
        self.joint_states = []
        self.poses = []
        self.diagnostics = []
        self.commands = self.create_publisher(Float64MultiArray, 'commands',
                                              PROBE_QOS)
        self.inputs = [
            self.create_subscription(JointState, 'joint_states',
                                     self.joint_states.append, PROBE_QOS),
            self.create_subscription(PoseStamped, 'platform/pose',
                                     self.poses.append, PROBE_QOS),
            self.create_subscription(DiagnosticArray, '/diagnostics',
                                     self._on_diagnostics, PROBE_QOS)]
        self.reset_client = self.create_client(Trigger, '/simulator/reset')

    def _on_diagnostics(self, msg):
        if msg.status[0].name == DIAGNOSTIC_NAME:
            self.diagnostics.append(msg)

    def send(self, values):
        """Publish one command (a list of floats, N)."""
        self.commands.publish(Float64MultiArray(data=list(values)))

    def matched(self):
        """Whether the command topic and every output are matched."""
        return matched((self.commands,), self.inputs)

    def clear(self):
        """Forget every message recorded so far."""
        for messages in (self.joint_states, self.poses, self.diagnostics):
            messages.clear()


@pytest.fixture
def graph(ros_context):
    """Return make(params): the node and a probe, matched; cleaned up."""
    with node_graphs(ros_context, SimulatorNode, SimProbe,
                     lambda probe, node: probe.matched(), WAIT) as make:
        yield make


def wait_diagnostics(g, predicate, timeout=WAIT):
    """Return the first diagnostics status whose values satisfy predicate."""
    return harness_wait_diagnostics(g.executor, g.probe.diagnostics,
                                    predicate, timeout).status[0]


def values(status):
    """Return the ``{key: value}`` of one DiagnosticStatus."""
    return {kv.key: kv.value for kv in status.values}


def send_until(g, command, until, timeout=WAIT, period=0.02):
    """Send ``command`` every ``period`` s until ``until()``, ``timeout`` s."""
    end = time.monotonic() + timeout
    while not until():
        assert time.monotonic() < end, 'not reached while sending'
        g.probe.send(command)
        spin_for(g.executor, period)


def plant_states(force, count, robot=None, start=ZERO, engine=Plant):
    """Return the plant's (position, lambda, lambdadot) after 1..count."""
    plant = engine(robot or Robot(), start, force_limit=1000.0)
    states = []
    for _ in range(count):
        plant.step(force, DT)
        states.append((plant.position, *plant.joint_state()))
    return states


# In-process ------------------------------------------------------------------
def test_held_publishes_every_tick_until_the_first_command(graph):
    """No command: joint states and pose at rest, same stamp, rate_hz grid."""
    rate = 200.0
    g = graph({'rate_hz': rate, 'base_frame': 'world',
               'initial_position': [0.05, -0.03, 0.02]})
    g.probe.clear()
    joints, poses = g.probe.joint_states, g.probe.poses
    assert spin_until(g.executor, lambda: len(joints) >= 50
                      and len(poses) >= 50, WAIT), (len(joints), len(poses))
    expected = mechanics.solve(Robot(), (0.05, -0.03, 0.02))
    for msg in joints:
        assert list(msg.name) == JOINT_NAMES
        assert tuple(msg.position) == expected.lambda_
        assert tuple(msg.velocity) == ZERO and tuple(msg.effort) == ZERO
    for msg in poses:
        assert msg.header.frame_id == 'world'
        p, q = msg.pose.position, msg.pose.orientation
        assert (p.x, p.y, p.z) == (0.05, -0.03, 0.02)
        assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 1.0)
    # One stamp per tick, the same on both outputs (pairs by stamp: a
    # message lost on one topic must not shift the comparison).
    joint_stamps = [header_stamp(m) for m in joints]
    pose_stamps = {header_stamp(m) for m in poses}
    assert len(set(joint_stamps)) == len(joint_stamps)
    shared = pose_stamps.intersection(joint_stamps)
    assert len(shared) >= 0.9 * min(len(joints), len(poses)), len(shared)
    # The rate, from the stamps (each its tick's grid time): never two
    # states within a period, and most one period apart (a stall past
    # MAX_CATCH_UP ticks, time dropped, or a lost state leaves a longer gap).
    # The first stamp is left out: the node's first clock offset is taken
    # however long its clock read took.
    period = 1e9 / rate
    gaps = [(s2 - s1) * 10**9 + n2 - n1
            for (s1, n1), (s2, n2) in zip(joint_stamps, joint_stamps[1:])]
    assert min(gaps[1:]) >= period - STAMP_SLACK, gaps
    on_grid = sum(abs(gap - period) <= STAMP_SLACK for gap in gaps)
    assert on_grid > len(gaps) / 2, gaps
    status = wait_diagnostics(g, lambda v: True)
    v = values(status)
    if status.level == DiagnosticStatus.WARN:
        # The machine, not the node: on a loaded machine this in-process
        # node may fall behind its grid, which it says, and nothing else
        # (beside a parallel neighbour and the pure set, 2026-12-06).
        assert float(v['time dropped (s)']) > 0.0
        assert status.message.startswith('slower than real time'), \
            status.message
    else:
        assert status.level == DiagnosticStatus.OK
        assert status.message == 'held: waiting for a command'
    assert (v['state'], v['steps'], v['sim time (s)']) == ('held', '0', '0')
    assert g.node.core.plant.time == 0.0


def test_static_holding_force_keeps_the_platform_at_home(graph):
    """
    mechanics.solve's force at rest at home holds the platform there.

    Bound 1e-9 m on lambda: the holding force, sent as float64, gives an
    acceleration at rounding level (about eps * g = 2e-15 m/s^2), which
    the open-loop instability (growth e^(3.5 t), x6 over 0.5 s) cannot
    carry anywhere near 1e-9 m; measured: exactly 0.
    """
    g = graph()

    def holding():
        return [m for m in g.probe.joint_states if tuple(m.effort) == HOLD]
    # 0.5 s of simulated time, however long this process takes to send it.
    send_until(g, HOLD, lambda: g.node.core.steps >= 500
               and len(holding()) > 100)
    wait_diagnostics(g, lambda v: int(v['steps']) > 100)
    running = holding()
    worst = max(abs(c) for m in running for c in (*m.position, *m.velocity))
    assert worst <= 1e-9, worst
    assert g.node.core.clipped == 0


# serial: a stall of this process past the 0.2 s command timeout brakes the
# plant, and its step count is judged.
@pytest.mark.serial
def test_constant_command_follows_the_plant_step_for_step(graph):
    """
    A command held until the timeout = Plant.step with dt = 1 ms, N times.

    N is the node's step count (diagnostics ``steps``); every published
    running state equals the Plant's state after as many steps, exactly,
    in order; after the timeout the last state is held at rest.
    """
    g = graph({'command_timeout': 0.2})
    force = (HOLD[0] + 20.0, HOLD[1] - 10.0, HOLD[2] + 5.0)
    g.probe.send(force)
    status = wait_diagnostics(g, lambda v: v['timeouts'] == '1')
    steps = int(values(status)['steps'])
    assert status.level == DiagnosticStatus.WARN
    assert values(status)['state'] == 'held'
    # 0.2 s of timeout at 1 kHz: about 200 steps, fewer if ticks are late.
    assert 20 <= steps <= 260, steps
    assert float(values(status)['sim time (s)']) == pytest.approx(
        steps * DT, rel=1e-5)
    states = plant_states(force, steps)
    index = {state[0]: k for k, state in enumerate(states)}
    spin_for(g.executor, 0.1)
    poses = {header_stamp(p): p for p in g.probe.poses}
    running = [(m, poses[header_stamp(m)]) for m in g.probe.joint_states
               if tuple(m.effort) == force and header_stamp(m) in poses]
    # One state per tick, the last of the steps it made: at most
    # MAX_CATCH_UP steps per tick when ticks are late (a busy machine).
    assert len(running) >= steps / MAX_CATCH_UP, (len(running), steps)
    previous = -1
    for joints, pose in running:
        p = pose.pose.position
        k = index[(p.x, p.y, p.z)]     # a KeyError: not a Plant state
        assert k > previous
        previous = k
        assert (tuple(joints.position), tuple(joints.velocity)) == \
            states[k][1:]
    # The last running state: the last step, unless the tick that timed out
    # also caught up steps (it publishes the held state only).
    assert steps - MAX_CATCH_UP <= previous + 1 <= steps
    # Real time on a grid: each stamp is its state's instant, so stamps
    # differ by whole steps (to the microseconds between the clock reads);
    # only an overrun (a stall over 10 steps, time dropped) adds more.
    stamps = [(index[(p.pose.position.x, p.pose.position.y,
                      p.pose.position.z)], header_stamp(p))
              for _, p in running]
    gaps = [(s2 - s1) * 10**9 + (n2 - n1) - (k2 - k1) * DT * 1e9
            for (k1, (s1, n1)), (k2, (s2, n2)) in zip(stamps, stamps[1:])]
    assert min(gaps) >= -STAMP_SLACK, min(gaps)
    on_grid = sum(abs(gap) <= STAMP_SLACK for gap in gaps)
    overruns = int(values(wait_diagnostics(g, lambda v: True))[
        'overruns (time dropped)'])
    assert on_grid >= len(gaps) - overruns, (on_grid, len(gaps), overruns)
    now = g.node.get_clock().now().nanoseconds
    last = stamps[-1][1]
    assert 0 < now - (last[0] * 10**9 + last[1]) < 10 * 10**9
    held = g.probe.joint_states[-1]
    assert tuple(held.position) == states[-1][1]
    assert tuple(held.velocity) == ZERO and tuple(held.effort) == ZERO
    assert g.node.core.plant.position == states[-1][0]


@pytest.mark.skipif(bool(mujoco_plant.unavailable()),
                    reason=mujoco_plant.unavailable() or 'ok')
def test_mujoco_engine_follows_its_plant_step_for_step(graph):
    """
    With engine mujoco: the same rules, MuJoCo's states, step for step.

    A command held until the timeout: every published running state is
    the MujocoPlant's after as many steps, in order, exactly; then held.
    """
    g = graph({'command_timeout': 0.2, 'engine': 'mujoco'})
    force = (HOLD[0] + 20.0, HOLD[1] - 10.0, HOLD[2] + 5.0)
    g.probe.send(force)
    status = wait_diagnostics(g, lambda v: v['timeouts'] == '1')
    assert values(status)['engine'] == 'mujoco'
    steps = int(values(status)['steps'])
    states = plant_states(force, steps, engine=mujoco_plant.MujocoPlant)
    index = {state[1]: k for k, state in enumerate(states)}
    running = [m for m in g.probe.joint_states if tuple(m.effort) == force]
    assert len(running) >= steps / MAX_CATCH_UP, (len(running), steps)
    order = [index[tuple(m.position)] for m in running]
    assert order == sorted(order) and order[-1] >= steps - MAX_CATCH_UP
    for m, k in zip(running, order):
        assert tuple(m.velocity) == states[k][2]
    assert tuple(g.probe.joint_states[-1].velocity) == ZERO


def test_publish_rate_samples_the_steps(graph):
    """
    publish_rate_hz 250 at rate_hz 1000: a state every fourth step.

    The physics keeps its 1 ms step (every published state is the Plant's
    after as many 1 ms steps); at most one state per 4 ms of the publish
    grid, and at least one per tick (MAX_CATCH_UP steps at most). An
    overrun (time dropped on a busy machine) moves the grid on without
    steps: each may put two published states four steps apart or less,
    and the grid's periods are those of the steps and the time dropped.
    """
    every = 4
    g = graph({'command_timeout': 0.2, 'publish_rate_hz': 1000.0 / every})
    force = (HOLD[0] + 20.0, HOLD[1] - 10.0, HOLD[2] + 5.0)
    g.probe.send(force)
    status = wait_diagnostics(g, lambda v: v['timeouts'] == '1')
    assert values(status)['publish_rate_hz'] == '250'
    steps = int(values(status)['steps'])
    states = plant_states(force, steps)
    index = {state[0]: k for k, state in enumerate(states)}
    spin_for(g.executor, 0.1)
    poses = {header_stamp(p): p for p in g.probe.poses}
    published = []
    for joints in g.probe.joint_states:
        pose = poses.get(header_stamp(joints))
        if tuple(joints.effort) != force or pose is None:
            continue
        p = pose.pose.position
        k = index[(p.x, p.y, p.z)]     # a KeyError: not a Plant state
        assert (tuple(joints.position), tuple(joints.velocity)) == \
            states[k][1:]
        published.append(k)
    # The grid's time: the steps made and the time dropped in overruns.
    dropped = round(float(values(status)['time dropped (s)']) * 1000.0)
    assert steps / MAX_CATCH_UP <= len(published) <= \
        (steps + dropped) / every + 2, (len(published), steps, dropped)
    periods = [(k - published[0]) // every for k in published]
    overruns = int(values(status)['overruns (time dropped)'])
    close = sum(b <= a for a, b in zip(periods, periods[1:]))
    assert close <= overruns, (published, overruns)


def test_stop_with_clear_error_then_reset(graph, capfd):
    """Out of the workspace: ERROR once, frozen, ignored; ~/reset restores."""
    g = graph({'command_timeout': 1.0})
    push = (1000.0, 0.0, 0.0)
    g.probe.send(push)
    status = wait_diagnostics(g, lambda v: v['state'] == 'stopped')
    assert status.level == DiagnosticStatus.ERROR
    assert status.message.startswith(
        'stopped: simulation stopped at position [')
    assert '(singular)' in status.message and '~/reset' in status.message
    v = values(status)
    assert v['state'] == 'stopped'
    core = g.node.core
    frozen = core.plant.position
    assert mechanics.workspace_status(Robot(), frozen).ok
    # Commands are ignored, the frozen state is published at rest.
    g.probe.send(HOLD)
    g.probe.send(HOLD)
    g.probe.clear()
    status = wait_diagnostics(
        g, lambda v: v['commands ignored (stopped)'] == '2')
    assert status.level == DiagnosticStatus.ERROR
    assert spin_until(g.executor, lambda: g.probe.joint_states, WAIT)
    lam = mechanics.solve(Robot(), frozen).lambda_
    for msg in g.probe.joint_states:
        assert tuple(msg.position) == lam
        assert tuple(msg.velocity) == ZERO and tuple(msg.effort) == ZERO
    log = capfd.readouterr().err
    assert log.count('simulation stopped at position') == 1, log
    assert '[ERROR]' in log
    # ~/reset: back home at rest, held, OK.
    assert g.probe.reset_client.wait_for_service(timeout_sec=WAIT)
    future = g.probe.reset_client.call_async(Trigger.Request())
    assert spin_until(g.executor, future.done, WAIT)
    answer = future.result()
    assert answer.success, answer.message
    assert 'initial_position [0.0, 0.0, 0.0] m' in answer.message
    g.probe.clear()
    status = wait_diagnostics(g, lambda v: v['state'] == 'held')
    # The stop's ERROR is gone; the period that held the reset may still
    # report a lag of the steps (a loaded machine), the only WARN left.
    if status.level == DiagnosticStatus.WARN:
        assert status.message.startswith('slower than real time'), \
            status.message
    else:
        assert status.level == DiagnosticStatus.OK
        assert status.message == 'held: waiting for a command'
    assert spin_until(g.executor, lambda: g.probe.joint_states, WAIT)
    assert tuple(g.probe.joint_states[-1].position) == ZERO
    assert core.plant.position == ZERO and core.plant.time == 0.0
    # It runs again.
    send_until(g, HOLD, lambda: core.state == 'running')


def test_bad_commands_rejected_by_reason(graph):
    """Wrong length or non-finite: counted, warned, never applied."""
    g = graph()
    g.probe.send([1.0, 2.0])
    g.probe.send([math.nan, 0.0, 300.0])
    g.probe.send([0.0, math.inf, 300.0, 1.0])
    status = wait_diagnostics(g, lambda v: v['rejected length'] ==
                              '2' and v['rejected non_finite'] == '1')
    assert status.level == DiagnosticStatus.WARN
    assert values(status)['state'] == 'held'
    assert values(status)['commands received'] == '0'
    assert g.node.core.steps == 0


def test_joint_commands_by_name_like_topic_based_ros2_control(graph):
    """
    A JointState on joint_commands: efforts picked by joint name.

    The order of the names does not matter and other joints are ignored;
    a command missing a slider or with efforts not matching its names is
    refused by reason and never applied.
    """
    g = graph()
    publisher = g.probe.create_publisher(JointState, 'joint_commands',
                                         PROBE_QOS)
    assert spin_until(g.executor, lambda: publisher.get_subscription_count(),
                      WAIT)
    names = ['slider_c', 'gripper', 'slider_a', 'slider_b']
    publisher.publish(JointState(name=names[:3], effort=[1.0, 2.0, 3.0]))
    publisher.publish(JointState(name=names, effort=[1.0, 2.0]))
    status = wait_diagnostics(g, lambda v: v['rejected missing_joint'] ==
                              '1' and v['rejected malformed'] == '1')
    assert values(status)['commands received'] == '0'
    command = (HOLD[2], 0.0, HOLD[0], HOLD[1])
    publisher.publish(JointState(name=names, effort=list(command)))
    assert spin_until(g.executor, lambda: any(
        tuple(m.effort) == HOLD for m in g.probe.joint_states), WAIT)


def test_parameter_changes_live_and_at_reset(graph):
    """joint_limits apply at once, robot.* at ~/reset, bad ones refused."""
    g = graph()
    node = g.node
    results = node.set_parameters([Parameter('rate_hz', value=-1.0)])
    assert not results[0].successful and 'rate_hz' in results[0].reason
    results = node.set_parameters([Parameter('initial_position',
                                             value=[0.9, 0.0, 0.0])])
    assert not results[0].successful
    assert 'initial_position' in results[0].reason
    results = node.set_parameters([Parameter(
        'joint_limits.slider_c.max_effort', value=100.0),
                                   Parameter('robot.m5', value=20.0),
                                   Parameter('rate_hz', value=500.0)])
    assert all(r.successful for r in results)
    clipped = (0.0, 0.0, 100.0)
    send_until(g, HOLD, lambda: any(tuple(m.effort) == clipped
                                    for m in g.probe.joint_states))
    core = node.core
    assert core.plant.robot == Robot() and core.pending_reset
    assert core.clipped > 0
    wait_diagnostics(g, lambda v: v['pending reset'] == 'true'
                     and v['rate_hz'] == '500')
    future = g.probe.reset_client.call_async(Trigger.Request())
    assert spin_until(g.executor, future.done, WAIT)
    assert future.result().success and 'applied' in future.result().message
    assert core.plant.robot == Robot(m5=20.0) and not core.pending_reset


# As a process ----------------------------------------------------------------
def simulator_command():
    """Return the command line of the installed console script."""
    return [node_executable('simulator')]


needs_script = needs_scripts('simulator')


@needs_script
@pytest.mark.parametrize('argument, word', [
    ('rate_hz:=-1.0', 'rate_hz'),
    ('initial_position:=[0.9, 0.0, 0.0]', 'initial_position'),
])
def test_process_invalid_parameter_exits_2(argument, word):
    """An invalid start-up parameter: FATAL naming it, exit code 2."""
    code, stderr = run_to_exit(['--ros-args', '-p', argument],
                               simulator_command(), START_WAIT)
    assert code == 2, f'exit code {code}; stderr:\n{stderr}'
    assert 'FATAL' in stderr and word in stderr, stderr
    assert 'Traceback' not in stderr, stderr


@needs_script
@pytest.mark.skipif(bool(mujoco_plant.unavailable()),
                    reason=mujoco_plant.unavailable() or 'ok')
def test_process_mujoco_divergence_is_an_error_and_publishes_nothing(
        tmp_path):
    """
    Under absurd masses and forces MuJoCo diverges; the node says so.

    ``engine:=mujoco``, every mass 1e-6 kg, each ``max_effort`` 1e6 N, +-1e6 N
    commands every 10 ms, the process in an empty working directory:
    diagnostics ERROR ``diverged: ...`` with MuJoCo's reason, no step
    counted, no state published from the push on (none ever with its
    effort), one ERROR log line, no ``MUJOCO_LOG.TXT`` and no MuJoCo
    warning on the output; ``~/reset`` brings the states back, held.
    """
    from orthoglide_testing.hostile.peer import Peer
    light = [arg for i in range(1, 7) for arg in ('-p', f'robot.m{i}:=1e-6')]
    limits = [arg for joint in ('slider_a', 'slider_b', 'slider_c')
              for arg in ('-p', f'joint_limits.{joint}.max_effort:=1e6')]
    proc = start_node_process(
        ['--ros-args', '-p', 'engine:=mujoco', *limits, *light],
        command=simulator_command(), cwd=str(tmp_path))
    try:
        with Peer() as peer:
            states = peer.record('joint_states', JointState)
            commands = peer.publisher(Float64MultiArray, 'commands')
            assert peer.wait(lambda: len(states) > 10, START_WAIT)
            end = time.monotonic() + START_WAIT
            found, k = None, 0
            while time.monotonic() < end:
                sign = 1.0 if k % 2 == 0 else -1.0
                commands.publish(Float64MultiArray(
                    data=[sign * 1e6, -sign * 1e6, sign * 1e6]))
                k += 1
                time.sleep(0.01)
                found = peer.diagnostics.get('simulator')
                if found and found[2].get('state') == 'diverged':
                    break
            assert found and found[2].get('state') == 'diverged', found
            level, message, v = found[:3]
            assert level == ERROR
            assert message.startswith('diverged: the mujoco engine diverged')
            assert 'Nan, Inf or huge value in QACC' in message, message
            assert '~/reset' in message
            assert (v['steps'], v['divergences'], v['sim time (s)']) == (
                '0', '1', '0'), v
            # Nothing published since the push: commands go on for 1 s.
            time.sleep(0.2)
            published = len(states)
            end = time.monotonic() + 1.0
            while time.monotonic() < end:
                commands.publish(Float64MultiArray(data=[1e6, -1e6, 1e6]))
                time.sleep(0.01)
            assert len(states) == published, (len(states), published)
            assert not any(any(m.effort) for _, m in states)
            status = peer.status('simulator', timeout=WAIT)
            assert status[0] == ERROR
            assert int(status[2]['commands ignored (stopped)']) > 0
            # The way out: ~/reset, held at home, states published again.
            answer = peer.call(Trigger, '/simulator/reset', Trigger.Request(),
                               WAIT)
            assert answer is not None and answer.success, answer
            assert peer.wait(lambda: len(states) > published + 10, WAIT)
            status = peer.status('simulator', timeout=WAIT)
            assert status[2]['state'] == 'held', status
    finally:
        code, stderr = stop_process(proc)
    assert code == 0, stderr
    assert stderr.count('[ERROR]') == 1, stderr
    assert stderr.count('diverged after time') == 1, stderr
    assert 'WARNING: Nan' not in stderr, stderr
    assert os.listdir(tmp_path) == []
