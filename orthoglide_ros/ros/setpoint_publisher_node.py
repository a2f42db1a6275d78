"""
The ``setpoint_publisher`` ROS 2 node: streams eq. (6) or the excitation.

Glue over :class:`orthoglide_ros.cores.setpoint_publisher.Stream`
(doc/setpoint_publisher.md).
"""

import time

from rclpy.duration import Duration
from rclpy.task import Future

from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros.ros.managed_node import ManagedNode
from orthoglide_ros.cores.setpoint_publisher import PARAMETERS, Stream

# The platform centre G as the one multi-DOF "joint" of a trajectory.
JOINT_NAME = 'platform'
ACK_TIMEOUT = 1.0   # s to wait at the end for subscribers to acknowledge
# Seeing a subscriber matched here does not mean that it has matched this
# publisher yet (it drops samples until then): measured, the other side
# follows within ~60 ms on a busy machine.
MATCH_SETTLE = 0.25  # s


class SetpointPublisher(ManagedNode):
    """Node ``setpoint_publisher``: a motion in real time, one pass or more."""

    NAME = 'setpoint_publisher'
    TITLE = 'Orthoglide setpoint publisher'
    PARAMETERS = PARAMETERS

    def __init__(self, **kwargs):
        self.done = Future()
        super().__init__(**kwargs)

    def build(self, settings):
        """Configure: the stream, the outputs, the timer; no input."""
        self.core = Stream(settings, time.monotonic())
        frame = settings.frame_id
        if settings.input == 'trajectory':
            self._trajectory = MultiDOFJointTrajectory(
                joint_names=[JOINT_NAME],
                points=[MultiDOFJointTrajectoryPoint(
                    transforms=[Transform()], velocities=[Twist()],
                    accelerations=[Twist()])])
            self._trajectory.header.frame_id = frame
            self._stream_publishers = [self.create_output(
                MultiDOFJointTrajectory, 'setpoint/trajectory')]
        else:
            # Default orientation: the identity quaternion (w = 1).
            self._pose, self._twist, self._accel = (
                PoseStamped(), TwistStamped(), AccelStamped())
            for msg in (self._pose, self._twist, self._accel):
                msg.header.frame_id = frame
            self._stream_publishers = [
                self.create_output(kind, f'setpoint/{name}')
                for kind, name in ((PoseStamped, 'pose'),
                                   (TwistStamped, 'twist'),
                                   (AccelStamped, 'accel'))]
        self._created_ns = self._now_ns()
        self._matched_ns = None     # when every output got its subscribers
        self._started = False
        self.inputs.periodic(lambda: 1.0 / settings.rate_hz,
                             self._on_timer, 'setpoints')

    @property
    def published(self):
        """Setpoints published so far."""
        return self.core.published

    @property
    def finished(self):
        """Whether the last pass is over (:func:`run` then stops)."""
        return self.done.done()

    def _now_ns(self):
        return self.get_clock().now().nanoseconds

    def _ready(self, now_ns):
        """Whether to start: outputs matched and settled, or delay over."""
        settings = self.core.settings
        if (now_ns - self._created_ns) / 1e9 >= settings.start_delay:
            return True
        if self._matched_ns is None:
            if all(p.get_subscription_count() >= settings.min_subscribers
                   for p in self._stream_publishers):
                self._matched_ns = now_ns
            return False
        return (now_ns - self._matched_ns) / 1e9 >= MATCH_SETTLE

    def _on_timer(self):
        if self.done.done():
            return
        now_ns = self._now_ns()
        if not self._started:
            if not self._ready(now_ns):
                return
            self._started = True
        with self.lock:
            sample = self.core.next(now_ns)
            done = self.core.done
        if done:
            self.done.set_result(True)
        elif sample is not None:
            self._publish(now_ns, sample)

    def _publish(self, stamp_ns, sample):
        """Publish one setpoint stamped ``stamp_ns`` (ns)."""
        (x, y, z), (vx, vy, vz), (ax, ay, az) = sample
        sec, nanosec = divmod(stamp_ns, 10**9)
        if self.core.settings.input == 'trajectory':
            msg = self._trajectory
            msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
            point = msg.points[0]
            p = point.transforms[0].translation
            v = point.velocities[0].linear
            a = point.accelerations[0].linear
            p.x, p.y, p.z = x, y, z
            v.x, v.y, v.z = vx, vy, vz
            a.x, a.y, a.z = ax, ay, az
            self._stream_publishers[0].publish(msg)
            return
        for msg in (self._pose, self._twist, self._accel):
            msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        p = self._pose.pose.position
        v = self._twist.twist.linear
        a = self._accel.accel.linear
        p.x, p.y, p.z = x, y, z
        v.x, v.y, v.z = vx, vy, vz
        a.x, a.y, a.z = ax, ay, az
        for publisher, msg in zip(self._stream_publishers, (
                self._pose, self._twist, self._accel)):
            publisher.publish(msg)

    def on_stop(self, interrupted):
        """Log the summary, after the subscribers' acknowledgements."""
        if self.core is None:
            return
        for publisher in () if interrupted else self._stream_publishers:
            publisher.wait_for_all_acked(Duration(seconds=ACK_TIMEOUT))
        self.log('info', self.core.summary())
