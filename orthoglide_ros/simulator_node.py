"""
The ``simulator`` ROS 2 node: actuator forces in, measured joint states out.

A thin layer over :class:`orthoglide_ros.simulator.Simulator`: it declares
the parameters of :data:`orthoglide_ros.simulator.PARAMETERS`, reads
the commands, runs the step timer, publishes, serves ``~/reset`` and
publishes the core's status on ``/diagnostics``. Run it with ``ros2 run
orthoglide_ros simulator``; ``doc/simulator.md`` has the topics,
parameters and states.

Timing: real time on a fixed grid. The steps sit on a grid of period
``1 / rate_hz`` of the steady (monotonic) clock, and every step advances the
simulation by exactly that period. Each tick of the step timer makes every
step of the grid that is due, so a late tick catches up (with the command
held, as the drive held it) and the simulated time keeps pace with the wall
clock, up to MAX_CATCH_UP steps per tick; beyond that the missed time is
dropped (counted in ``overruns``: the plant then runs slower than real
time). The published stamp is the grid time of the state published (the
node clock at that instant), not the time of publication. With
``publish_rate_hz`` the states are published on a coarser grid than the
steps (a sampled encoder): the physics keeps its step, the subscribers get
fewer messages.
"""

import array
import time

from rclpy.clock import Clock, ClockType
from rclpy.duration import Duration
from rclpy.qos_overriding_options import QoSOverridingOptions

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from orthoglide_ros.inputs import Rejected
from orthoglide_ros.node_runtime import default_qos, InputNode, run
from orthoglide_ros.simulator import PARAMETERS, Simulator, STOPPED

# Steps one tick may make to catch up with the grid (10 ms at 1 kHz).
MAX_CATCH_UP = 10


class SimulatorNode(InputNode):
    """
    Node ``simulator``: the Orthoglide's forward dynamics in real time.

    The ``commands`` subscription is read on the input thread of
    :class:`InputNode`; the step and diagnostics timers, ``~/reset`` and
    the parameter services run on the executor; all hold ``self.lock`` on
    the core.
    """

    def __init__(self, **kwargs):
        super().__init__('simulator', **kwargs)
        # Raises ValueError on an invalid start-up set (run() reports it).
        self._core = Simulator(self.declare_settings(PARAMETERS),
                               time.monotonic())

        overrides = QoSOverridingOptions.with_default_policies()
        self._pub_joints = self.create_publisher(
            JointState, 'joint_states', default_qos(),
            qos_overriding_options=overrides)
        self._pub_pose = self.create_publisher(
            PoseStamped, 'platform/pose', default_qos(),
            qos_overriding_options=overrides)
        self.create_input_subscription(
            Float64MultiArray, 'commands', self._on_command, default_qos(),
            qos_overriding_options=overrides)
        self.create_service(Trigger, '~/reset', self._on_reset)

        self._joints = JointState()
        self._pose = PoseStamped()
        self._pose.pose.orientation.w = 1.0
        self._apply_names()
        self._step_clock = Clock(clock_type=ClockType.STEADY_TIME)
        self._step_timer = None
        self._grid = None       # monotonic time of the next step due
        self._next_publish = None   # grid time of the next state published
        self._set_timer()
        self.publish_status('Orthoglide simulator', self._core)
        # Last: the QoS override parameters declared above are no concern.
        self.apply_changes_with(self._configure)
        self.start_inputs()

    # Parameters -----------------------------------------------------------
    def _configure(self, settings):
        """Apply the live settings at once (lock held); the plant's wait."""
        old = self._core.settings
        self._core.configure(settings)
        self._apply_names()
        if settings.rate_hz != old.rate_hz:
            self._set_timer()
        if settings.publish_rate_hz != old.publish_rate_hz:
            self._next_publish = None
        if self._core.pending_reset:
            self.get_logger().info(
                'new robot, initial_position or singularity_margin: '
                'applies at the next ~/reset')

    def _apply_names(self):
        settings = self._core.settings
        self._joints.name = list(settings.joint_names)
        self._joints.header.frame_id = ''
        self._pose.header.frame_id = settings.base_frame

    def _set_timer(self):
        if self._step_timer is not None:
            self.destroy_timer(self._step_timer)
        self._grid = None
        self._next_publish = None
        self._step_timer = self.create_timer(
            1.0 / self._core.settings.rate_hz, self._on_step,
            clock=self._step_clock)

    # Inputs ---------------------------------------------------------------
    def _on_command(self, msg):
        """Take one command (input thread, lock held)."""
        try:
            self._core.command(msg.data, self.arrival)
        except Rejected as rejection:
            self.warn_throttled(rejection.reason,
                                f'command rejected ({rejection.reason}): '
                                f'{rejection}')
        else:
            if self._core.state == STOPPED:
                self.warn_throttled(
                    'ignored', 'command ignored: the simulation is stopped '
                    '(call ~/reset)')

    def _on_reset(self, request, response):
        try:
            with self.lock:
                response.message = self._core.reset()
            response.success = True
            self.get_logger().info(f'reset: {response.message}')
        except Exception:   # a defect: answer it, keep the node alive
            self.report_defect('in ~/reset')
            response.success = False
            response.message = 'internal error: see the log'
        return response

    # Steps ----------------------------------------------------------------
    def _on_step(self):
        now = time.monotonic()
        try:
            with self.lock:
                tick, instant = self._catch_up(now)
                if tick is not None and self._publish_due(tick, instant):
                    self._publish(tick, instant)
        except Exception:   # a defect: count it, the next tick goes on
            self.report_defect('in a step')
            return
        if tick is None:
            return
        if tick.event == 'stopped':
            self.get_logger().error(self._core.stop_message)
        elif tick.event == 'timeout':
            self.warn_throttled('timeout', (
                f'no valid command for command_timeout '
                f'{self._core.settings.command_timeout:g} s: braked, held '
                'until the next command'))

    def _catch_up(self, now):
        """
        Make every step of the grid due at ``now`` (lock held).

        Returns the last step's Tick (None if none was due) and the
        monotonic time its state holds at (s). The grid starts half a period
        before the first tick, so that timer jitter below half a period
        makes exactly one step per tick.
        """
        period = 1.0 / self._core.settings.rate_hz
        if self._grid is None:
            self._grid = now - 0.5 * period
        elif now - self._grid > MAX_CATCH_UP * period:
            self._core.overruns += 1
            self._grid = now - (MAX_CATCH_UP - 0.5) * period
        tick = None
        while self._grid <= now:
            tick = self._core.tick(self._grid)
            self._grid += period
            if tick.event is not None:
                break
        return tick, self._grid - period

    def _publish_due(self, tick, instant):
        """
        Say whether to publish the state at grid time ``instant`` (lock held).

        Every tick with ``publish_rate_hz`` 0.0; else the first state at or
        after each instant of the publish grid (period 1/publish_rate_hz,
        instants a late tick skipped are dropped), and always a state that
        ends in an event (a timeout, a stop).
        """
        settings = self._core.settings
        if settings.publish_rate_hz == 0.0 or tick.event is not None:
            return True
        # Half a step of slack: the two grids' float sums drift apart.
        slack = 0.5 / settings.rate_hz
        due = self._next_publish
        if due is not None and instant < due - slack:
            return False
        period = 1.0 / settings.publish_rate_hz
        due = instant if due is None else due
        while due <= instant + slack:
            due += period
        self._next_publish = due
        return True

    def _publish(self, tick, instant):
        """Publish a state, stamped with the node-clock time of ``instant``."""
        lag = time.monotonic() - instant
        stamp = (self.get_clock().now()
                 - Duration(nanoseconds=round(lag * 1e9))).to_msg()
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
        self._core.published += 1


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(SimulatorNode, 'simulator', args)


if __name__ == '__main__':
    raise SystemExit(main())
