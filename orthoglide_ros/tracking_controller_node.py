"""
The ``tracking_controller`` ROS 2 node: desired and measured joints in, forces out.

A thin layer over :class:`orthoglide_ros.tracking.Tracking`: it declares the
parameters of :data:`orthoglide_ros.tracking.CONTROLLER_SPECS`, hands the
joint states' arrays to the core, publishes the commands, logs throttled
warnings and reports diagnostics. Run it with ``ros2 run orthoglide_ros
tracking_controller``; see the README for the topics, parameters and rules.
"""

import array
import time

from rclpy.qos_overriding_options import QoSOverridingOptions

from diagnostic_msgs.msg import DiagnosticStatus
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from orthoglide_ros.node_runtime import (
    default_qos, diagnostic_array, InputNode, run)
from orthoglide_ros.tracking import (
    CONTROLLER_SPECS, controller_settings_from_parameters, INPUTS, REASONS,
    Rejected, SKIPS, Tracking)


class TrackingControllerNode(InputNode):
    """
    Node ``tracking_controller``: PD plus feedforward on the three actuators.

    Both joint-state subscriptions are read on the input thread of
    :class:`InputNode`; the diagnostics timer and the parameter services
    run on the executor; both hold ``self.lock`` on the core.
    """

    def __init__(self, **kwargs):
        super().__init__('tracking_controller', **kwargs)
        # Raises ValueError on an invalid start-up set (run() reports it).
        self._core = Tracking(self.declare_settings(
            CONTROLLER_SPECS, controller_settings_from_parameters))

        overrides = QoSOverridingOptions.with_default_policies()
        self._pub_commands = self.create_publisher(
            Float64MultiArray, 'commands', default_qos(),
            qos_overriding_options=overrides)
        # Measured first: when both inputs are ready in one wake-up of the
        # input thread, the measurements are taken before the desired
        # states, so a command uses the newest measurement.
        self.create_input_subscription(
            JointState, 'joint_states', self._on_measured, default_qos(),
            qos_overriding_options=overrides)
        self.create_input_subscription(
            JointState, 'feedforward/joint_states', self._on_desired,
            default_qos(), qos_overriding_options=overrides)

        self._command = Float64MultiArray()
        self._command.layout.dim = [
            MultiArrayDimension(label='actuator', size=3, stride=3)]
        # Start of the diagnostics period: (time, commands, skipped,
        # rejected) at that moment.
        self._window = (time.monotonic(), 0, 0, 0)
        self.publish_diagnostics_with(self._diagnostics)
        # The core swaps its settings at once (under the lock).
        self.apply_changes_with(self._core.configure)
        self.start_inputs()

    # Inputs (input thread, self.lock held) --------------------------------
    def _on_measured(self, msg):
        self._take('measured', self._core.measured, msg)

    def _on_desired(self, msg):
        command = self._take('desired', self._core.desired, msg)
        if command is not None:
            self._command.data = array.array('d', command.force)
            self._pub_commands.publish(self._command)

    def _take(self, source, method, msg):
        """Hand one joint state to the core; warn on a rejection."""
        try:
            return method(msg.name, msg.position, msg.velocity, msg.effort,
                          self.arrival)
        except Rejected as rejection:
            self.warn_throttled(
                (source, rejection.reason),
                f'{source} joint state rejected ({rejection.reason}): '
                f'{rejection}')
        except Exception:   # a defect, not bad input: publish nothing, go on
            self.report_defect(f'on a {source} joint state, nothing '
                               'published')
        return None

    # Diagnostics ----------------------------------------------------------
    def _diagnostics(self):
        """Return the DiagnosticArray of the period ending now."""
        core = self._core
        now = time.monotonic()
        start, commands, skipped_before, rejected_before = self._window
        period = max(now - start, 1e-9)
        skipped = sum(core.skipped.values())
        rejected = sum(core.rejected.values())
        self._window = (now, core.commands, skipped, rejected)
        age = None if core.measurement_arrival is None \
            else now - core.measurement_arrival
        if self.internal_errors:
            level = DiagnosticStatus.ERROR
            text = f'{self.internal_errors} internal error(s): see the log'
        elif skipped > skipped_before:
            level = DiagnosticStatus.WARN
            what = 'no measurement yet' if age is None \
                else f'newest measurement {age:.3f} s old'
            text = (f'{skipped - skipped_before} desired state(s) without a '
                    f'fresh measurement ({what}): nothing commanded')
        elif rejected > rejected_before:
            level = DiagnosticStatus.WARN
            text = (f'{rejected - rejected_before} joint state(s) rejected '
                    'in the last period')
        elif core.received['desired'] == 0:
            level, text = DiagnosticStatus.OK, 'waiting for desired states'
        else:
            level, text = DiagnosticStatus.OK, 'ok'
        settings = core.settings
        errors = core.latest.error if core.latest is not None \
            else (float('nan'),) * 3
        values = [
            ('command rate (Hz)', (core.commands - commands) / period),
            ('commands published', core.commands),
            ('clipped forces', core.clipped),
            ('time since last measurement (s)',
             age if age is not None else float('nan')),
            ('measurement fresh', core.fresh(now)),
        ]
        values += [(f'tracking error {name} (m)', e)
                   for name, e in zip(settings.joint_names, errors)]
        values += [(f'skipped {s}', core.skipped[s]) for s in SKIPS]
        values += [(f'received {i}', core.received[i]) for i in INPUTS]
        values += [(f'rejected {i} {r}', core.rejected[i, r])
                   for i in INPUTS for r in REASONS]
        values += [
            ('feedforward', settings.feedforward),
            ('force_limit (N)', settings.force_limit),
            ('internal errors', self.internal_errors),
        ]
        return diagnostic_array(self, 'Orthoglide tracking controller',
                                level, text, values)


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(TrackingControllerNode, 'tracking_controller', args)


if __name__ == '__main__':
    raise SystemExit(main())
