"""
The ``feedforward`` ROS 2 node: setpoints in, joint states and forces out.

A thin layer over :class:`orthoglide_ros.cores.feedforward.Feedforward`: it declares
the parameters of :data:`orthoglide_ros.cores.feedforward.PARAMETERS`, converts
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
from trajectory_msgs.msg import JointTrajectory, MultiDOFJointTrajectory

from orthoglide_ros.formats import cdr
from orthoglide_ros.cores.feedforward import (
    CARTESIAN_TRAJECTORY_BYTES, convert_trajectory, Feedforward, PARAMETERS,
    TRAJECTORY_MESSAGE_BYTES)
from orthoglide_ros.cores.inputs import Rejected, SMALL_MESSAGE_BYTES
from orthoglide_ros.ros.node_runtime import default_qos, InputNode, run

# Longest message of another encoding than little-endian CDR that is read.
FALLBACK_BYTES = SMALL_MESSAGE_BYTES
# Period of the tick thread while rate_hz is 0.0 (it then only waits), s.
IDLE_TICK = 0.1


class FeedforwardNode(InputNode):
    """
    Node ``feedforward``: the Orthoglide's inverse dynamics every tick.

    The setpoint inputs are read on the input thread of :class:`InputNode`
    (raw, decoded by :mod:`cdr` outside the lock); the fixed-rate tick and
    the diagnostics run on periodic threads; the executor serves only the
    parameter services. All hold ``self.lock`` on the core.
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
        # Raw inputs: cdr reads the few fields used straight from the
        # serialized message, several times cheaper than rclpy's conversion.
        for kind, reader, method in (
                (PoseStamped, cdr.pose_stamped, self._core.pose),
                (TwistStamped, cdr.vector3_stamped, self._core.twist),
                (AccelStamped, cdr.vector3_stamped, self._core.accel)):
            source = kind.__name__.replace('Stamped', '').lower()
            self.create_input(
                kind, f'setpoint/{source}',
                lambda fields, method=method: self._take(method, *fields),
                default_qos(), source, decode=raw_decoder(reader, kind),
                qos_overriding_options=overrides)
        self.create_input(
            MultiDOFJointTrajectory, 'setpoint/trajectory',
            self._on_trajectory, default_qos(), 'trajectory',
            decode=raw_decoder(cdr.trajectory_point, MultiDOFJointTrajectory),
            max_bytes=TRAJECTORY_MESSAGE_BYTES,
            qos_overriding_options=overrides)
        # Whole trajectories on a thread of their own: converting 10,000
        # points must not hold the setpoints back.
        self._pub_trajectory = self.create_publisher(
            JointTrajectory, 'feedforward/joint_trajectory', default_qos(),
            qos_overriding_options=overrides)
        self._read_waypoints = raw_decoder(cdr.cartesian_trajectory,
                                           MultiDOFJointTrajectory)
        self.create_input(
            MultiDOFJointTrajectory, 'cartesian_trajectory',
            self._on_cartesian_trajectory, default_qos(),
            'cartesian_trajectory', decode=self._convert,
            max_bytes=CARTESIAN_TRAJECTORY_BYTES, group='trajectories',
            qos_overriding_options=overrides)

        self._joints = JointState()
        self._forces = _vector_message()
        self._power = _vector_message()
        self._set_joint_names()
        self.create_periodic(self._tick_period, self._on_tick, 'tick')
        self.publish_status('Orthoglide feedforward', self._core)
        self.apply_changes_with(self._swap)
        self.start_threads()

    # Parameters -----------------------------------------------------------
    def _swap(self, settings):
        """Swap in the new settings (lock held): the next setpoint uses them."""
        old = self._core.settings
        self._core.configure(settings)
        if self._core.settings.joint_names != old.joint_names:
            self._set_joint_names()

    def _set_joint_names(self):
        self._joints.name = list(self._core.settings.joint_names)

    # Inputs (input thread, lock held) -------------------------------------
    def _on_trajectory(self, fields):
        stamp, frame, point = fields
        if point is None:
            self.on_input_rejected('trajectory', Rejected(
                'malformed', 'trajectory without a point holding a '
                'transform'))
            return
        position, orientation, velocity, acceleration, offset = point
        self._take(self._core.trajectory_message, stamp, offset,
                   self.get_clock().now().seconds_nanoseconds(), frame,
                   position, orientation, velocity, acceleration)

    def on_input_rejected(self, source, rejection):
        """Count a message refused before it was read (oversize, malformed)."""
        try:
            if source == 'cartesian_trajectory':
                self._core.reject_trajectory(rejection)
            else:
                self._core.reject(source, rejection)
        except Rejected:
            what = 'trajectory' if source == 'cartesian_trajectory' \
                else 'setpoint'
            self.warn_throttled((source, rejection.reason),
                                f'{what} rejected ({rejection.reason}): '
                                f'{rejection}')

    # Whole trajectories (their input thread) ------------------------------
    def _convert(self, data):
        """
        Read, convert and serialize a Cartesian trajectory (no lock held).

        The settings are read once (one immutable tuple, swapped whole);
        a refusal raises Rejected, which :meth:`on_input_rejected` counts.
        Returns the conversion and the JointTrajectory's bytes.
        """
        settings = self._core.settings
        conversion = convert_trajectory(settings, self._read_waypoints(data))
        s = conversion.solution
        return conversion, cdr.joint_trajectory(
            conversion.stamp, conversion.frame, settings.joint_names,
            conversion.time, s.lambda_, s.lambdadot, s.lambdaddot, s.force)

    def _on_cartesian_trajectory(self, converted):
        conversion, data = converted
        self._pub_trajectory.publish(data)
        self._core.count_trajectory(conversion,
                                    time.monotonic() - self.arrival)

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
        if output is not None and self._core.settings.rate_hz == 0.0:
            self._publish(output)

    def on_inputs_idle(self):
        """Drop the partial setpoints whose partners did not come in time."""
        dropped = self._core.expire(time.monotonic())
        if dropped:
            self._warn('unpaired', f'{dropped} partial setpoint(s) dropped '
                       'without partners within pairing_timeout')

    # Fixed-rate tick (its own thread) -------------------------------------
    def _tick_period(self):
        rate = self._core.settings.rate_hz
        return 1.0 / rate if rate > 0.0 else IDLE_TICK

    def _on_tick(self):
        with self.lock:
            if self._core.settings.rate_hz == 0.0:
                return
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


def raw_decoder(reader, kind):
    """
    Return a decoder of serialized ``kind`` messages with a ``cdr`` reader.

    A buffer that is not the little-endian CDR the fast reader knows is
    decoded by rclpy and read in the local encoding, if it is at most
    FALLBACK_BYTES long (rclpy's conversion costs ~10 us per kB); a longer
    one is refused (``malformed``). ROS 2 writes little-endian CDR on every
    little-endian host, so the fallback only serves foreign writers.
    """
    def decode(data):
        try:
            return reader(data)
        except cdr.CdrError as error:
            if len(data) > FALLBACK_BYTES:
                raise Rejected('malformed', (
                    f'{kind.__name__} of {len(data)} bytes that the fast '
                    f'reader cannot read ({error}): other encodings are '
                    f'read up to {FALLBACK_BYTES} bytes')) from None
            return reader(serialize_message(deserialize_message(data, kind)))
    return decode


def _vector_message():
    msg = Float64MultiArray()
    msg.layout.dim = [MultiArrayDimension(label='actuator', size=3, stride=3)]
    return msg


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(FeedforwardNode, 'feedforward', args)


if __name__ == '__main__':
    raise SystemExit(main())
