"""
Tests of the ``setpoint_publisher`` node: eq. (6) streamed in real time.

The node samples eq. (6) at ``t = (stamp - first stamp) / 1e9`` exactly, so
every received value must equal :func:`trajectory.paper_sample` at the time
recovered from the stamps, whatever the timer's jitter.
"""

from pathlib import Path
import sys
import time

import pytest

from orthoglide_ros.model import trajectory

rclpy = pytest.importorskip('rclpy')

from geometry_msgs.msg import (AccelStamped, PoseStamped,  # noqa: E402
                               TwistStamped)
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import (HistoryPolicy, QoSProfile,  # noqa: E402
                       ReliabilityPolicy)
from trajectory_msgs.msg import MultiDOFJointTrajectory  # noqa: E402

from orthoglide_ros.ros.setpoint_publisher_node import (  # noqa: E402
    SetpointPublisher)
from orthoglide_testing.processes import (start_node_process,  # noqa: E402
                                          stop_process, wait_exit)

pytestmark = pytest.mark.ros  # DDS and node processes

EXECUTABLE = Path(sys.executable).parent / 'setpoint_publisher'
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                 reliability=ReliabilityPolicy.RELIABLE)
TOLERANCE = 1e-12   # the same function of the same t: only rounding
PROCESS_TIMEOUT = 20.0
# s of one pass: the 10 setpoints the tests want at least come even if this
# process is descheduled for a good part of it.
DURATION = 1.0


def _ns(stamp):
    return stamp.sec * 10**9 + stamp.nanosec


def _xyz(v):
    return (v.x, v.y, v.z)


def _stream(context, input_kind, received, rate_hz=1000.0,
            duration=DURATION):
    """Run one pass of the node in-process; return it after the drain."""
    node = SetpointPublisher(context=context, parameter_overrides=[
        Parameter('rate_hz', value=rate_hz),
        Parameter('duration', value=duration),
        Parameter('input', value=input_kind),
        Parameter('start_delay', value=5.0)])
    listener = Node('listener', context=context)
    if input_kind == 'trajectory':
        def on_trajectory(msg):
            point = msg.points[0]
            assert _ns(point.time_from_start) == 0
            received.setdefault('trajectory', []).append((
                _ns(msg.header.stamp), msg.header.frame_id,
                _xyz(point.transforms[0].translation),
                _xyz(point.velocities[0].linear),
                _xyz(point.accelerations[0].linear)))
        listener.create_subscription(MultiDOFJointTrajectory,
                                     'setpoint/trajectory', on_trajectory,
                                     QOS)
    else:
        for kind, name, part in (
                (PoseStamped, 'pose', lambda m: m.pose.position),
                (TwistStamped, 'twist', lambda m: m.twist.linear),
                (AccelStamped, 'accel', lambda m: m.accel.linear)):
            def callback(msg, name=name, part=part):
                if name == 'pose':
                    q = msg.pose.orientation
                    assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 1.0)
                received.setdefault(name, []).append((
                    _ns(msg.header.stamp), msg.header.frame_id,
                    _xyz(part(msg))))
            listener.create_subscription(kind, f'setpoint/{name}', callback,
                                         QOS)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(listener)
    try:
        executor.spin_until_future_complete(node.done, timeout_sec=15.0)
        assert node.done.done(), 'the pass did not end'
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline and min(
                (len(v) for v in received.values()), default=0) \
                < node.published:
            executor.spin_once(timeout_sec=0.05)
        return node.published
    finally:
        executor.shutdown()
        node.destroy_node()
        listener.destroy_node()


def test_trajectory_values_equal_eq6_at_the_stamps(ros_context):
    received = {}
    published = _stream(ros_context, 'trajectory', received)
    samples = received['trajectory']
    assert published >= 10
    assert len(samples) == published
    stamps = [s[0] for s in samples]
    assert stamps[0] > 0
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    # One pass of DURATION: no stamp beyond it.
    assert stamps[-1] - stamps[0] <= DURATION * 1e9
    for stamp, frame, p, v, a in samples:
        assert frame == 'base_link'
        expected = trajectory.paper_sample((stamp - stamps[0]) / 1e9)
        for got, want in zip((p, v, a), expected):
            assert got == pytest.approx(want, abs=TOLERANCE, rel=0)
    # The first setpoint is the trajectory's start: at rest at home.
    assert samples[0][2:4] == ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def test_topics_publish_pose_twist_accel_with_equal_stamps(ros_context):
    received = {}
    published = _stream(ros_context, 'topics', received, rate_hz=500.0)
    assert published >= 10
    assert [len(received[k]) for k in ('pose', 'twist', 'accel')] == \
        [published] * 3
    stamps = [s[0] for s in received['pose']]
    assert stamps[0] > 0
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    for parts in zip(received['pose'], received['twist'], received['accel']):
        assert parts[0][0] == parts[1][0] == parts[2][0]
        expected = trajectory.paper_sample((parts[0][0] - stamps[0]) / 1e9)
        for (_, frame, got), want in zip(parts, expected):
            assert frame == 'base_link'
            assert got == pytest.approx(want, abs=TOLERANCE, rel=0)


def test_invalid_input_parameter_is_refused(ros_context):
    with pytest.raises(ValueError, match='input'):
        SetpointPublisher(context=ros_context, parameter_overrides=[
            Parameter('input', value='pose')])


def _run(*parameters):
    args = ['--ros-args']
    for p in parameters:
        args += ['-p', p]
    return start_node_process(args, command=[str(EXECUTABLE)])


def _finish(process, interrupt_after=None):
    """Return (exit code, output); SIGINT first if ``interrupt_after`` s."""
    if interrupt_after is None:
        wait_exit(process, PROCESS_TIMEOUT)
    else:
        time.sleep(interrupt_after)
    return stop_process(process)


def test_process_exits_0_after_one_pass():
    code, output = _finish(_run('duration:=0.2', 'start_delay:=0.0'))
    assert code == 0, output
    assert 'published' in output and '(trajectory) over' in output, output


def test_process_exits_0_on_ctrl_c_while_looping(ros_context):
    listener = Node('listener', context=ros_context)
    stamps = []
    listener.create_subscription(
        PoseStamped, 'setpoint/pose',
        lambda msg: stamps.append(_ns(msg.header.stamp)), QOS)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(listener)
    process = _run('loop:=true', 'duration:=0.2', 'start_delay:=0.0',
                   'input:=topics')
    try:
        # Interrupt once it streams, past the end of its first pass.
        deadline = time.monotonic() + PROCESS_TIMEOUT
        while time.monotonic() < deadline and process.poll() is None and (
                not stamps or stamps[-1] - stamps[0] < 300_000_000):
            executor.spin_once(timeout_sec=0.05)
        assert stamps, 'the looping publisher never published'
        code, output = _finish(process, interrupt_after=0.0)
    finally:
        stop_process(process)
        executor.shutdown()
        listener.destroy_node()
    assert code == 0, output
    assert 'Traceback' not in output, output
    assert 'pass(es)' in output and '(topics) over' in output, output
