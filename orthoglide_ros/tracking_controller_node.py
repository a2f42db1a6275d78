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
import traceback

from rclpy.qos_overriding_options import QoSOverridingOptions

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rcl_interfaces.msg import SetParametersResult
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from orthoglide_ros.node_runtime import (
    declare_specs, default_qos, diagnostic_array, DIAGNOSTICS_PERIOD,
    InputNode, run, spec_values)
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
        declare_specs(self, CONTROLLER_SPECS)
        # Raises ValueError on an invalid start-up set (run() reports it).
        self._core = Tracking(
            controller_settings_from_parameters(self._values()))
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        overrides = QoSOverridingOptions.with_default_policies()
        self._pub_commands = self.create_publisher(
            Float64MultiArray, 'commands', default_qos(),
            qos_overriding_options=overrides)
        self._pub_diagnostics = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10)
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
        self._internal_errors = 0
        # Start of the diagnostics period: (time, commands, skipped,
        # rejected) at that moment.
        self._window = (time.monotonic(), 0, 0, 0)
        self.create_timer(DIAGNOSTICS_PERIOD, self._publish_diagnostics)
        self.start_inputs()

    # Parameters -----------------------------------------------------------
    def _values(self, changes=()):
        """Return the parameter values with ``changes``, as plain types."""
        return spec_values(self, CONTROLLER_SPECS, changes)

    def _validate_parameters(self, parameters):
        """Accept a change only if the whole resulting set is valid."""
        try:
            controller_settings_from_parameters(self._values(parameters))
        except ValueError as error:
            self.get_logger().warning(f'parameter change refused: {error}')
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        """Swap in the new settings at once: the next message uses them."""
        settings = controller_settings_from_parameters(self._values())
        with self.lock:
            self._core.configure(settings)

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
                          time.monotonic())
        except Rejected as rejection:
            self.warn_throttled(
                (source, rejection.reason),
                f'{source} joint state rejected ({rejection.reason}): '
                f'{rejection}')
        except Exception:   # a defect, not bad input: publish nothing, go on
            self._internal_errors += 1
            if self.throttle('internal'):
                self.get_logger().error(
                    f'internal error on a {source} joint state, nothing '
                    'published:\n' + traceback.format_exc())
        return None

    # Diagnostics ----------------------------------------------------------
    def _publish_diagnostics(self):
        with self.lock:
            message = self._diagnostics()
        self._pub_diagnostics.publish(message)

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
        if self._internal_errors:
            level = DiagnosticStatus.ERROR
            text = f'{self._internal_errors} internal error(s): see the log'
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
            ('internal errors', self._internal_errors),
        ]
        return diagnostic_array(self, 'Orthoglide tracking controller',
                                level, text, values)


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    return run(TrackingControllerNode, 'tracking_controller', args)


if __name__ == '__main__':
    raise SystemExit(main())
