"""
The ``feedforward`` ROS 2 node: setpoints in, joint states and forces out.

Glue over :class:`orthoglide_ros.cores.feedforward.Feedforward`: its
inputs, one line each in :meth:`FeedforwardNode.build`, its publishers and
its tick. ``ros2 run orthoglide_ros feedforward``; ``doc/feedforward.md``
has the topics, parameters, rules and the path of a setpoint.
"""

import array
import time

from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import JointTrajectory, MultiDOFJointTrajectory

from orthoglide_ros.cores.feedforward import (convert_trajectory, Feedforward,
                                              PARAMETERS)
from orthoglide_ros.cores.inputs import (CARTESIAN_TRAJECTORY_BYTES, Rejected,
                                         TRAJECTORY_MESSAGE_BYTES)
from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import ManagedNode


class FeedforwardNode(ManagedNode):
    """
    Node ``feedforward``: the Orthoglide's inverse dynamics every tick.

    The setpoint inputs are read on the ``inputs`` thread (raw, decoded by
    :mod:`cdr` outside the lock), whole trajectories on a thread of their
    own; the fixed-rate tick runs on a periodic thread; the executor
    serves only the parameter and lifecycle services. All hold
    ``self.lock`` on the core.
    """

    NAME = 'feedforward'
    TITLE = 'Orthoglide feedforward'
    PARAMETERS = PARAMETERS

    def build(self, settings):
        """Configure: the core, the outputs, the tick and the inputs."""
        core = self.core = Feedforward(settings, time.monotonic())
        self._pub_joints = self.create_output(JointState,
                                              'feedforward/joint_states')
        self._pub_forces = self.create_output(Float64MultiArray,
                                              'feedforward/forces')
        self._pub_power = self.create_output(Float64MultiArray,
                                             'feedforward/power')
        self._pub_trajectory = self.create_output(
            JointTrajectory, 'feedforward/joint_trajectory')
        self._joints = JointState()
        self._joints.name = list(settings.joint_names)
        self._forces = _vector_message()
        self._power = _vector_message()
        self.inputs.periodic(core.tick_period, self._on_tick, 'tick')
        # Each input: topic, type, decoder (no lock), core method (lock
        # held), publisher. Whole trajectories on a thread of their own:
        # converting 10,000 points must not hold the setpoints back.
        sub = self.inputs.subscribe
        sub('setpoint/pose', PoseStamped, cdr.pose_stamped, core.pose,
            self._publish, source='pose')
        sub('setpoint/twist', TwistStamped, cdr.vector3_stamped, core.twist,
            self._publish, source='twist')
        sub('setpoint/accel', AccelStamped, cdr.vector3_stamped, core.accel,
            self._publish, source='accel')
        sub('setpoint/trajectory', MultiDOFJointTrajectory,
            self._trajectory_point, core.trajectory_message, self._publish,
            source='trajectory', max_bytes=TRAJECTORY_MESSAGE_BYTES)
        sub('cartesian_trajectory', MultiDOFJointTrajectory, self._convert,
            core.cartesian_trajectory, self._pub_trajectory.publish,
            max_bytes=CARTESIAN_TRAJECTORY_BYTES, thread='trajectories')

    def reconfigure(self, settings):
        """Swap in the new settings (lock held): the next setpoint uses them."""
        self.core.configure(settings)
        self._joints.name = list(settings.joint_names)

    def inputs_idle(self):
        """Drop the partial setpoints whose partners did not come in time."""
        dropped = self.core.expire(time.monotonic())
        if dropped:
            self.warn_throttled('unpaired', (
                f'{dropped} partial setpoint(s) dropped without partners '
                'within pairing_timeout'))

    # Decoders (input threads, no lock) ------------------------------------
    def _trajectory_point(self, data):
        """
        Read a setpoint/trajectory message as the core takes it.

        ``(header stamp, time_from_start, the node clock now, frame,
        position, orientation, velocity, acceleration)``; one without a
        point holding a transform is malformed.
        """
        stamp, frame, point = cdr.trajectory_point(data)
        if point is None:
            raise Rejected('malformed', 'trajectory without a point holding '
                           'a transform')
        position, orientation, velocity, acceleration, offset = point
        return (stamp, offset, self.get_clock().now().seconds_nanoseconds(),
                frame, position, orientation, velocity, acceleration)

    def _convert(self, data):
        """
        Read, convert and serialize a Cartesian trajectory.

        The settings are read once (one immutable tuple, swapped whole);
        a refusal raises Rejected, which the core then counts. Returns the
        conversion and the JointTrajectory's bytes.
        """
        settings = self.core.settings
        conversion = convert_trajectory(settings,
                                        cdr.cartesian_trajectory(data))
        s = conversion.solution
        return conversion, cdr.joint_trajectory(
            conversion.stamp, conversion.frame, settings.joint_names,
            conversion.time, s.lambda_, s.lambdadot, s.lambdaddot, s.force)

    # Outputs --------------------------------------------------------------
    def _on_tick(self):
        with self.lock:
            output = self.core.tick(time.monotonic())
            if output is not None:
                self._publish(output)

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


def _vector_message():
    msg = Float64MultiArray()
    msg.layout.dim = [MultiArrayDimension(label='actuator', size=3, stride=3)]
    return msg
