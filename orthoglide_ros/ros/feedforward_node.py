"""
The ``feedforward`` ROS 2 node: setpoints in, joint states and forces out.

A thin layer over :class:`orthoglide_ros.cores.feedforward.Feedforward`: it declares
the parameters of :data:`orthoglide_ros.cores.feedforward.PARAMETERS`, converts
messages to plain values and back, publishes, logs throttled warnings and
publishes the core's status on ``/diagnostics``. A managed node
(:mod:`orthoglide_ros.ros.lifecycle`): configured and activated at start
unless ``autostart`` is false. Run it with ``ros2 run orthoglide_ros
feedforward``; ``doc/feedforward.md`` has the topics, parameters and
rules.
"""

import array
import time

from rclpy.serialization import deserialize_message, serialize_message

from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import JointTrajectory, MultiDOFJointTrajectory

from orthoglide_ros.cores.feedforward import (convert_trajectory, Feedforward,
                                              PARAMETERS)
from orthoglide_ros.cores.inputs import (CARTESIAN_TRAJECTORY_BYTES, Rejected,
                                         SMALL_MESSAGE_BYTES,
                                         TRAJECTORY_MESSAGE_BYTES)
from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.lifecycle import ManagedNode
from orthoglide_ros.ros.node_runtime import run

# Longest message of another encoding than little-endian CDR that is read.
FALLBACK_BYTES = SMALL_MESSAGE_BYTES


class FeedforwardNode(ManagedNode):
    """
    Node ``feedforward``: the Orthoglide's inverse dynamics every tick.

    The setpoint inputs are read on the input thread of :class:`InputNode`
    (raw, decoded by :mod:`cdr` outside the lock); the fixed-rate tick and
    the diagnostics run on periodic threads; the executor serves only the
    parameter and lifecycle services. All hold ``self.lock`` on the core.
    """

    def __init__(self, **kwargs):
        super().__init__('feedforward', **kwargs)
        self.declare_table(PARAMETERS, 'Orthoglide feedforward')
        self.apply_changes_with(self._swap)
        self.start()

    def build(self, settings):
        """Configure: the core, the inputs, the outputs, the tick."""
        self.core = Feedforward(settings, time.monotonic())
        self.core.active = False
        self._pub_joints = self.create_output(JointState,
                                              'feedforward/joint_states')
        self._pub_forces = self.create_output(Float64MultiArray,
                                              'feedforward/forces')
        self._pub_power = self.create_output(Float64MultiArray,
                                             'feedforward/power')
        # Raw inputs: cdr reads the few fields used straight from the
        # serialized message, several times cheaper than rclpy's conversion.
        for kind, reader, method in (
                (PoseStamped, cdr.pose_stamped, self.core.pose),
                (TwistStamped, cdr.vector3_stamped, self.core.twist),
                (AccelStamped, cdr.vector3_stamped, self.core.accel)):
            source = kind.__name__.replace('Stamped', '').lower()
            self.create_input(
                kind, f'setpoint/{source}',
                lambda fields, method=method: self._publish_now(
                    method(*fields, self.arrival)),
                source, decode=raw_decoder(reader, kind))
        self.create_input(
            MultiDOFJointTrajectory, 'setpoint/trajectory',
            self._on_trajectory, 'trajectory',
            decode=raw_decoder(_trajectory_point, MultiDOFJointTrajectory),
            max_bytes=TRAJECTORY_MESSAGE_BYTES)
        # Whole trajectories on a thread of their own: converting 10,000
        # points must not hold the setpoints back.
        self._pub_trajectory = self.create_output(
            JointTrajectory, 'feedforward/joint_trajectory')
        self._read_waypoints = raw_decoder(cdr.cartesian_trajectory,
                                           MultiDOFJointTrajectory)
        self.create_input(
            MultiDOFJointTrajectory, 'cartesian_trajectory',
            self._on_cartesian_trajectory, 'cartesian_trajectory',
            decode=self._convert, max_bytes=CARTESIAN_TRAJECTORY_BYTES,
            group='trajectories')

        self._joints = JointState()
        self._forces = _vector_message()
        self._power = _vector_message()
        self._set_joint_names()
        self.create_periodic(self.core.tick_period, self._on_tick, 'tick')

    # Parameters -----------------------------------------------------------
    def _swap(self, settings):
        """Swap in the new settings (lock held): the next setpoint uses them."""
        old = self.core.settings
        self.core.configure(settings)
        if self.core.settings.joint_names != old.joint_names:
            self._set_joint_names()

    def _set_joint_names(self):
        self._joints.name = list(self.core.settings.joint_names)

    # Inputs (input thread, lock held) -------------------------------------
    def _on_trajectory(self, fields):
        stamp, frame, (position, orientation, velocity, acceleration,
                       offset) = fields
        self._publish_now(self.core.trajectory_message(
            stamp, offset, self.get_clock().now().seconds_nanoseconds(),
            frame, position, orientation, velocity, acceleration,
            self.arrival))

    def on_inputs_idle(self):
        """Drop the partial setpoints whose partners did not come in time."""
        dropped = self.core.expire(time.monotonic())
        if dropped:
            self.warn_throttled('unpaired', (
                f'{dropped} partial setpoint(s) dropped without partners '
                'within pairing_timeout'))

    # Whole trajectories (their input thread) ------------------------------
    def _convert(self, data):
        """
        Read, convert and serialize a Cartesian trajectory (no lock held).

        The settings are read once (one immutable tuple, swapped whole);
        a refusal raises Rejected, which the core then counts. Returns the
        conversion and the JointTrajectory's bytes.
        """
        settings = self.core.settings
        conversion = convert_trajectory(settings, self._read_waypoints(data))
        s = conversion.solution
        return conversion, cdr.joint_trajectory(
            conversion.stamp, conversion.frame, settings.joint_names,
            conversion.time, s.lambda_, s.lambdadot, s.lambdaddot, s.force)

    def _on_cartesian_trajectory(self, converted):
        conversion, data = converted
        if self.core.count_trajectory(conversion,
                                      time.monotonic() - self.arrival):
            self._pub_trajectory.publish(data)

    # Fixed-rate tick (its own thread) -------------------------------------
    def _on_tick(self):
        with self.lock:
            self._publish(self.core.output_at_tick(time.monotonic()))

    # Outputs --------------------------------------------------------------
    def _publish_now(self, output):
        self._publish(self.core.output_now(output))

    def _publish(self, output):
        if output is None:
            return
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


def _trajectory_point(data):
    """Read a setpoint/trajectory message; refuse one without a point."""
    stamp, frame, point = cdr.trajectory_point(data)
    if point is None:
        raise Rejected('malformed', 'trajectory without a point holding a '
                       'transform')
    return stamp, frame, point


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
