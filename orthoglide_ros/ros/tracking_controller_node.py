"""
The ``tracking_controller`` ROS 2 node: desired and measured joints in, forces out.

A thin layer over :class:`orthoglide_ros.cores.tracking_controller.Tracking`: it declares the
parameters of :data:`orthoglide_ros.cores.tracking_controller.PARAMETERS`, hands the
joint states' arrays to the core, publishes the commands, logs throttled
warnings and publishes the core's status on ``/diagnostics``. A managed
node (:mod:`orthoglide_ros.ros.managed_node`): configured and activated at
start unless ``autostart`` is false; deactivated, it holds (see
:meth:`~orthoglide_ros.cores.tracking_controller.Tracking.deactivate`).
Run it with ``ros2 run orthoglide_ros tracking_controller``;
``doc/tracking_controller.md`` has the topics, parameters and rules.
"""

import array
import time

from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import Input, ManagedNode
from orthoglide_ros.ros.node_runtime import run
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
        """Configure: the core, the command output, the loop; the inputs."""
        core = self.core = Tracking(settings, time.monotonic())
        self._mode = FOLLOWING
        self._pub_commands = self.create_output(Float64MultiArray, 'commands')
        self._command = Float64MultiArray()
        self._command.layout.dim = [
            MultiArrayDimension(label='actuator', size=3, stride=3)]
        self.inputs.periodic(lambda: 1.0 / self.core.settings.rate_hz,
                             self._on_tick, 'trajectory')
        # Measured first: when both inputs are ready in one wake-up of the
        # input thread, the measurements are taken before the desired
        # states, so a command uses the newest measurement. Trajectories,
        # a joint_trajectory_controller's input, on a thread of their own.
        return (
            Input('joint_states', JointState, cdr.joint_state, core.measured,
                  source='measured'),
            Input('feedforward/joint_states', JointState, cdr.joint_state,
                  core.desired, source='desired', output=self._send),
            Input('joint_trajectory', JointTrajectory, self._trajectory,
                  core.trajectory, JOINT_TRAJECTORY_BYTES,
                  source='trajectory', group='trajectories'),
        )

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


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(TrackingControllerNode, 'tracking_controller', args)


if __name__ == '__main__':
    raise SystemExit(main())
