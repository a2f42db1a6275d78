"""
Tests of the feedforward node in the test's own process, over real DDS.

The node (``FeedforwardNode``) and a probe
(:class:`orthoglide_testing.probe.Probe`) share one rclpy context and one
executor (the EventsExecutor the node runs on, unless a test says otherwise);
messages still go through Fast DDS. Setpoints are sent in lock-step: the test
spins until the outputs of one setpoint arrive before it sends the next, so no
message is lost and nothing waits for real time except the timers (rate_hz,
diagnostics at 1 Hz).
"""

import itertools
import math
import time

import pytest
from rclpy.parameter import Parameter
from rclpy.qos import ReliabilityPolicy

from diagnostic_msgs.msg import DiagnosticStatus

from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.feedforward import INPUTS, PARAMETERS, REASONS
from orthoglide_ros.ros.feedforward_node import FeedforwardNode
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import paper_sample, paper_times

from node_checks import assert_declared, assert_vector, close
from orthoglide_testing.messages import (diagnostic_values, header_stamp,
                                         stamp_of)
from orthoglide_testing.probe import (call, node_graphs, parameter_client,
                                      Probe, spin_for, spin_until,
                                      wait_diagnostics as harness_wait_diagnostics)

pytestmark = pytest.mark.ros  # DDS and node processes
WAIT = 10.0     # s: generous, the machine is shared
JOINT_NAMES = ['slider_a', 'slider_b', 'slider_c']
ZERO = (0.0, 0.0, 0.0)
NAN = float('nan')
UNREACHABLE = (0.9, 0.0, 0.0)
NEAR_SINGULAR = (0.84, 0.0, 0.0)
DIAGNOSTIC_NAME = 'feedforward: Orthoglide feedforward'
# Timeouts no stall of this process reaches: for the tests that check the
# pairing itself, not its window (a setpoint's parts can arrive 100 ms and
# more apart on a busy host, past the default 50 ms).
PATIENT = {'setpoint_timeout': 60.0, 'pairing_timeout': 60.0}


@pytest.fixture
def graph(ros_context):
    """Return make(params, executor): the node and a probe, matched."""
    with node_graphs(ros_context, FeedforwardNode, Probe,
                     lambda probe, node: probe.matched(node), WAIT) as make:
        yield make


def assert_layout(msg):
    """Check a Float64MultiArray's layout: one dimension 'actuator' of 3."""
    assert len(msg.layout.dim) == 1
    dim = msg.layout.dim[0]
    assert (dim.label, dim.size, dim.stride) == ('actuator', 3, 3)
    assert msg.layout.data_offset == 0


def assert_output(probe, k, stamp, solution, names=JOINT_NAMES):
    """Check the k-th joint state, forces and power against a Solution."""
    joints, forces, power = (probe.joint_states[k], probe.forces[k],
                             probe.power[k])
    assert header_stamp(joints) == stamp
    assert list(joints.name) == names
    assert_vector(joints.position, solution.lambda_, f'lambda {k}')
    assert_vector(joints.velocity, solution.lambdadot, f'lambdadot {k}')
    assert_vector(joints.effort, solution.force, f'force {k}')
    assert list(forces.data) == list(joints.effort)
    assert_vector(power.data, solution.power, f'power {k}')
    assert_layout(forces)
    assert_layout(power)


def wait_outputs(g, count, timeout=WAIT):
    """Spin until ``count`` joint states, forces and powers have arrived."""
    p = g.probe
    ok = spin_until(g.executor, lambda: min(
        len(p.joint_states), len(p.forces), len(p.power)) >= count, timeout)
    assert ok, (f'expected {count} outputs, got {len(p.joint_states)} joint '
                f'states, {len(p.forces)} forces, {len(p.power)} powers')


def send_paper(g, t, count):
    """Send eq. (6) at ``t`` s, stamped ``t``; wait for ``count`` outputs."""
    sample = paper_sample(t)
    g.probe.send(stamp_of(t), *sample)
    wait_outputs(g, count)
    return sample


def wait_diagnostics(g, predicate, timeout=WAIT):
    """Spin until a diagnostics message satisfies ``predicate(values)``."""
    return harness_wait_diagnostics(g.executor, g.probe.diagnostics,
                                    predicate, timeout)


def duration(t):
    """Return ``t`` seconds as a (sec, nanosec) time_from_start."""
    return divmod(round(t * 1e9), 10**9)


def solve(position, velocity=ZERO, acceleration=ZERO, robot=None):
    """Return mechanics.solve with the paper robot and default margin."""
    return mechanics.solve(robot or Robot(), position, velocity,
                           acceleration)


# The paper trajectory --------------------------------------------------------
@pytest.mark.parametrize('form, executor', [
    ('topics', 'events'), ('trajectory', 'events'), ('topics', 'single')])
def test_paper_trajectory(graph, form, executor):
    """Eq. (6), 50 samples over 2 s: every output equals mechanics.solve."""
    g = graph(PATIENT, executor=executor)
    times = [float(t) for t in paper_times(50)]
    for k, t in enumerate(times):
        p, v, a = paper_sample(t)
        if form == 'topics':
            g.probe.send(stamp_of(t), p, v, a)
        else:   # the stamp is header.stamp + time_from_start
            g.probe.send_trajectory((1000, 0), p, v, a,
                                    time_from_start=duration(t))
        wait_outputs(g, k + 1)
        assert_output(g.probe, k, stamp_of(t), solve(p, v, a))
    spin_for(g.executor, 0.05)
    assert len(g.probe.joint_states) == 50
    assert len(g.probe.forces) == len(g.probe.power) == 50
    core = g.node.core
    assert core.computed == 50
    assert not any(core.rejected.values())


# serial: its 90 ms pairing window lost setpoints beside a parallel
# neighbour (the ros set with -n 2, three runs, 2026-12-05); alone, none.
@pytest.mark.serial
@pytest.mark.parametrize('executor', ['single', 'events'])
def test_inputs_keep_pace_whatever_spins_the_node(graph, executor):
    """
    1000 setpoints in lock-step on the three topics: none lost or late.

    With rmw_fastrtps a reader's QoS events and its data share one status
    condition: an executor waiting on the inputs' events would hide data
    from the input thread for 100 ms and more, and partial setpoints would
    expire (about 1 in 1000 here). A pairing timeout of 90 ms still sees
    that, where the default 50 ms also saw this process descheduled.
    """
    g = graph({'pairing_timeout': 0.09}, executor=executor)
    for k in range(1000):
        t = 0.002 * k
        g.probe.send(stamp_of(t), *paper_sample(t))
        wait_outputs(g, k + 1, timeout=1.0)
    assert g.node.core.rejected['unpaired'] == 0


def test_out_of_order_three_topic_input(graph):
    """Pose, twist and accel pair by stamp whatever their arrival order."""
    g = graph(PATIENT)
    orders = list(itertools.permutations(('pose', 'twist', 'accel')))
    times = [float(t) for t in paper_times(12)]
    for k, (t, order) in enumerate(zip(times, itertools.cycle(orders))):
        p, v, a = paper_sample(t)
        g.probe.send(stamp_of(t), p, v, a, order=order)
        wait_outputs(g, k + 1)
        assert_output(g.probe, k, stamp_of(t), solve(p, v, a))
    # Two stamps interleaved: s2's accel first, s1 completes in between.
    (p1, v1, a1), (p2, v2, a2) = paper_sample(0.3), paper_sample(0.7)
    s1, s2 = stamp_of(10.0), stamp_of(10.0 + 1e-9)
    g.probe.send(s2, p2, v2, a2, order=('accel',))
    g.probe.send(s1, p1, v1, a1, order=('pose', 'twist'))
    g.probe.send(s2, p2, v2, a2, order=('pose',))
    g.probe.send(s1, p1, v1, a1, order=('accel',))
    wait_outputs(g, 13)
    assert_output(g.probe, 12, s1, solve(p1, v1, a1))
    g.probe.send(s2, p2, v2, a2, order=('twist',))
    wait_outputs(g, 14)
    assert_output(g.probe, 13, s2, solve(p2, v2, a2))
    assert not any(g.node.core.rejected.values())


def test_inputs_that_wait_together_are_handled_in_reception_order(graph):
    """
    Pose, twist and accel held back together go to the core as received.

    The node's lock held while two setpoints' parts come interleaved (s2's
    accel first, then s1 whole, then s2's pose and twist): its input thread
    takes them together once the lock is free. Handled input by input
    (every pose, then every twist, then every accel), s2 would complete
    first and drop s1 as unpaired; in reception order both complete.
    """
    g = graph(PATIENT)
    (p1, v1, a1), (p2, v2, a2) = paper_sample(0.3), paper_sample(0.7)
    s1, s2 = stamp_of(10.0), stamp_of(10.0 + 1e-9)
    with g.node.lock:
        g.probe.send(s2, p2, v2, a2, order=('accel',))
        g.probe.send(s1, p1, v1, a1)
        g.probe.send(s2, p2, v2, a2, order=('pose', 'twist'))
        spin_for(g.executor, 0.2)
        assert g.node.core.received == dict.fromkeys(INPUTS, 0)
    wait_outputs(g, 2)
    assert_output(g.probe, 0, s1, solve(p1, v1, a1))
    assert_output(g.probe, 1, s2, solve(p2, v2, a2))
    assert not any(g.node.core.rejected.values())


def test_trajectory_stamps_and_points(graph):
    """Stamp = header.stamp + time_from_start; zero header = now; 1st point."""
    g = graph({'base_frame': 'orthoglide_base'})
    p, v, a = paper_sample(1.0)
    # Nanoseconds carry into seconds.
    g.probe.send_trajectory((100, 900_000_000), p, v, a,
                            frame='orthoglide_base',
                            time_from_start=(0, 150_000_000))
    wait_outputs(g, 1)
    assert_output(g.probe, 0, (101, 50_000_000), solve(p, v, a))
    # Only the first point counts (the second would be refused).
    p2, v2, a2 = paper_sample(1.5)
    g.probe.send_trajectory((200, 0), p2, v2, a2,
                            extra_points=[(UNREACHABLE, ZERO, ZERO)])
    wait_outputs(g, 2)
    assert_output(g.probe, 1, (200, 0), solve(p2, v2, a2))
    # A zero header stamp means "now" (the node's clock), plus the offset.
    before = g.node.get_clock().now().nanoseconds
    g.probe.send_trajectory((0, 0), p, v, a, time_from_start=(0, 500_000_000))
    wait_outputs(g, 3)
    after = g.node.get_clock().now().nanoseconds
    sec, nanosec = header_stamp(g.probe.joint_states[2])
    assert before + 500_000_000 <= sec * 10**9 + nanosec <= after + 500_000_000
    assert_output(g.probe, 2, (sec, nanosec), solve(p, v, a))
    assert not any(g.node.core.rejected.values())


# Bad input -------------------------------------------------------------------
def test_bad_inputs_rejected_counted_and_node_goes_on(graph):
    """Each bad setpoint: no output, one counted rejection, then business."""
    # No timeout in play: a stall of the machine between the parts of a good
    # setpoint must not drop them; the unpaired one is dropped when the next
    # setpoint completes.
    g = graph(PATIENT)
    probe = g.probe
    sent = dict.fromkeys(('pose', 'twist', 'accel', 'trajectory'), 0)
    good_stamps = []
    clock = itertools.count(1)

    def topics(stamp, p, v=ZERO, a=ZERO, order=('pose', 'twist', 'accel'),
               **kwargs):
        probe.send(stamp, p, v, a, order=order, **kwargs)
        for part in order:
            sent[part] += 1

    def trajectory(stamp, p, v=ZERO, a=ZERO, **kwargs):
        probe.send_trajectory(stamp, p, v, a, **kwargs)
        sent['trajectory'] += 1

    def good(form):
        """Send a good setpoint; wait for it: the node went on."""
        t = next(clock) / 10.0
        stamp = stamp_of(t)
        sample = paper_sample(t)
        (topics if form == 'topics' else trajectory)(stamp, *sample)
        good_stamps.append(stamp)
        wait_outputs(g, len(good_stamps))
        assert probe.output_stamps() == good_stamps
        assert_output(probe, len(good_stamps) - 1, stamp, solve(*sample))

    def bad_stamp():
        return stamp_of(next(clock) / 10.0)

    tilted = (0.0, math.sin(0.05), 0.0, math.cos(0.05))    # 0.1 rad
    good('topics')
    topics(bad_stamp(), (NAN, 0.0, 0.0))                    # non_finite
    good('topics')
    trajectory(bad_stamp(), ZERO, a=(0.0, float('inf'), 0.0))  # non_finite
    good('trajectory')
    topics(bad_stamp(), UNREACHABLE)                        # unreachable
    good('topics')
    trajectory(bad_stamp(), NEAR_SINGULAR)                  # singular
    good('trajectory')
    topics(bad_stamp(), ZERO, frame='world')                # frame
    good('topics')
    topics(bad_stamp(), ZERO, orientation=tilted)           # orientation
    good('topics')
    trajectory(bad_stamp(), ZERO, orientation=tilted)       # orientation
    good('trajectory')
    topics((0, 0), ZERO)                                    # stamp x 3
    good('topics')
    topics(bad_stamp(), ZERO, order=('pose', 'twist'))      # unpaired
    good('topics')
    trajectory(bad_stamp(), ZERO, with_point=False)         # malformed
    trajectory(bad_stamp(), ZERO, with_transform=False)     # malformed
    trajectory(bad_stamp(), ZERO, v=None)                   # malformed
    trajectory(bad_stamp(), ZERO, a=None)                   # malformed
    good('trajectory')
    topics(bad_stamp(), ZERO, v=(0.0, 0.0, 6.0))            # speed_limit
    good('topics')
    trajectory(bad_stamp(), ZERO, a=(0.0, 1e200, 0.0))      # acceleration
    good('trajectory')
    expected = {'non_finite': 2, 'speed_limit': 1, 'acceleration_limit': 1,
                'unreachable': 1, 'singular': 1, 'overflow': 0,
                'velocity_limit': 0, 'force_limit': 0, 'frame': 1, 'orientation': 2, 'stamp': 3,
                'malformed': 4, 'oversize': 0, 'unpaired': 1}
    assert set(expected) == set(REASONS)
    n = len(good_stamps)
    msg = wait_diagnostics(g, lambda d: d['setpoints computed'] == str(n)
                           and d['rejected unpaired'] == '1')
    values = diagnostic_values(msg)
    for reason, count in expected.items():
        assert values[f'rejected {reason}'] == str(count), reason
    for name in ('pose', 'twist', 'accel'):
        assert values[f'received {name}'] == str(sent[name]), name
    # (received trajectory: see test_malformed_trajectories_counted_received)
    assert values['outputs published'] == str(n)
    assert values['pending partial setpoints'] == '0'
    spin_for(g.executor, 0.05)
    assert probe.output_stamps() == good_stamps
    assert len(probe.forces) == len(probe.power) == n


def test_malformed_trajectories_counted_received(graph):
    """A trajectory without a usable point is still a received trajectory."""
    g = graph()
    g.probe.send_trajectory(stamp_of(0.1), ZERO, with_point=False)
    g.probe.send_trajectory(stamp_of(0.2), ZERO, with_transform=False)
    g.probe.send_trajectory(stamp_of(0.3), ZERO, velocity=None)
    g.probe.send_trajectory(stamp_of(0.4), ZERO)
    wait_outputs(g, 1)
    core = g.node.core
    assert core.rejected['malformed'] == 3
    assert core.received['trajectory'] == 4


def test_diagnostics(graph):
    """Name, level, keys and values of /diagnostics, period by period."""
    g = graph(PATIENT)
    probe = g.probe
    first = wait_diagnostics(g, lambda d: True, timeout=WAIT)
    assert len(first.status) == 1
    status = first.status[0]
    assert status.name == DIAGNOSTIC_NAME
    assert status.hardware_id == 'orthoglide'
    assert status.level == DiagnosticStatus.OK
    assert status.message == 'waiting for the first setpoint'
    values = diagnostic_values(first)
    for key in ('tick rate (Hz)', 'compute time mean (us)',
                'compute time max (us)', 'stale', 'singularity distance',
                'singularity margin', 'setpoints computed',
                'outputs published', 'time since last setpoint (s)',
                'pending partial setpoints', 'rate_hz'):
        assert key in values, key
    for reason in REASONS:
        assert values[f'rejected {reason}'] == '0'
    assert values['stale'] == 'true'
    assert values['singularity distance'] == 'nan'
    assert values['setpoints computed'] == '0'
    assert float(values['tick rate (Hz)']) == 0.0
    assert values['singularity margin'] == '0.2'
    header = first.header.stamp
    assert header.sec > 0

    # Five setpoints, then one refused: the period's status is WARN.
    times = (0.2, 0.6, 1.0, 1.4, 1.8)
    for k, t in enumerate(times):
        send_paper(g, t, k + 1)
    probe.send(stamp_of(3.0), UNREACHABLE)
    # The period of the fifth computation: its compute time and rate.
    msg = wait_diagnostics(g, lambda d: d['setpoints computed'] == '5')
    values = diagnostic_values(msg)
    assert 0.0 < float(values['compute time max (us)'])
    assert 0.0 < float(values['compute time mean (us)'])
    assert 0.0 < float(values['tick rate (Hz)'])
    # The period of the refusal: WARN.
    msg = wait_diagnostics(g, lambda d: d['rejected unreachable'] == '1')
    status = msg.status[0]
    values = diagnostic_values(msg)
    assert status.level == DiagnosticStatus.WARN
    assert 'rejected' in status.message
    assert values['setpoints computed'] == '5'
    assert values['outputs published'] == '5'
    assert values['stale'] == 'false'
    last = solve(*paper_sample(times[-1]))
    assert values['singularity distance'] == \
        f'{last.singularity_distance:.6g}'
    assert 0.0 <= float(values['time since last setpoint (s)']) < 60.0
    assert values['received pose'] == '6'

    # The next period: nothing new, still fresh: OK, no outputs.
    index = probe.diagnostics.index(msg) + 1
    assert spin_until(g.executor, lambda: len(probe.diagnostics) > index,
                      WAIT)
    msg = probe.diagnostics[index]
    status = msg.status[0]
    values = diagnostic_values(msg)
    assert (status.level, status.message) == (DiagnosticStatus.OK, 'ok')
    assert float(values['tick rate (Hz)']) == 0.0
    assert values['rejected unreachable'] == '1'


# Fixed rate ------------------------------------------------------------------
# serial: a rate verdict (the median gap between outputs at 50 Hz).
@pytest.mark.serial
def test_fixed_rate_stale_and_resume(graph):
    """rate_hz > 0: the newest result at the rate until setpoint_timeout."""
    rate, timeout = 50.0, 0.4
    g = graph({'rate_hz': rate, 'setpoint_timeout': timeout})
    probe = g.probe
    p, v, a = paper_sample(0.5)
    expected = solve(p, v, a)
    start = time.monotonic()
    probe.send(stamp_of(0.5), p, v, a)
    wait_outputs(g, 1)
    spin_for(g.executor, timeout + 0.6 - (time.monotonic() - start))
    n = len(probe.joint_states)
    assert 3 <= n <= rate * timeout + 2, n
    for k in range(n):
        assert_output(probe, k, stamp_of(0.5), expected)
    gaps = sorted(b - a for a, b in zip(probe.arrivals, probe.arrivals[1:]))
    median = gaps[len(gaps) // 2]
    assert 0.5 / rate <= median <= 2.0 / rate, gaps
    assert probe.arrivals[-1] - start <= timeout + 0.5
    # Stopped: nothing more, and the diagnostics say stale.
    spin_for(g.executor, 0.3)
    assert len(probe.joint_states) == n
    msg = wait_diagnostics(g, lambda d: d['stale'] == 'true'
                           and d['setpoints computed'] == '1')
    assert msg.status[0].level == DiagnosticStatus.WARN
    assert msg.status[0].message.startswith('stale')
    assert len(probe.joint_states) == n
    # A fresh setpoint resumes; a newer one replaces it at the next tick.
    p2, v2, a2 = send_paper(g, 1.0, n + 3)
    p3, v3, a3 = paper_sample(1.5)
    probe.send(stamp_of(1.5), p3, v3, a3)
    assert spin_until(g.executor, lambda: stamp_of(1.5) in
                      probe.output_stamps(), WAIT)
    wait_outputs(g, len(probe.joint_states) + 2)
    stamps = probe.output_stamps()[n:]
    first_new = stamps.index(stamp_of(1.5))
    assert first_new >= 3
    assert set(stamps[:first_new]) == {stamp_of(1.0)}
    assert set(stamps[first_new:]) == {stamp_of(1.5)}
    for k in range(n, len(probe.joint_states)):
        if header_stamp(probe.joint_states[k]) == stamp_of(1.0):
            assert_output(probe, k, stamp_of(1.0), solve(p2, v2, a2))
        else:
            assert_output(probe, k, stamp_of(1.5), solve(p3, v3, a3))


# Parameters ------------------------------------------------------------------
def test_invalid_parameter_changes_refused(graph):
    """Invalid changes are refused with a reason and change nothing."""
    g = graph()
    probe = g.probe
    client = parameter_client(g, 'feedforward')
    refused = [
        ([Parameter('robot.m5', value=-1.0)], 'robot.m5'),
        ([Parameter('pairing_timeout', value=0.5)], 'pairing_timeout'),
        ([Parameter('setpoint_timeout', value=0.01)], 'pairing_timeout'),
        ([Parameter('joint_names', value=['a', 'b'])], 'joint_names'),
        ([Parameter('robot.alpha', value=2.0)], 'robot.alpha'),
        ([Parameter('robot.l3', value='long')], None),   # rclpy: type
        ([Parameter('rate_hz', value=-1.0)], None),      # rclpy: range
    ]
    for parameters, word in refused:
        response = call(g, client.set_parameters(parameters))
        assert len(response.results) == 1
        result = response.results[0]
        assert not result.successful, parameters[0].name
        assert result.reason, parameters[0].name
        if word is not None:
            assert word in result.reason, result.reason
    # Atomically: one bad value refuses the whole set.
    result = call(g, client.set_parameters_atomically([
        Parameter('robot.m5', value=18.0),
        Parameter('robot.l3', value=-0.85)])).result
    assert not result.successful
    assert 'robot.l3' in result.reason
    values = call(g, client.get_parameters(
        ['robot.m5', 'robot.l3', 'pairing_timeout', 'setpoint_timeout',
         'joint_names', 'rate_hz', 'robot.alpha'])).values
    assert [v.double_value for v in values[:4]] == [15.0, 0.85, 0.05, 0.1]
    assert list(values[4].string_array_value) == JOINT_NAMES
    assert values[5].double_value == 0.0
    assert values[6].double_value == Robot().alpha
    assert g.node.core.settings.robot == Robot()
    p, v, a = send_paper(g, 1.2, 1)
    assert_output(probe, 0, stamp_of(1.2), solve(p, v, a))


def test_valid_atomic_change_applies_to_next_setpoint(graph):
    """robot.m5 with robot.gravity, atomically: the next output uses both."""
    g = graph()
    probe = g.probe
    client = parameter_client(g, 'feedforward')
    p, v, a = send_paper(g, 1.2, 1)
    assert_output(probe, 0, stamp_of(1.2), solve(p, v, a))
    result = call(g, client.set_parameters_atomically([
        Parameter('robot.m5', value=18.0),
        Parameter('robot.gravity', value=[0.0, 0.0, -9.0])])).result
    assert result.successful, result.reason
    robot = Robot(m5=18.0, gravity=(0.0, 0.0, -9.0))
    probe.send(stamp_of(1.3), p, v, a)
    wait_outputs(g, 2)
    assert_output(probe, 1, stamp_of(1.3), solve(p, v, a, robot))
    assert not close(probe.joint_states[1].effort[2],
                     probe.joint_states[0].effort[2])


def test_a_payload_set_over_dds_is_the_next_setpoints_and_shown(graph):
    """robot.payload as ros2 param set sets it: m5 + payload from then on."""
    g = graph()
    probe = g.probe
    client = parameter_client(g, 'feedforward')
    p, v, a = send_paper(g, 0.7, 1)
    result = call(g, client.set_parameters([
        Parameter('robot.payload', value=5.0)])).results[0]
    assert result.successful, result.reason
    probe.send(stamp_of(0.8), p, v, a)
    wait_outputs(g, 2)
    assert_output(probe, 0, stamp_of(0.7), solve(p, v, a))
    assert_output(probe, 1, stamp_of(0.8),
                  solve(p, v, a, Robot(m5=Robot().m5 + 5.0)))
    wait_diagnostics(g, lambda v: v.get('payload (kg)') == '5')


def test_valid_changes_apply_to_next_setpoint(graph):
    """Mass, joint names and singularity margin, one by one."""
    g = graph()
    probe = g.probe
    client = parameter_client(g, 'feedforward')
    names = ['ax', 'by', 'cz']
    response = call(g, client.set_parameters([
        Parameter('robot.m5', value=18.0),
        Parameter('joint_names', value=names),
        Parameter('singularity_margin', value=0.01)]))
    assert [r.successful for r in response.results] == [True] * 3, [
        r.reason for r in response.results]
    robot = Robot(m5=18.0)
    p = NEAR_SINGULAR       # refused at the default margin 0.2
    probe.send(stamp_of(2.0), p)
    wait_outputs(g, 1)
    assert_output(probe, 0, stamp_of(2.0),
                  mechanics.solve(robot, p, ZERO, ZERO, 0.01), names)


def test_declared_parameters_and_qos_override(graph):
    """Every PARAMETERS row is declared; a QoS override is honoured."""
    topic = '/setpoint/trajectory'
    g = graph({f'qos_overrides.{topic}.subscription.reliability':
               'best_effort', 'robot.m4': 0.25})
    node = g.node
    assert_declared(node, PARAMETERS)
    assert node.get_parameter('robot.m4').value == 0.25
    assert node.core.settings.robot == Robot(m4=0.25)

    def reliability(topic_name):
        infos = [i for i in node.get_subscriptions_info_by_topic(topic_name)
                 if i.node_name == 'feedforward']
        assert len(infos) == 1, topic_name
        return infos[0].qos_profile.reliability

    assert reliability(topic) == ReliabilityPolicy.BEST_EFFORT
    for other in ('/setpoint/pose', '/setpoint/twist', '/setpoint/accel'):
        assert reliability(other) == ReliabilityPolicy.RELIABLE
    # A reliable publisher still reaches the best-effort subscription.
    p, v, a = paper_sample(0.9)
    g.probe.send_trajectory(stamp_of(0.9), p, v, a)
    wait_outputs(g, 1)
    assert_output(g.probe, 0, stamp_of(0.9),
                  solve(p, v, a, Robot(m4=0.25)))


def test_invalid_start_parameters_raise(ros_context):
    """Construction with an invalid set raises ValueError naming it."""
    for overrides, word in (
            ([Parameter('robot.m5', value=-1.0)], 'robot.m5'),
            ([Parameter('pairing_timeout', value=0.5)], 'pairing_timeout'),
            ([Parameter('joint_names', value=['a', 'b'])], 'joint_names')):
        with pytest.raises(ValueError, match=word):
            FeedforwardNode(context=ros_context,
                            parameter_overrides=overrides)
