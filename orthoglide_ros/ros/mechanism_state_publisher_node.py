"""
The ``mechanism_state_publisher`` ROS 2 node: three sliders in, every joint out.

A thin layer over :class:`orthoglide_ros.cores.mechanism_state_publisher.MechanismState`:
it declares the parameters of :data:`orthoglide_ros.cores.mechanism_state_publisher.PARAMETERS`,
hands each ``joint_states`` message's arrays to the core, publishes every
non-fixed joint of the Orthoglide's URDF on ``mechanism/joint_states`` with
the input's stamp, logs throttled warnings and publishes the core's status
on ``/diagnostics``. With the URDF as ``robot_description``,
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
from orthoglide_ros.ros.node_runtime import InputNode, run


class MechanismStatePublisherNode(InputNode):
    """
    Node ``mechanism_state_publisher``: the URDF's joint state from the sliders.

    The input is read on the input thread of :class:`InputNode` (raw,
    decoded by :mod:`cdr` outside the lock); the diagnostics run on a
    periodic thread and the parameter services on the executor; all hold
    ``self.lock`` on the core.
    """

    def __init__(self, **kwargs):
        super().__init__('mechanism_state_publisher', **kwargs)
        # Raises ValueError on an invalid start-up set (run() reports it).
        self.core = MechanismState(self.declare_settings(PARAMETERS),
                                   time.monotonic())
        self._publisher = self.create_output(JointState,
                                             'mechanism/joint_states')
        self.create_input(JointState, 'joint_states', self._on_joint_state,
                          'joint_states', decode=cdr.joint_state)
        self._message = JointState()
        self._names = None
        self.publish_status('Orthoglide mechanism state')
        # The core swaps its settings at once (under the lock).
        self.apply_changes_with(self.core.configure)
        self.start_threads()

    def _on_joint_state(self, fields):
        """Solve one joint state and publish it (input thread, lock held)."""
        stamp, frame, names, position, velocity, _ = fields
        state = self.core.joint_state(names, position, velocity, self.arrival)
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
