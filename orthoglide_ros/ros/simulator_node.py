"""
The ``simulator`` ROS 2 node: actuator forces in, measured joint states out.

Glue over :class:`orthoglide_ros.cores.simulator.Simulator`: its inputs,
one line each in :meth:`SimulatorNode.build`, ``~/reset``, and the steps on
a thread of their own, each published with the node-clock time of its grid
instant (:meth:`SimulatorNode._node_time`). ``ros2 run orthoglide_ros
simulator``; ``doc/simulator.md`` has the topics, parameters and states.
"""

import array
import time

from rclpy.duration import Duration

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import ManagedNode
from orthoglide_ros.cores.simulator import PARAMETERS, Simulator

# Longest span (s) of the two monotonic reads around a node-clock read.
CLOCK_READ = 20e-6


class SimulatorNode(ManagedNode):
    """
    Node ``simulator``: the Orthoglide's forward dynamics in real time.

    The command inputs are read on the ``inputs`` thread; the steps run on
    a periodic thread; ``~/reset``, the parameter and lifecycle services
    on the executor; all hold ``self.lock`` on the core.
    """

    NAME = 'simulator'
    TITLE = 'Orthoglide simulator'
    PARAMETERS = PARAMETERS

    def build(self, settings):
        """Configure: the core, the outputs, ~/reset, the steps; the inputs."""
        core = self.core = Simulator(settings, time.monotonic())
        self._clock_offset = None   # node clock - monotonic (a Time)
        self._pub_joints = self.create_output(JointState, 'joint_states')
        self._pub_pose = self.create_output(PoseStamped, 'platform/pose')
        self.create_guarded_service(Trigger, '~/reset', self._on_reset)
        self._joints = JointState()
        self._pose = PoseStamped()
        self._pose.pose.orientation.w = 1.0
        self._apply_names()
        self.inputs.periodic(lambda: 1.0 / self.core.settings.rate_hz,
                             self._on_steps, 'steps')
        sub = self.inputs.subscribe
        sub('commands', Float64MultiArray, _forces, core.command)
        # The same commands by joint name: topic-based ros2_control.
        sub('joint_commands', JointState, cdr.joint_state, core.joint_command)

    def reconfigure(self, settings):
        """Apply the live settings at once (lock held); the plant's wait."""
        self.core.configure(settings)
        self._apply_names()
        if self.core.pending_reset:
            self.log('info', 'new robot, initial_position or '
                     'singularity_margin: applies at the next ~/reset')

    def _apply_names(self):
        settings = self.core.settings
        self._joints.name = list(settings.joint_names)
        self._joints.header.frame_id = ''
        self._pose.header.frame_id = settings.base_frame

    def _on_reset(self, request, response):
        with self.lock:
            response.message = self.core.reset()
        response.success = True
        # A client may call it again and again: one line a second.
        self.log_throttled('info', 'reset', f'reset: {response.message}')
        return response

    # Steps (their own thread) ---------------------------------------------
    def _on_steps(self):
        """Make every step due, each published as the core says."""
        now = time.monotonic()
        while True:
            with self.lock:
                step = self.core.step_due(now)
                if step is None:
                    return
                tick, instant = step
                publish = self.core.publish_due(tick, instant)
            if publish:
                self._publish(tick, instant)
            if tick.event in ('stopped', 'diverged'):
                # A reset loop: one line a second.
                self.log_throttled('error', tick.event,
                                   self.core.stop_message)
            elif tick.event == 'timeout':
                self.warn_throttled('timeout', (
                    f'no valid command for command_timeout '
                    f'{self.core.settings.command_timeout:g} s: braked, '
                    'held until the next command'))
            if tick.event is not None:
                return

    def _publish(self, tick, instant):
        """Publish a state, stamped with the node-clock time of ``instant``."""
        stamp = self._node_time(instant).to_msg()
        joints, pose = self._joints, self._pose
        joints.header.stamp = stamp
        joints.position = array.array('d', tick.lambda_)
        joints.velocity = array.array('d', tick.lambdadot)
        joints.effort = array.array('d', tick.effort)
        pose.header.stamp = stamp
        p = pose.pose.position
        p.x, p.y, p.z = tick.position
        self._pub_joints.publish(joints)
        self._pub_pose.publish(pose)

    def _node_time(self, instant):
        """
        Return the node clock's time at the monotonic ``instant`` (s).

        ``instant`` plus the offset of the node clock from the monotonic
        one, measured by a read of the node clock between two monotonic
        reads less than CLOCK_READ apart; a read another thread broke in
        on keeps the last good offset. So the stamps of the grid's states
        are as evenly spaced as the grid itself, however late the thread
        that publishes them (a stamp off by a preemption made the
        accelerations of a log, and the masses identified from it, wrong).
        """
        before = time.monotonic()
        now = self.get_clock().now()
        after = time.monotonic()
        if self._clock_offset is None or after - before < CLOCK_READ:
            self._clock_offset = now - Duration(
                nanoseconds=round(0.5 * (before + after) * 1e9))
        return self._clock_offset + Duration(
            nanoseconds=round(instant * 1e9))


def _forces(data):
    """Read a command: its forces, as the core's one field."""
    return (cdr.float64_array(data),)
