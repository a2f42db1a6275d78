"""
Tests of the tracking_controller node over real DDS, in-process and as a process.

In-process: the node (``TrackingControllerNode``) and a :class:`TrackingProbe`
share one rclpy context and one EventsExecutor; messages still go through
Fast DDS. The probe sends a measurement, waits until the node has taken it,
then sends a desired state and waits for the command, so each command's
inputs are known exactly. The commands are checked against the law computed
here (to floating-point rounding). As a process: the console script starts,
answers, exits 0 on SIGINT and 2 on an invalid parameter.
"""

import math
import time

import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from orthoglide_ros.cores.parameters import joint_limit_values
from orthoglide_ros.cores.tracking_controller import INPUTS, PARAMETERS, REASONS
from orthoglide_ros.ros.tracking_controller_node import TrackingControllerNode

from node_checks import assert_declared, needs_scripts
from orthoglide_testing.messages import diagnostic_values
from orthoglide_testing.probe import (call, matched, node_graphs,
                                      parameter_client, PROBE_QOS,
                                      spin_for, spin_until,
                                      wait_diagnostics as harness_wait_diagnostics)
from orthoglide_testing.processes import node_executable, run_to_exit

pytestmark = pytest.mark.ros  # DDS and node processes

WAIT = 10.0         # s: generous, the machine is shared
START_WAIT = 40.0   # s for a process to come up and answer
NAMES = ['slider_a', 'slider_b', 'slider_c']
ZERO = (0.0, 0.0, 0.0)
NAN = float('nan')
DIAGNOSTIC_NAME = 'tracking_controller: Orthoglide tracking controller'
# A slow machine must not make the measurement stale between the two
# messages of a lock-step exchange; the stale tests set their own. The law
# is checked with errors far beyond the path tolerance and pauses beyond
# stall_timeout: both off here (their own tests are in test_tracking.py and
# test_hostile_peers.py).
PATIENT = {'measurement_timeout': 30.0, 'path_tolerance': [0.0, 0.0, 0.0],
           'stall_timeout': 0.0}
EFFORT = 'joint_limits.slider_a.max_effort'


class TrackingProbe(Node):
    """Publishes desired and measured joint states; records the outputs."""

    def __init__(self, context, name='tracking_probe'):
        super().__init__(name, context=context)
        self.pub_desired = self.create_publisher(
            JointState, 'feedforward/joint_states', PROBE_QOS)
        self.pub_measured = self.create_publisher(
            JointState, 'joint_states', PROBE_QOS)
        self.pub_trajectory = self.create_publisher(
            JointTrajectory, 'joint_trajectory', PROBE_QOS)
        self.commands = []
        self.diagnostics = []
        self.sub_commands = self.create_subscription(
            Float64MultiArray, 'commands', self.commands.append, PROBE_QOS)
        self.sub_diagnostics = self.create_subscription(
            DiagnosticArray, '/diagnostics', self.diagnostics.append,
            PROBE_QOS)

    def matched(self):
        """Whether both inputs and both outputs are matched."""
        return matched(
            (self.pub_desired, self.pub_measured, self.pub_trajectory),
            (self.sub_commands, self.sub_diagnostics))

    def send(self, which, position, velocity=ZERO, effort=None,
             names=NAMES):
        """Publish one JointState on ``which`` ('desired' or 'measured')."""
        msg = JointState()
        msg.name = list(names)
        msg.position = [float(x) for x in position]
        msg.velocity = [float(x) for x in velocity]
        msg.effort = [float(x) for x in (effort or ())]
        (self.pub_desired if which == 'desired'
         else self.pub_measured).publish(msg)


def _matched(probe, node):
    return probe.matched() and all(
        p.get_subscription_count() > 0 for p in node.publishers
        if p.topic_name != '/parameter_events')


@pytest.fixture
def graph(ros_context):
    """Return make(params): the node and a probe, matched; cleaned up after."""
    with node_graphs(ros_context, TrackingControllerNode, TrackingProbe,
                     _matched, WAIT) as make:
        yield make


def received(g, source):
    """Return how many ``source`` joint states the node has taken."""
    with g.node.lock:
        return g.node.core.received[source]


def measure(g, position, velocity=ZERO, names=NAMES):
    """Send a measurement and wait until the node has taken it."""
    before = received(g, 'measured')
    g.probe.send('measured', position, velocity, names=names)
    assert spin_until(g.executor, lambda: received(g, 'measured') > before,
                      WAIT), 'the node did not take the measurement'


def command(g, position, velocity=ZERO, effort=ZERO, names=NAMES):
    """Send a desired state; return the command it produced."""
    count = len(g.probe.commands)
    g.probe.send('desired', position, velocity, effort, names=names)
    assert spin_until(g.executor, lambda: len(g.probe.commands) > count,
                      WAIT), 'no command'
    assert len(g.probe.commands) == count + 1
    return g.probe.commands[-1]


def no_command(g, position, velocity=ZERO, effort=ZERO, names=NAMES):
    """Send a desired state; check the node took it and commanded nothing."""
    count = len(g.probe.commands)
    before = received(g, 'desired')
    g.probe.send('desired', position, velocity, effort, names=names)
    assert spin_until(g.executor, lambda: received(g, 'desired') > before,
                      WAIT), 'the node did not take the desired state'
    spin_for(g.executor, 0.1)
    assert len(g.probe.commands) == count


def law(kp, kd, lam_d, dlam_d, f_ff, lam, dlam, limit=1000.0):
    """Return the forces and their rounding bounds, computed here."""
    forces, bounds = [], []
    for i in range(3):
        terms = [kp[i] * (lam_d[i] - lam[i]), kd[i] * (dlam_d[i] - dlam[i])]
        if f_ff is not None:
            terms.append(f_ff[i])
        forces.append(min(max(math.fsum(terms), -limit), limit))
        bounds.append(8 * 2.0 ** -52 * sum(abs(t) for t in terms))
    return forces, bounds


def assert_command(msg, expected):
    """Check a command's layout and its forces to rounding."""
    forces, bounds = expected
    assert len(msg.layout.dim) == 1
    dim = msg.layout.dim[0]
    assert (dim.label, dim.size, dim.stride) == ('actuator', 3, 3)
    assert msg.layout.data_offset == 0
    data = list(msg.data)
    assert len(data) == 3
    for got, want, bound in zip(data, forces, bounds):
        assert abs(got - want) <= bound, (data, forces)


def wait_diagnostics(g, predicate, timeout=WAIT):
    """Spin until a diagnostics message satisfies ``predicate(values)``."""
    return harness_wait_diagnostics(g.executor, g.probe.diagnostics,
                                    predicate, timeout)


# Joint trajectories ----------------------------------------------------------
def joint_trajectory(times, positions, efforts, names=NAMES):
    """Build a JointTrajectory with a zero stamp (start on reception)."""
    msg = JointTrajectory(joint_names=list(names))
    for t, p, e in zip(times, positions, efforts):
        point = JointTrajectoryPoint(positions=[float(x) for x in p],
                                     velocities=[0.0] * len(names),
                                     effort=[float(x) for x in e])
        point.time_from_start.sec, point.time_from_start.nanosec = divmod(
            round(t * 1e9), 10**9)
        msg.points.append(point)
    return msg


def test_joint_trajectory_followed_then_held_and_a_bad_one_refused(graph):
    """
    The loop samples the trajectory and applies the law; its end is held.

    At rest at 0 with Kp = 100 N/m, Kd = 0: once the trajectory's last
    point (0.01 m, 7 N) is reached, every command is 7 + 100 * 0.01 N. A
    trajectory without one of the joints is refused and counted; the one
    followed goes on.
    """
    g = graph({**PATIENT, 'kp': [100.0] * 3, 'kd': [0.0] * 3,
               'rate_hz': 100.0})
    measure(g, ZERO)
    g.probe.pub_trajectory.publish(joint_trajectory(
        [0.1, 0.2], [ZERO, (0.01,) * 3], [(5.0,) * 3, (7.0,) * 3]))
    end = law([100.0] * 3, [0.0] * 3, (0.01,) * 3, ZERO, (7.0,) * 3, ZERO,
              ZERO)

    def held():
        return (len(g.probe.commands) > 0
                and list(g.probe.commands[-1].data) == end[0])
    # A plant at rest: the measurements keep coming (the plan is sampled
    # at the newest one's arrival).
    deadline = time.monotonic() + WAIT
    while not held() and time.monotonic() < deadline:
        measure(g, ZERO)
        spin_for(g.executor, 0.01)
    assert held(), g.probe.commands[-1:]
    assert_command(g.probe.commands[-1], end)
    g.probe.pub_trajectory.publish(joint_trajectory(
        [0.1], [(0.5,) * 2], [(1.0,) * 2], names=NAMES[:2]))
    values = wait_diagnostics(g, lambda v: v.get(
        'rejected trajectory missing_joint') == '1')
    values = diagnostic_values(values)
    assert values['trajectories received'] == '1'
    assert values['trajectory'] == 'holding its last point'
    count = len(g.probe.commands)
    measure(g, ZERO)
    assert spin_until(g.executor, lambda: len(g.probe.commands) > count,
                      WAIT), 'no command after the refused trajectory'
    assert_command(g.probe.commands[-1], end)


# The law ---------------------------------------------------------------------
def test_law_exact_on_published_commands(graph):
    """Each command is f_ff + Kp e + Kd edot of its inputs (defaults)."""
    g = graph(PATIENT)
    kp, kd = [20000.0] * 3, [1200.0] * 3
    for k in range(12):
        t = 0.1 * k
        lam = (0.01 * math.sin(t), -0.02 * math.cos(t), 0.005 * t)
        dlam = (0.1 * math.cos(t), 0.05 * math.sin(t), -0.03)
        lam_d = tuple(x + 1e-3 * (i + 1) * math.cos(3 * t)
                      for i, x in enumerate(lam))
        dlam_d = tuple(x - 2e-2 * math.sin(t + i) for i, x in enumerate(dlam))
        f_ff = (40.0 * math.sin(t), -25.0, 60.0 * math.cos(2 * t))
        measure(g, lam, dlam)
        msg = command(g, lam_d, dlam_d, f_ff)
        assert_command(msg, law(kp, kd, lam_d, dlam_d, f_ff, lam, dlam))
    core = g.node.core
    assert core.commands == 12 and core.clipped == 0
    assert not any(core.rejected.values())
    assert not any(core.skipped.values())


def test_joint_names_matched_in_any_order(graph):
    """Messages in any order, with extra joints; commands in joint_names order."""
    names = ['ax', 'by', 'cz']
    g = graph({**PATIENT, 'joint_names': names,
               'kp': [100.0, 200.0, 300.0], 'kd': [1.0, 2.0, 3.0]})
    # Measured: c, extra, a, b.  Desired: b, c, a, extra.
    measure(g, (0.3, 9.0, 0.1, 0.2), (0.03, 9.0, 0.01, 0.02),
            names=['cz', 'extra', 'ax', 'by'])
    msg = command(g, (0.25, 0.5, 0.0, 7.0), (0.0, 0.0, 0.0, 7.0),
                  (20.0, 30.0, 10.0, 7.0), names=['by', 'cz', 'ax', 'extra'])
    # a: 10 + 100*(0 - 0.1) + 1*(0 - 0.01); b: 20 + 200*0.05 + 2*(-0.02);
    # c: 30 + 300*0.2 + 3*(-0.03).
    assert_command(msg, law([100.0, 200.0, 300.0], [1.0, 2.0, 3.0],
                            (0.0, 0.25, 0.5), ZERO, (10.0, 20.0, 30.0),
                            (0.1, 0.2, 0.3), (0.01, 0.02, 0.03)))
    assert list(msg.data) == pytest.approx([-0.01, 29.96, 89.91])


def test_feedforward_off_is_pd_alone(graph):
    """With feedforward false, efforts are ignored and not needed at all."""
    g = graph({**PATIENT, 'feedforward': False})
    lam, dlam = (0.1, 0.2, 0.3), (0.0, 0.1, -0.1)
    lam_d, dlam_d = (0.101, 0.199, 0.3), (0.01, 0.1, 0.0)
    measure(g, lam, dlam)
    expected = law([20000.0] * 3, [1200.0] * 3, lam_d, dlam_d, None, lam,
                   dlam)
    assert_command(command(g, lam_d, dlam_d, (500.0, 500.0, 500.0)),
                   expected)
    assert_command(command(g, lam_d, dlam_d, effort=None), expected)
    assert not any(g.node.core.rejected.values())


def test_clipping_counted(graph):
    """Forces beyond max_effort are clipped to it and counted."""
    g = graph({**PATIENT, **joint_limit_values('max_effort', 50.0)})
    measure(g, ZERO)
    msg = command(g, (0.01, -0.01, 0.0001), ZERO, (0.0, 0.0, 1.0))
    assert list(msg.data) == [50.0, -50.0, pytest.approx(3.0)]
    assert g.node.core.clipped == 2
    wait_diagnostics(g, lambda d: d['clipped forces'] == '2')


# Timing ----------------------------------------------------------------------
def test_missing_then_stale_measurement_commands_nothing(graph):
    """No measurement yet, or an old one: no command, counted, WARN."""
    # Longer than this process is ever descheduled between a measurement
    # and the desired state that must find it fresh.
    timeout = 2.0
    g = graph({**PATIENT, 'measurement_timeout': timeout})
    no_command(g, (0.01, 0.0, 0.0))
    msg = wait_diagnostics(g, lambda d: d['skipped no_measurement'] == '1')
    assert msg.status[0].level == DiagnosticStatus.WARN
    assert 'no measurement yet' in msg.status[0].message
    # Fresh: a command. Then older than the timeout: nothing.
    measure(g, ZERO)
    assert len(command(g, (0.001, 0.0, 0.0)).data) == 3
    spin_for(g.executor, timeout + 0.2)
    no_command(g, (0.001, 0.0, 0.0))
    msg = wait_diagnostics(g, lambda d: d['skipped stale_measurement'] == '1')
    assert msg.status[0].level == DiagnosticStatus.WARN
    assert diagnostic_values(msg)['measurement fresh'] == 'false'
    # A fresh measurement resumes.
    measure(g, ZERO)
    assert list(command(g, (0.001, 0.0, 0.0)).data)[0] == \
        pytest.approx(20.0)
    assert g.node.core.skipped == {'no_measurement': 1,
                                   'stale_measurement': 1,
                                   'trajectory_active': 0, 'inactive': 0}


def test_bad_inputs_rejected_counted_and_node_goes_on(graph):
    """Missing joint, NaN, missing velocity or effort: no command, counted."""
    g = graph(PATIENT)
    core = g.node.core
    measure(g, ZERO)
    no_command(g, (0.0, 0.0), names=['slider_a', 'slider_b'])
    no_command(g, (0.0, NAN, 0.0))
    no_command(g, ZERO, velocity=(), effort=ZERO)
    no_command(g, ZERO, effort=None)
    g.probe.send('measured', (NAN, 0.0, 0.0))
    assert spin_until(g.executor, lambda: received(g, 'measured') == 2, WAIT)
    assert core.rejected['desired', 'missing_joint'] == 1
    assert core.rejected['desired', 'non_finite'] == 1
    assert core.rejected['desired', 'missing_velocity'] == 1
    assert core.rejected['desired', 'missing_effort'] == 1
    assert core.rejected['measured', 'non_finite'] == 1
    # The previous measurement stays; the node goes on.
    assert len(command(g, (0.001, 0.0, 0.0)).data) == 3
    msg = wait_diagnostics(
        g, lambda d: d['rejected measured non_finite'] == '1')
    assert msg.status[0].level == DiagnosticStatus.WARN
    assert g.node.internal_errors == 0


def test_internal_error_reported_and_node_goes_on(graph):
    """A defect in a callback: counted, ERROR in diagnostics, node lives."""
    g = graph(PATIENT)
    core = g.node.core
    original = core._command     # what core.desired (the input's) calls

    def broken(*args):
        core._command = original
        raise RuntimeError('injected defect')

    measure(g, ZERO)
    core._command = broken
    g.probe.send('desired', (0.001, 0.0, 0.0), ZERO, ZERO)
    msg = wait_diagnostics(g, lambda d: d['internal errors'] == '1')
    assert msg.status[0].level == DiagnosticStatus.ERROR
    measure(g, ZERO)
    assert len(command(g, (0.001, 0.0, 0.0)).data) == 3


def test_diagnostics_values(graph):
    """Name, keys, rate and the last tracking error per joint."""
    g = graph(PATIENT)
    first = wait_diagnostics(g, lambda d: True)
    status = first.status[0]
    assert status.name == DIAGNOSTIC_NAME
    assert status.hardware_id == 'orthoglide'
    assert (status.level, status.message) == (
        DiagnosticStatus.OK, 'waiting for desired states')
    values = diagnostic_values(first)
    for source in INPUTS:
        for reason in REASONS:
            assert values[f'rejected {source} {reason}'] == '0'
    assert values['tracking error slider_a (m)'] == 'nan'
    measure(g, (0.1, 0.2, 0.3))
    for _ in range(3):
        command(g, (0.1005, 0.199, 0.3))
    msg = wait_diagnostics(g, lambda d: d['commands published'] == '3')
    values = diagnostic_values(msg)
    assert float(values['command rate (Hz)']) > 0.0
    assert float(values['tracking error slider_a (m)']) == \
        pytest.approx(0.0005)
    assert float(values['tracking error slider_b (m)']) == \
        pytest.approx(-0.001)
    assert float(values['tracking error slider_c (m)']) == 0.0
    assert values['feedforward'] == 'true'
    assert values['max_effort A, B, C (N)'] == '1000, 1000, 1000'
    assert msg.status[0].level == DiagnosticStatus.OK


# Parameters ------------------------------------------------------------------
def test_invalid_parameter_changes_refused(graph):
    """Invalid changes are refused with a reason and change nothing."""
    g = graph(PATIENT)
    client = parameter_client(g, 'tracking_controller')
    refused = [
        (Parameter('kp', value=[1.0]), 'kp'),
        (Parameter('kd', value=[1.0, -2.0, 3.0]), 'kd'),
        (Parameter('kd', value=[1.0, NAN, 3.0]), 'kd'),
        (Parameter('joint_names', value=['a', 'a', 'b']), 'joint_names'),
        (Parameter(EFFORT, value=-1.0), None),              # rclpy: range
        (Parameter(EFFORT, value=0.0), EFFORT),             # flag true
        (Parameter('force_limit', value=5.0), None),        # retired
        (Parameter('feedforward', value=1.0), None),        # rclpy: type
        (Parameter('measurement_timeout', value=-1.0), None),
    ]
    for parameter, word in refused:
        response = call(g, client.set_parameters([parameter]))
        result = response.results[0]
        assert not result.successful, parameter.name
        assert result.reason, parameter.name
        if word is not None:
            assert word in result.reason, result.reason
    # Atomically: one bad value refuses the whole set.
    result = call(g, client.set_parameters_atomically([
        Parameter('kp', value=[1.0, 1.0, 1.0]),
        Parameter('kd', value=[1.0]),
    ])).result
    assert not result.successful and 'kd' in result.reason
    values = call(g, client.get_parameters(
        ['kp', 'kd', EFFORT, 'feedforward', 'joint_names'])).values
    assert list(values[0].double_array_value) == [20000.0] * 3
    assert list(values[1].double_array_value) == [1200.0] * 3
    assert values[2].double_value == 1000.0
    assert values[3].bool_value is True
    assert list(values[4].string_array_value) == NAMES
    measure(g, ZERO)
    assert_command(command(g, (0.001, 0.0, 0.0), ZERO, (1.0, 2.0, 3.0)),
                   law([20000.0] * 3, [1200.0] * 3, (0.001, 0.0, 0.0), ZERO,
                       (1.0, 2.0, 3.0), ZERO, ZERO))


def test_valid_change_applied_to_next_command(graph):
    """Gains, feedforward and limit, atomically: the next command uses all."""
    g = graph(PATIENT)
    client = parameter_client(g, 'tracking_controller')
    measure(g, ZERO)
    command(g, (0.001, 0.0, 0.0))
    result = call(g, client.set_parameters_atomically([
        Parameter('kp', value=[10.0, 20.0, 30.0]),
        Parameter('kd', value=[1.0, 2.0, 3.0]),
        Parameter('feedforward', value=False),
        *(Parameter(name, value=value) for name, value in
          joint_limit_values('max_effort', 5.0).items())])).result
    assert result.successful, result.reason
    measure(g, ZERO, (0.5, 0.5, 0.5))
    msg = command(g, (0.1, 0.2, 0.3), ZERO, (100.0, 100.0, 100.0))
    # a: 10*0.1 + 1*(-0.5) = 0.5; b: 4 - 1 = 3; c: 9 - 1.5 = 7.5 -> 5.
    assert_command(msg, law([10.0, 20.0, 30.0], [1.0, 2.0, 3.0],
                            (0.1, 0.2, 0.3), ZERO, None, ZERO,
                            (0.5, 0.5, 0.5), limit=5.0))
    assert list(msg.data)[2] == 5.0


def test_declared_parameters(graph):
    """Every PARAMETERS row is declared with its description."""
    node = graph().node
    assert_declared(node, PARAMETERS)


def test_invalid_start_parameters_raise(ros_context):
    """Construction with an invalid set raises ValueError naming it."""
    for name, value in (('kp', [1.0]), ('joint_names', ['a', 'b'])):
        with pytest.raises(ValueError, match=name):
            TrackingControllerNode(
                context=ros_context,
                parameter_overrides=[Parameter(name, value=value)])


# The console script ----------------------------------------------------------
EXECUTABLE = node_executable('tracking_controller')
needs_script = needs_scripts('tracking_controller')


@needs_script
def test_process_exits_2_on_invalid_parameter():
    """-p kp:=[1.0]: exit 2 and a fatal line naming kp, no traceback."""
    code, stderr = run_to_exit(['--ros-args', '-p', 'kp:=[1.0]'],
                               [EXECUTABLE], START_WAIT)
    assert code == 2, f'exit code {code}; stderr:\n{stderr}'
    assert 'kp' in stderr, stderr
    assert 'Traceback' not in stderr, stderr
