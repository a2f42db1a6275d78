"""
The ``feedforward`` ROS 2 node: setpoints in, joint states and forces out.

A thin layer over :class:`orthoglide_ros.feedforward.Feedforward`: it declares
the parameters of :mod:`orthoglide_ros.settings`, converts messages to plain
values and back, publishes, logs throttled warnings and reports diagnostics.
Run it with ``ros2 run orthoglide_ros feedforward``; see the README for the
topics, parameters and rules.
"""

import array
from copy import copy
import signal
import time
import traceback

import rclpy
from rclpy.exceptions import (ParameterException,
                              ParameterUninitializedException)
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.signals import SignalHandlerOptions

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from rcl_interfaces.msg import (FloatingPointRange, ParameterDescriptor,
                                SetParametersResult)
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_ros import cdr
from orthoglide_ros.feedforward import Feedforward, REASONS, Rejected
from orthoglide_ros.settings import SPECS, settings_from_parameters

# Reliable, keep-last 10 on every input and output; users override it with
# the standard qos_overrides.<topic>.<publisher|subscription>.* parameters.
# Each entity gets a copy: rclpy writes the overrides into the profile.
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                 reliability=ReliabilityPolicy.RELIABLE)
DIAGNOSTICS_PERIOD = 1.0    # s
WARNING_PERIOD = 1.0        # s between two warnings of the same reason

_TYPES = {'double': Parameter.Type.DOUBLE,
          'double_array': Parameter.Type.DOUBLE_ARRAY,
          'string': Parameter.Type.STRING,
          'string_array': Parameter.Type.STRING_ARRAY,
          'bool': Parameter.Type.BOOL}


class FeedforwardNode(Node):
    """Node ``feedforward``: the Orthoglide's inverse dynamics every tick."""

    def __init__(self, **kwargs):
        super().__init__('feedforward', **kwargs)
        for spec in SPECS:
            descriptor = ParameterDescriptor(
                description=spec.description,
                type=_TYPES[spec.type].value)
            if spec.range is not None:
                descriptor.floating_point_range = [FloatingPointRange(
                    from_value=spec.range[0], to_value=spec.range[1])]
            self.declare_parameter(
                spec.name, _TYPES[spec.type] if spec.default is None
                else spec.default, descriptor)
        # Raises ValueError on an invalid start-up set (main() reports it).
        self._core = Feedforward(settings_from_parameters(self._values()))
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        overrides = QoSOverridingOptions.with_default_policies()
        self._pub_joints = self.create_publisher(
            JointState, 'feedforward/joint_states', copy(QOS),
            qos_overriding_options=overrides)
        self._pub_forces = self.create_publisher(
            Float64MultiArray, 'feedforward/forces', copy(QOS),
            qos_overriding_options=overrides)
        self._pub_power = self.create_publisher(
            Float64MultiArray, 'feedforward/power', copy(QOS),
            qos_overriding_options=overrides)
        self._pub_diagnostics = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10)
        for kind, callback in ((PoseStamped, self._on_pose),
                               (TwistStamped, self._on_twist),
                               (AccelStamped, self._on_accel)):
            name = kind.__name__.replace('Stamped', '').lower()
            self.create_subscription(
                kind, f'setpoint/{name}', callback, copy(QOS),
                qos_overriding_options=overrides, raw=True)
        self.create_subscription(
            MultiDOFJointTrajectory, 'setpoint/trajectory',
            self._on_trajectory, copy(QOS), qos_overriding_options=overrides,
            raw=True)

        self._joints = JointState()
        self._forces = _vector_message()
        self._power = _vector_message()
        self._set_joint_names()
        self._tick_timer = None
        self._set_tick()
        self._published = 0
        self._internal_errors = 0
        self._last_warning = {}
        # Start of the diagnostics period: (time, published, computed,
        # compute ns, rejected) at that moment.
        self._window = (time.monotonic(), 0, 0, 0, 0)
        self.create_timer(DIAGNOSTICS_PERIOD, self._publish_diagnostics)

    # Parameters -----------------------------------------------------------
    def _values(self, changes=()):
        """
        Return the parameter values with ``changes`` applied, as plain types.

        rclpy gives double arrays as ``array.array``; the settings take lists.
        """
        values = {}
        for spec in SPECS:
            try:
                values[spec.name] = self.get_parameter(spec.name).value
            except ParameterUninitializedException:
                values[spec.name] = None
        values.update((p.name, p.value) for p in changes)
        return {name: list(value) if isinstance(value, array.array)
                else value for name, value in values.items()}

    def _validate_parameters(self, parameters):
        """Accept a change only if the whole resulting set is valid."""
        try:
            settings_from_parameters(self._values(parameters))
        except ValueError as error:
            self.get_logger().warning(f'parameter change refused: {error}')
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        """Swap in the new settings at once: the next setpoint uses them."""
        old = self._core.settings
        self._core.configure(settings_from_parameters(self._values()))
        if self._core.settings.joint_names != old.joint_names:
            self._set_joint_names()
        if self._core.settings.rate_hz != old.rate_hz:
            self._set_tick()

    def _set_joint_names(self):
        self._joints.name = list(self._core.settings.joint_names)

    def _set_tick(self):
        if self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = None
        rate = self._core.settings.rate_hz
        if rate > 0.0:
            self._tick_timer = self.create_timer(1.0 / rate, self._on_tick)

    # Inputs ---------------------------------------------------------------
    # Subscriptions are raw: cdr reads the few fields used straight from the
    # serialized message, several times cheaper than rclpy's conversion.
    def _on_pose(self, data):
        fields = self._read(cdr.pose_stamped, data, PoseStamped, 'pose')
        if fields is not None:
            self._take(self._core.pose, *fields)

    def _on_twist(self, data):
        fields = self._read(cdr.vector3_stamped, data, TwistStamped, 'twist')
        if fields is not None:
            self._take(self._core.twist, *fields)

    def _on_accel(self, data):
        fields = self._read(cdr.vector3_stamped, data, AccelStamped, 'accel')
        if fields is not None:
            self._take(self._core.accel, *fields)

    def _on_trajectory(self, data):
        fields = self._read(cdr.trajectory_point, data,
                            MultiDOFJointTrajectory, 'trajectory')
        if fields is None:
            return
        stamp, frame, point = fields
        if point is None:
            self._take(self._core.reject_malformed, 'trajectory',
                       'trajectory without a point holding a transform')
            return
        position, orientation, velocity, acceleration, offset = point
        if stamp == (0, 0):
            stamp = self.get_clock().now().seconds_nanoseconds()
        nanoseconds = (stamp[0] + offset[0]) * 10**9 + stamp[1] + offset[1]
        self._take(self._core.trajectory_point, divmod(nanoseconds, 10**9),
                   frame, position, orientation, velocity, acceleration)

    def _read(self, reader, data, kind, name):
        """Read a raw message; None (counted, warned) if it is unreadable."""
        try:
            return read_raw(reader, data, kind)
        except Exception as error:   # any decoding failure is malformed
            self._take(self._core.reject_malformed, name,
                       f'unreadable {kind.__name__}: {error}')
            return None

    def _take(self, method, *args):
        """Call the core; publish a completed setpoint, warn on a rejection."""
        try:
            output = method(*args, time.monotonic())
        except Rejected as rejection:
            self._warn(rejection.reason, str(rejection))
            return
        except Exception:   # a defect, not bad input: publish nothing, go on
            self._internal_errors += 1
            if self._throttle('internal'):
                self.get_logger().error(
                    'internal error on a setpoint, nothing published:\n'
                    + traceback.format_exc())
            return
        if output is not None and self._tick_timer is None:
            self._publish(output)

    def _on_tick(self):
        output = self._core.tick(time.monotonic())
        if output is not None:
            self._publish(output)

    # Outputs --------------------------------------------------------------
    def _publish(self, output):
        s = output.solution
        header = self._joints.header
        header.stamp.sec, header.stamp.nanosec = output.stamp
        self._joints.position = array.array('d', s.lambda_)
        self._joints.velocity = array.array('d', s.lambdadot)
        force = array.array('d', s.force)
        self._joints.effort = force
        self._pub_joints.publish(self._joints)
        self._forces.data = force
        self._pub_forces.publish(self._forces)
        self._power.data = array.array('d', s.power)
        self._pub_power.publish(self._power)
        self._published += 1

    def _warn(self, reason, message):
        if self._throttle(reason):
            self.get_logger().warning(f'setpoint rejected ({reason}): '
                                      f'{message}')

    def _throttle(self, reason):
        """Say whether a message of this reason may be logged now."""
        now = time.monotonic()
        if now - self._last_warning.get(reason, -1e9) < WARNING_PERIOD:
            return False
        self._last_warning[reason] = now
        return True

    def _publish_diagnostics(self):
        core = self._core
        now = time.monotonic()
        dropped = core.expire(now)
        if dropped:
            self._warn('unpaired', f'{dropped} partial setpoint(s) dropped '
                       'without partners within pairing_timeout')
        start, published, computed, compute_ns, rejected_before = \
            self._window
        period = max(now - start, 1e-9)
        count = core.computed - computed
        mean_us = (core.compute_ns_total - compute_ns) / count / 1e3 \
            if count else 0.0
        rejected = sum(core.rejected.values())
        self._window = (now, self._published, core.computed,
                        core.compute_ns_total, rejected)
        status = DiagnosticStatus(
            name=f'{self.get_name()}: Orthoglide feedforward',
            hardware_id='orthoglide')
        age = None if core.latest_arrival is None \
            else now - core.latest_arrival
        if self._internal_errors:
            status.level = DiagnosticStatus.ERROR
            status.message = (f'{self._internal_errors} internal error(s): '
                              'see the log')
        elif age is None:
            status.level, status.message = DiagnosticStatus.OK, \
                'waiting for the first setpoint'
        elif not core.fresh(now):
            status.level = DiagnosticStatus.WARN
            status.message = (f'stale: no fresh setpoint for {age:.2f} s, '
                              'outputs stopped')
        elif rejected > rejected_before:
            status.level = DiagnosticStatus.WARN
            status.message = (f'{rejected - rejected_before} setpoint(s) '
                              'rejected in the last period')
        else:
            status.level, status.message = DiagnosticStatus.OK, 'ok'
        settings = core.settings
        distance = core.latest.solution.singularity_distance \
            if core.latest is not None else float('nan')
        values = [
            ('tick rate (Hz)', (self._published - published) / period),
            ('compute time mean (us)', mean_us),
            ('compute time max (us)', core.compute_ns_max / 1e3),
            ('setpoints computed', core.computed),
            ('outputs published', self._published),
            ('stale', age is None or not core.fresh(now)),
            ('time since last setpoint (s)',
             age if age is not None else float('nan')),
            ('singularity distance', distance),
            ('singularity margin', settings.singularity_margin),
            ('pending partial setpoints', core.pending),
            ('rate_hz', settings.rate_hz),
            ('internal errors', self._internal_errors),
        ]
        values += [(f'received {k}', v) for k, v in core.received.items()]
        values += [(f'rejected {r}', core.rejected[r]) for r in REASONS]
        status.values = [KeyValue(key=k, value=_text(v)) for k, v in values]
        core.compute_ns_max = 0
        message = DiagnosticArray(status=[status])
        message.header.stamp = self.get_clock().now().to_msg()
        self._pub_diagnostics.publish(message)


def read_raw(reader, data, kind):
    """
    Read a serialized message of type ``kind`` with a ``cdr`` reader.

    A buffer that is not the little-endian CDR the fast reader knows is
    decoded by rclpy and read in the local encoding; an unreadable one
    raises (CdrError or rclpy's error).
    """
    try:
        return reader(data)
    except cdr.CdrError:
        return reader(serialize_message(deserialize_message(data, kind)))


def _vector_message():
    msg = Float64MultiArray()
    msg.layout.dim = [MultiArrayDimension(label='actuator', size=3, stride=3)]
    return msg


def _text(value):
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)


def main(args=None):
    """Run the node until Ctrl-C or shutdown; return the exit code."""
    logger = rclpy.logging.get_logger('feedforward')
    # Ctrl-C and SIGTERM only set a flag that the spin loop reads (within
    # 0.1 s): rclpy's handlers would raise or shut the context down inside a
    # callback, breaking off a publish (logged FATAL by the executor).
    stop = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda number, frame: stop.append(number))
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as error:   # rcl refuses the arguments or file
        logger.fatal(f'cannot start: {error}')
        return 2
    node = None
    try:
        node = FeedforwardNode()
        executor = _executor()
        executor.add_node(node)
        # Not executor.spin(): with the EventsExecutor of the rclpy 7.1.6
        # wheels it busy-loops without running callbacks or seeing SIGINT.
        while rclpy.ok() and not stop:
            executor.spin_once(timeout_sec=0.1)
    except (ValueError, ParameterException) as error:
        logger.fatal(f'invalid parameters, not starting: {error}')
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        if rclpy.ok():
            raise
        # Interrupted while starting: rcl calls fail on the shut-down context.
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _executor():
    """Return the EventsExecutor (2.5x less CPU per message here) if any."""
    try:
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    except ImportError:
        return rclpy.executors.SingleThreadedExecutor()


if __name__ == '__main__':
    raise SystemExit(main())
