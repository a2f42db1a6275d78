"""
The ``mechanism_state_publisher`` ROS 2 node: three sliders in, every joint out.

Glue over :class:`orthoglide_ros.cores.mechanism_state_publisher.MechanismState`
(doc/mechanism_state_publisher.md).
"""

import array
import time

from sensor_msgs.msg import JointState

from orthoglide_ros.cores.mechanism_state_publisher import (MechanismState,
                                                            PARAMETERS)
from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import ManagedNode

# Said at configure for a robot as built (doc/mechanism_state_publisher.md).
AS_BUILT = ('robot.* describe legs as built: give robot_state_publisher '
            'the URDF of the same robot.* (orthoglide urdf --params FILE); '
            'the installed urdf/orthoglide.urdf is the drawing\'s')


class MechanismStatePublisherNode(ManagedNode):
    """
    Node ``mechanism_state_publisher``: the URDF's joint state from the sliders.

    The input is read on the ``inputs`` thread (raw, decoded by :mod:`cdr`
    outside the lock); the executor serves the parameter and lifecycle
    services; all hold ``self.lock`` on the core.
    """

    NAME = 'mechanism_state_publisher'
    TITLE = 'Orthoglide mechanism state'
    PARAMETERS = PARAMETERS

    def build(self, settings):
        """Configure: the core, the output and the input."""
        self.core = MechanismState(settings, time.monotonic())
        if not settings.robot.as_drawn:
            self.log('info', AS_BUILT)
        self._publisher = self.create_output(JointState,
                                             'mechanism/joint_states')
        self._message = JointState()
        self._names = None
        self.inputs.subscribe('joint_states', JointState, cdr.joint_state,
                              self.core.joint_state, self._publish)

    def _publish(self, solved):
        """Publish one solved joint state with its input's stamp and frame."""
        stamp, frame, state = solved
        message = self._message
        message.header.stamp.sec, message.header.stamp.nanosec = stamp
        message.header.frame_id = frame
        if state.names != self._names:
            message.name = list(state.names)
            self._names = state.names
        message.position = array.array('d', state.position)
        message.velocity = array.array('d', state.velocity)
        self._publisher.publish(message)
