"""
The ``mechanism_state_publisher`` ROS 2 node: three sliders in, every joint out.

A thin layer over :class:`orthoglide_ros.cores.mechanism_state_publisher.MechanismState`:
it declares the parameters of :data:`orthoglide_ros.cores.mechanism_state_publisher.PARAMETERS`,
hands each ``joint_states`` message's arrays to the core, publishes every
non-fixed joint of the Orthoglide's URDF on ``mechanism/joint_states`` with
the input's stamp, logs throttled warnings and publishes the core's status
on ``/diagnostics``. A managed node
(:mod:`orthoglide_ros.ros.managed_node`), configured and activated at
start unless ``autostart`` is false. With the URDF as ``robot_description``,
``robot_state_publisher`` remapped to ``mechanism/joint_states`` gives TF for
every body. Run it with ``ros2 run orthoglide_ros mechanism_state_publisher``;
``doc/mechanism_state_publisher.md`` has the topics, parameters and rules.
"""

import array
import time

from sensor_msgs.msg import JointState

from orthoglide_ros.cores.mechanism_state_publisher import (MechanismState,
                                                            PARAMETERS)
from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import Input, ManagedNode
from orthoglide_ros.ros.node_runtime import run


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
        """Configure: the core and the output; return the input."""
        self.core = MechanismState(settings, time.monotonic())
        self._publisher = self.create_output(JointState,
                                             'mechanism/joint_states')
        self._message = JointState()
        self._names = None
        return (Input('joint_states', JointState, cdr.joint_state,
                      self.core.joint_state, output=self._publish),)

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


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(MechanismStatePublisherNode, 'mechanism_state_publisher', args)


if __name__ == '__main__':
    raise SystemExit(main())
