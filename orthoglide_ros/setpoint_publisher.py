"""
The ``setpoint_publisher`` node: streams the paper's trajectory, eq. (6).

It publishes one setpoint per timer tick, stamped with the node clock at
publication, and samples eq. (6) (:func:`trajectory.paper_sample`) at
``t = (stamp - start) / 1e9`` s exactly, where ``start`` is the stamp of the
pass's first setpoint, so a subscriber can recompute every value from the
stamps alone. With ``input`` ``trajectory`` a setpoint is one
MultiDOFJointTrajectory on ``setpoint/trajectory`` (one point,
``time_from_start`` 0); with ``topics`` it is a PoseStamped, TwistStamped
and AccelStamped of equal stamp on ``setpoint/pose|twist|accel``. After
one pass (``duration`` s) the node exits with code 0, or starts the next
pass with ``loop``. Run it with ``ros2 run orthoglide_ros setpoint_publisher
--ros-args -p input:=topics`` (parameters: see PARAMETERS below).
"""

from copy import copy
import math
import signal

import rclpy
from rclpy.duration import Duration
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange,
                                ParameterDescriptor)
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros import trajectory
from orthoglide_ros.node_runtime import freeze_start_up_objects

# The feedforward's inputs are reliable, keep-last 10: match them (users
# override it with the qos_overrides.<topic>.publisher.* parameters).
# Each publisher gets a copy: rclpy writes the overrides into the profile.
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                 reliability=ReliabilityPolicy.RELIABLE)
INPUTS = ('trajectory', 'topics')
# The platform centre G as the one multi-DOF "joint" of a trajectory.
JOINT_NAME = 'platform'
ACK_TIMEOUT = 1.0   # s to wait at the end for subscribers to acknowledge
# Seeing a subscriber matched here does not mean that it has matched this
# publisher yet (it drops samples until then): measured here, the other side
# follows within ~60 ms on a busy machine.
MATCH_SETTLE = 0.25  # s


def _range(low, high):
    return [FloatingPointRange(from_value=low, to_value=high)]


# (name, default, description, floating-point range or None)
PARAMETERS = (
    ('rate_hz', 500.0, 'setpoints per second (Hz)', _range(0.1, 10000.0)),
    ('input', 'trajectory', "'trajectory': one MultiDOFJointTrajectory on "
     "setpoint/trajectory; 'topics': pose, twist and accel of equal stamp "
     'on setpoint/pose|twist|accel', None),
    ('duration', trajectory.PAPER_DURATION,
     'length of one pass of eq. (6) (s)', _range(0.0, 3600.0)),
    ('target', list(trajectory.PAPER_TARGET),
     'r* of eq. (6): three coordinates (m) in frame_id', None),
    ('omega', trajectory.PAPER_OMEGA, 'omega of eq. (6) (rad/s)',
     _range(-1000.0, 1000.0)),
    ('loop', False, 'repeat the pass, from t = 0 at home again, until '
     'Ctrl-C (else exit 0 after one pass)', None),
    ('start_delay', 1.0, 'longest wait (s) before the first setpoint: it '
     'comes earlier, 0.25 s after every output has min_subscribers matched '
     'subscribers', _range(0.0, 3600.0)),
    ('min_subscribers', 1, 'matched subscribers per output that end the '
     'start_delay wait early', None),
    ('frame_id', 'base_link', 'frame of the setpoints (header.frame_id)',
     None),
)


class SetpointPublisher(Node):
    """Node ``setpoint_publisher``: eq. (6) in real time, one pass or more."""

    def __init__(self, **kwargs):
        super().__init__('setpoint_publisher', **kwargs)
        for name, default, description, floats in PARAMETERS:
            descriptor = ParameterDescriptor(description=description,
                                             read_only=True)
            if floats is not None:
                descriptor.floating_point_range = floats
            if name == 'min_subscribers':
                descriptor.integer_range = [
                    IntegerRange(from_value=0, to_value=1000)]
            self.declare_parameter(name, default, descriptor)
        value = {name: self.get_parameter(name).value
                 for name, *_ in PARAMETERS}
        if value['input'] not in INPUTS:
            raise ValueError(f"input: must be 'trajectory' or 'topics', got "
                             f"{value['input']!r}")
        if len(value['target']) != 3 or not all(
                math.isfinite(c) for c in value['target']):
            raise ValueError('target: must be three finite coordinates (m), '
                             f"got {list(value['target'])!r}")
        self._input = value['input']
        self._duration_ns = round(value['duration'] * 1e9)
        self._target = tuple(value['target'])
        self._omega = value['omega']
        self._loop = value['loop']
        self._start_delay = value['start_delay']
        self._min_subscribers = value['min_subscribers']
        frame = value['frame_id']
        overrides = QoSOverridingOptions.with_default_policies()

        if self._input == 'trajectory':
            self._trajectory = MultiDOFJointTrajectory(
                joint_names=[JOINT_NAME],
                points=[MultiDOFJointTrajectoryPoint(
                    transforms=[Transform()], velocities=[Twist()],
                    accelerations=[Twist()])])
            self._trajectory.header.frame_id = frame
            self._publishers = [self.create_publisher(
                MultiDOFJointTrajectory, 'setpoint/trajectory', copy(QOS),
                qos_overriding_options=overrides)]
        else:
            # Default orientation: the identity quaternion (w = 1).
            self._pose, self._twist, self._accel = (
                PoseStamped(), TwistStamped(), AccelStamped())
            for msg in (self._pose, self._twist, self._accel):
                msg.header.frame_id = frame
            self._publishers = [
                self.create_publisher(kind, f'setpoint/{name}', copy(QOS),
                                      qos_overriding_options=overrides)
                for kind, name in ((PoseStamped, 'pose'),
                                   (TwistStamped, 'twist'),
                                   (AccelStamped, 'accel'))]

        self.done = Future()
        self._created_ns = self._now_ns()
        self._matched_ns = None     # when every output got its subscribers
        self._start_ns = None       # stamp of the pass's first setpoint
        self._first_ns = None       # stamp of the very first setpoint
        self._last_ns = None
        self._largest_gap_ns = 0
        self._published = 0
        self._passes = 0
        self.create_timer(1.0 / value['rate_hz'], self._on_timer)

    @property
    def published(self):
        """Setpoints published so far."""
        return self._published

    def _now_ns(self):
        return self.get_clock().now().nanoseconds

    def _ready(self, now_ns):
        """Whether to start: outputs matched and settled, or delay over."""
        if (now_ns - self._created_ns) / 1e9 >= self._start_delay:
            return True
        if self._matched_ns is None:
            if all(p.get_subscription_count() >= self._min_subscribers
                   for p in self._publishers):
                self._matched_ns = now_ns
            return False
        return (now_ns - self._matched_ns) / 1e9 >= MATCH_SETTLE

    def _on_timer(self):
        if self.done.done():
            return
        now_ns = self._now_ns()
        if self._start_ns is None:
            if not self._ready(now_ns):
                return
            self._start_ns = self._first_ns = now_ns
            self._passes = 1
        elapsed_ns = now_ns - self._start_ns
        if elapsed_ns > self._duration_ns:
            if not self._loop:
                self.done.set_result(True)
                return
            self._start_ns, elapsed_ns = now_ns, 0
            self._passes += 1
        self._publish(now_ns, elapsed_ns / 1e9)

    def _publish(self, stamp_ns, t):
        """Publish eq. (6) at t (s) stamped ``stamp_ns`` (ns)."""
        (x, y, z), (vx, vy, vz), (ax, ay, az) = trajectory.paper_sample(
            t, self._target, self._omega)
        sec, nanosec = divmod(stamp_ns, 10**9)
        if self._input == 'trajectory':
            msg = self._trajectory
            msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
            point = msg.points[0]
            p = point.transforms[0].translation
            v = point.velocities[0].linear
            a = point.accelerations[0].linear
            p.x, p.y, p.z = x, y, z
            v.x, v.y, v.z = vx, vy, vz
            a.x, a.y, a.z = ax, ay, az
            self._publishers[0].publish(msg)
        else:
            for msg in (self._pose, self._twist, self._accel):
                msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
            p = self._pose.pose.position
            v = self._twist.twist.linear
            a = self._accel.accel.linear
            p.x, p.y, p.z = x, y, z
            v.x, v.y, v.z = vx, vy, vz
            a.x, a.y, a.z = ax, ay, az
            for publisher, msg in zip(self._publishers, (
                    self._pose, self._twist, self._accel)):
                publisher.publish(msg)
        if self._last_ns is not None:
            self._largest_gap_ns = max(self._largest_gap_ns,
                                       stamp_ns - self._last_ns)
        self._last_ns = stamp_ns
        self._published += 1

    def finish(self, wait=True):
        """Log the one-line summary, after the acknowledgements if ``wait``."""
        for publisher in self._publishers if wait else ():
            publisher.wait_for_all_acked(Duration(seconds=ACK_TIMEOUT))
        if not self._published:
            self.get_logger().info('published no setpoint')
            return
        span = (self._last_ns - self._first_ns) / 1e9
        rate = (self._published - 1) / span if span > 0.0 else 0.0
        self.get_logger().info(
            f'published {self._published} setpoints ({self._input}) over '
            f'{span:.3f} s in {self._passes} pass(es): mean {rate:.1f} Hz, '
            f'largest gap {self._largest_gap_ns / 1e6:.2f} ms')


def main(args=None):
    """Stream setpoints until the pass ends or Ctrl-C; return the exit code."""
    # Ctrl-C raises KeyboardInterrupt with the context still valid, so the
    # summary can be logged (even where the parent left SIGINT ignored, as
    # a shell does for `&`); SIGTERM shuts the context down (no summary).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.SIGTERM)
    node = None
    try:
        node = SetpointPublisher()
        executor = rclpy.executors.SingleThreadedExecutor()
        executor.add_node(node)
        freeze_start_up_objects()
        executor.spin_until_future_complete(node.done)
        node.finish()
    except (ValueError, ParameterException) as error:
        rclpy.logging.get_logger('setpoint_publisher').fatal(
            f'invalid parameters, not starting: {error}')
        return 2
    except KeyboardInterrupt:
        if node is not None:
            node.finish(wait=False)
    except ExternalShutdownException:
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
