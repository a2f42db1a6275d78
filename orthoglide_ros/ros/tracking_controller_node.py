"""
The ``tracking_controller`` ROS 2 node: desired and measured joints in, forces out.

A thin layer over :class:`orthoglide_ros.cores.tracking_controller.Tracking`: it declares the
parameters of :data:`orthoglide_ros.cores.tracking_controller.PARAMETERS`, hands the
joint states' arrays to the core, publishes the commands, logs throttled
warnings and publishes the core's status on ``/diagnostics``. A managed
node (:mod:`orthoglide_ros.ros.lifecycle`): configured and activated at
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
from orthoglide_ros.ros.lifecycle import ManagedNode
from orthoglide_ros.ros.node_runtime import run
from orthoglide_ros.cores.inputs import JOINT_TRAJECTORY_BYTES
from orthoglide_ros.cores.tracking_controller import (HOLDING, PARAMETERS,
                                                      Tracking)


class TrackingControllerNode(ManagedNode):
    """
    Node ``tracking_controller``: PD plus feedforward on the three actuators.

    Both joint-state inputs are read on the input thread of
    :class:`InputNode` (raw, decoded by :mod:`cdr` outside the lock),
    joint trajectories on a thread of their own; a periodic thread samples
    the trajectory followed at ``rate_hz``; the diagnostics run on a
    periodic thread and the parameter and lifecycle services on the
    executor; all hold ``self.lock`` on the core.
    """

    def __init__(self, **kwargs):
        super().__init__('tracking_controller', **kwargs)
        self.declare_table(PARAMETERS, 'Orthoglide tracking controller')
        # The core swaps its settings at once (under the lock).
        self.apply_changes_with(lambda settings: self.core.configure(
            settings))
        self.start()

    def build(self, settings):
        """Configure: the core, the inputs, the command output, the loop."""
        self.core = Tracking(settings, time.monotonic())
        self.core.active = False
        self._pub_commands = self.create_output(Float64MultiArray, 'commands')
        # Measured first: when both inputs are ready in one wake-up of the
        # input thread, the measurements are taken before the desired
        # states, so a command uses the newest measurement.
        self.create_input(JointState, 'joint_states', self._on_measured,
                          'measured', decode=cdr.joint_state)
        self.create_input(JointState, 'feedforward/joint_states',
                          self._on_desired, 'desired', decode=cdr.joint_state)
        # A joint_trajectory_controller's input: whole trajectories.
        self.create_input(
            JointTrajectory, 'joint_trajectory', self._on_trajectory,
            'trajectory', decode=cdr.joint_trajectory_points,
            max_bytes=JOINT_TRAJECTORY_BYTES, group='trajectories')
        self.create_periodic(lambda: 1.0 / self.core.settings.rate_hz,
                             self._on_tick, 'trajectory')

        self._command = Float64MultiArray()
        self._command.layout.dim = [
            MultiArrayDimension(label='actuator', size=3, stride=3)]

    # Inputs (input thread, self.lock held) --------------------------------
    def _on_measured(self, fields):
        _, _, names, position, velocity, effort = fields
        self.core.measured(names, position, velocity, effort, self.arrival)

    def _on_desired(self, fields):
        _, _, names, position, velocity, effort = fields
        mode = self.core.mode
        self._send(self.core.desired(names, position, velocity, effort,
                                     self.arrival), mode)

    def _on_trajectory(self, points):
        self.core.trajectory(points, self._node_seconds(), self.arrival)

    # The trajectory loop (its own thread) ---------------------------------
    def _on_tick(self):
        if self.core.idle:      # no trajectory: not even the lock
            return
        with self.lock:
            mode = self.core.mode
            self._send(self.core.tick(self._node_seconds(),
                                      time.monotonic()), mode)

    def _node_seconds(self):
        """Return the node clock's time now (s), the trajectories' clock."""
        return self.get_clock().now().nanoseconds * 1e-9

    def _send(self, command, mode):
        """Publish a command (None: none); log a change of mode."""
        if self.core.mode != mode:
            self.log('error' if self.core.mode == HOLDING else 'info',
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
