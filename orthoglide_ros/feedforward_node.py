"""
The ``feedforward`` ROS 2 node: setpoints in, joint states and forces out.

A thin layer over :class:`orthoglide_ros.feedforward.Feedforward`: it declares
the parameters of :data:`orthoglide_ros.feedforward.PARAMETERS`, converts
messages to plain values and back, publishes, logs throttled warnings and
publishes the core's status on ``/diagnostics``. Run it with ``ros2 run
orthoglide_ros feedforward``; ``doc/feedforward.md`` has the topics,
parameters and rules.
"""

import array
import time

from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.serialization import deserialize_message, serialize_message

from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_ros import cdr
from orthoglide_ros.feedforward import Feedforward, PARAMETERS
from orthoglide_ros.inputs import Rejected
from orthoglide_ros.node_runtime import default_qos, InputNode, run


class FeedforwardNode(InputNode):
    """
    Node ``feedforward``: the Orthoglide's inverse dynamics every tick.

    The setpoint subscriptions are read on the input thread of
    :class:`InputNode`; the tick and diagnostics timers and the parameter
    services run on the executor; both hold ``self.lock`` on the core.
    """

    def __init__(self, **kwargs):
        super().__init__('feedforward', **kwargs)
        # Raises ValueError on an invalid start-up set (run() reports it).
        self._core = Feedforward(self.declare_settings(PARAMETERS),
                                 time.monotonic())

        overrides = QoSOverridingOptions.with_default_policies()
        self._pub_joints = self.create_publisher(
            JointState, 'feedforward/joint_states', default_qos(),
            qos_overriding_options=overrides)
        self._pub_forces = self.create_publisher(
            Float64MultiArray, 'feedforward/forces', default_qos(),
            qos_overriding_options=overrides)
        self._pub_power = self.create_publisher(
            Float64MultiArray, 'feedforward/power', default_qos(),
            qos_overriding_options=overrides)
        for kind, callback in ((PoseStamped, self._on_pose),
                               (TwistStamped, self._on_twist),
                               (AccelStamped, self._on_accel)):
            name = kind.__name__.replace('Stamped', '').lower()
            self.create_input_subscription(
                kind, f'setpoint/{name}', callback, default_qos(),
                qos_overriding_options=overrides, raw=True)
        self.create_input_subscription(
            MultiDOFJointTrajectory, 'setpoint/trajectory',
            self._on_trajectory, default_qos(), qos_overriding_options=overrides,
            raw=True)

        self._joints = JointState()
        self._forces = _vector_message()
        self._power = _vector_message()
        self._set_joint_names()
        self._tick_timer = None
        self._set_tick()
        self.publish_status('Orthoglide feedforward', self._core)
        self.apply_changes_with(self._swap)
        self.start_inputs()

    # Parameters -----------------------------------------------------------
    def _swap(self, settings):
        """Swap in the new settings (lock held): the next setpoint uses them."""
        old = self._core.settings
        self._core.configure(settings)
        if self._core.settings.joint_names != old.joint_names:
            self._set_joint_names()
        if self._core.settings.rate_hz != old.rate_hz:
            self._set_tick()

    def _set_joint_names(self):
        self._joints.name = list(self._core.settings.joint_names)

    def _set_tick(self):
        if self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = None
        rate = self._core.settings.rate_hz
        if rate > 0.0:
            self._tick_timer = self.create_timer(1.0 / rate, self._on_tick)

    # Inputs ---------------------------------------------------------------
    # Subscriptions are raw: cdr reads the few fields used straight from the
    # serialized message, several times cheaper than rclpy's conversion.
    def _on_pose(self, data):
        fields = self._read(cdr.pose_stamped, data, PoseStamped, 'pose')
        if fields is not None:
            self._take(self._core.pose, *fields)

    def _on_twist(self, data):
        fields = self._read(cdr.vector3_stamped, data, TwistStamped, 'twist')
        if fields is not None:
            self._take(self._core.twist, *fields)

    def _on_accel(self, data):
        fields = self._read(cdr.vector3_stamped, data, AccelStamped, 'accel')
        if fields is not None:
            self._take(self._core.accel, *fields)

    def _on_trajectory(self, data):
        fields = self._read(cdr.trajectory_point, data,
                            MultiDOFJointTrajectory, 'trajectory')
        if fields is None:
            return
        stamp, frame, point = fields
        if point is None:
            self._take(self._core.reject_malformed, 'trajectory',
                       'trajectory without a point holding a transform')
            return
        position, orientation, velocity, acceleration, offset = point
        if stamp == (0, 0):
            stamp = self.get_clock().now().seconds_nanoseconds()
        nanoseconds = (stamp[0] + offset[0]) * 10**9 + stamp[1] + offset[1]
        self._take(self._core.trajectory_point, divmod(nanoseconds, 10**9),
                   frame, position, orientation, velocity, acceleration)

    def _read(self, reader, data, kind, name):
        """Read a raw message; None (counted, warned) if it is unreadable."""
        try:
            return read_raw(reader, data, kind)
        except Exception as error:   # any decoding failure is malformed
            self._take(self._core.reject_malformed, name,
                       f'unreadable {kind.__name__}: {error}')
            return None

    def _take(self, method, *args):
        """Call the core; publish a completed setpoint, warn on a rejection."""
        try:
            output = method(*args, self.arrival)
        except Rejected as rejection:
            self._warn(rejection.reason, str(rejection))
            return
        except Exception:   # a defect, not bad input: publish nothing, go on
            self.report_defect('on a setpoint, nothing published')
            return
        if output is not None and self._tick_timer is None:
            self._publish(output)

    def on_inputs_idle(self):
        """Drop the partial setpoints whose partners did not come in time."""
        dropped = self._core.expire(time.monotonic())
        if dropped:
            self._warn('unpaired', f'{dropped} partial setpoint(s) dropped '
                       'without partners within pairing_timeout')

    def _on_tick(self):
        with self.lock:
            output = self._core.tick(time.monotonic())
            if output is not None:
                self._publish(output)

    # Outputs --------------------------------------------------------------
    def _publish(self, output):
        s = output.solution
        header = self._joints.header
        header.stamp.sec, header.stamp.nanosec = output.stamp
        self._joints.position = array.array('d', s.lambda_)
        self._joints.velocity = array.array('d', s.lambdadot)
        force = array.array('d', s.force)
        self._joints.effort = force
        self._pub_joints.publish(self._joints)
        self._forces.data = force
        self._pub_forces.publish(self._forces)
        self._power.data = array.array('d', s.power)
        self._pub_power.publish(self._power)
        self._core.published += 1

    def _warn(self, reason, message):
        self.warn_throttled(reason,
                            f'setpoint rejected ({reason}): {message}')


def read_raw(reader, data, kind):
    """
    Read a serialized message of type ``kind`` with a ``cdr`` reader.

    A buffer that is not the little-endian CDR the fast reader knows is
    decoded by rclpy and read in the local encoding; an unreadable one
    raises (CdrError or rclpy's error).
    """
    try:
        return reader(data)
    except cdr.CdrError:
        return reader(serialize_message(deserialize_message(data, kind)))


def _vector_message():
    msg = Float64MultiArray()
    msg.layout.dim = [MultiArrayDimension(label='actuator', size=3, stride=3)]
    return msg


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(FeedforwardNode, 'feedforward', args)


if __name__ == '__main__':
    raise SystemExit(main())
