"""
The ``tracking_controller`` ROS 2 node: desired and measured joints in, forces out.

Glue over :class:`orthoglide_ros.cores.tracking_controller.Tracking`: its
inputs, one line each in :meth:`TrackingControllerNode.build`, the command
publisher and the trajectory loop. ``ros2 run orthoglide_ros
tracking_controller``; ``doc/tracking_controller.md`` has the topics,
parameters and rules.
"""

import array
import time

from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import ManagedNode
from orthoglide_ros.cores.inputs import JOINT_TRAJECTORY_BYTES
from orthoglide_ros.cores.tracking_controller import (FOLLOWING, HOLDING,
                                                      PARAMETERS, Tracking)


class TrackingControllerNode(ManagedNode):
    """
    Node ``tracking_controller``: PD plus feedforward on the three actuators.

    Both joint-state inputs are read on the ``inputs`` thread (raw, decoded
    by :mod:`cdr` outside the lock), joint trajectories on a thread of
    their own; a periodic thread samples the trajectory followed at
    ``rate_hz``; the executor serves the parameter and lifecycle services;
    all hold ``self.lock`` on the core.
    """

    NAME = 'tracking_controller'
    TITLE = 'Orthoglide tracking controller'
    PARAMETERS = PARAMETERS

    def build(self, settings):
        """Configure: the core, the command output, the loop, the inputs."""
        core = self.core = Tracking(settings, time.monotonic())
        self._mode = FOLLOWING
        self._pub_commands = self.create_output(Float64MultiArray, 'commands')
        self._command = Float64MultiArray()
        self._command.layout.dim = [
            MultiArrayDimension(label='actuator', size=3, stride=3)]
        self.inputs.periodic(lambda: 1.0 / self.core.settings.rate_hz,
                             self._on_tick, 'trajectory')
        # Trajectories, a joint_trajectory_controller's input, on a thread
        # of their own.
        sub = self.inputs.subscribe
        sub('joint_states', JointState, cdr.joint_state, core.measured,
            source='measured')
        sub('feedforward/joint_states', JointState, cdr.joint_state,
            core.desired, self._send, source='desired')
        sub('joint_trajectory', JointTrajectory, self._trajectory,
            core.trajectory, source='trajectory',
            max_bytes=JOINT_TRAJECTORY_BYTES, thread='trajectories')

    def _trajectory(self, data):
        """Read a joint trajectory's points, and the node clock now (s)."""
        return cdr.joint_trajectory_points(data), self._node_seconds()

    # The trajectory loop (its own thread) ---------------------------------
    def _on_tick(self):
        if self.core.idle:      # no trajectory: not even the lock
            return
        with self.lock:
            self._send(self.core.tick(self._node_seconds(),
                                      time.monotonic()))

    def _node_seconds(self):
        """Return the node clock's time now (s), the trajectories' clock."""
        return self.get_clock().now().nanoseconds * 1e-9

    def _send(self, command):
        """Publish a command (None: none); log a change of mode."""
        mode = self.core.mode
        if mode != self._mode:
            self._mode = mode
            self.log('info' if mode != HOLDING else 'error'
                     if self.core.hold_is_fault else 'warning',
                     self.core.hold_message or 'path tolerance re-armed: '
                     'following the desired states again')
        if command is not None:
            self._command.data = array.array('d', command.force)
            self._pub_commands.publish(self._command)
