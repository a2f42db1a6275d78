"""
The ROS glue shared by the package's nodes: inputs, parameters, main loop.

- :class:`InputNode`: a Node whose input subscriptions are read on a thread
  of their own from an rcl wait set, so a flood cannot pile up work;
- :func:`declare_specs` and :func:`spec_values`: ROS parameters declared
  from a table of :class:`orthoglide_ros.settings.Spec` and read back as
  plain Python values; :meth:`InputNode.declare_settings` and
  :meth:`InputNode.apply_changes_with`: run-time changes validated as a
  whole set and applied at once;
- :func:`default_qos`: the reliable keep-last 10 profile of every topic;
- :func:`diagnostic_array`: one node's status for ``/diagnostics``;
- :func:`run`: ``main()`` of a node: start-up errors, signals, spinning.

Why a wait set for the inputs. rclpy's EventsExecutor queues one event per
message received, whatever the subscription's history depth: when messages
arrive faster than the callbacks run, the queue (and the process memory)
grows without bound and timers and services wait behind it (measured:
+10.7 MB over a 10 s flood, /diagnostics silent). A wait set is level
triggered instead: it says *that* a subscription holds messages, and the
reader takes what the middleware kept, at most the history depth. The
other entities (timers, the parameter services) stay with the executor on
the main thread; the input thread and they share :attr:`InputNode.lock`.
"""

import array
from copy import copy
from contextlib import ExitStack
import signal
import threading
import time
import traceback

import rclpy
from rclpy.exceptions import (ParameterException,
                              ParameterUninitializedException)
from rclpy.executors import ExternalShutdownException
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, ParameterDescriptor,
                                SetParametersResult)

# Reliable, keep-last 10 on every input and output; users override it with
# the standard qos_overrides.<topic>.<publisher|subscription>.* parameters.
_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                  reliability=ReliabilityPolicy.RELIABLE)
# Longest wait of the input thread before it looks at its stop flag and the
# context again (a stop also wakes it at once through a guard condition).
INPUT_WAIT = 0.1    # s
SPIN_PERIOD = 0.1   # s: the main loop sees a signal within this time
DIAGNOSTICS_PERIOD = 1.0    # s between two /diagnostics messages
WARNING_PERIOD = 1.0        # s between two warnings of the same reason

_TYPES = {'double': Parameter.Type.DOUBLE,
          'double_array': Parameter.Type.DOUBLE_ARRAY,
          'string': Parameter.Type.STRING,
          'string_array': Parameter.Type.STRING_ARRAY,
          'bool': Parameter.Type.BOOL}


def default_qos():
    """
    Return a new reliable keep-last 10 profile.

    A new one per entity: rclpy writes the QoS overrides into the profile
    it is given, so a shared one would leak them between entities.
    """
    return copy(_QOS)


def declare_specs(node, specs):
    """Declare one ROS parameter per Spec (type, default, range, text)."""
    for spec in specs:
        descriptor = ParameterDescriptor(
            description=spec.description, type=_TYPES[spec.type].value)
        if spec.range is not None:
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=spec.range[0], to_value=spec.range[1])]
        node.declare_parameter(
            spec.name, _TYPES[spec.type] if spec.default is None
            else spec.default, descriptor)


def spec_values(node, specs, changes=()):
    """
    Return ``{name: value}`` of the specs' parameters with ``changes`` applied.

    Plain types: rclpy gives double arrays as ``array.array``, this gives
    lists; a parameter declared without a value gives None.
    """
    values = {}
    for spec in specs:
        try:
            values[spec.name] = node.get_parameter(spec.name).value
        except ParameterUninitializedException:
            values[spec.name] = None
    values.update((p.name, p.value) for p in changes)
    return {name: list(value) if isinstance(value, array.array)
            else value for name, value in values.items()}


class InputNode(Node):
    """
    A Node whose input subscriptions run on an input thread (wait set).

    Subscriptions made with :meth:`create_input_subscription` are hidden
    from executors (:attr:`subscriptions` leaves them out) and read by the
    input thread, started by :meth:`start_inputs` and stopped by
    :meth:`destroy_node`. Their callbacks run with :attr:`lock` held; the
    node's other callbacks (timers, parameter changes) that touch the same
    state take it too. Each wake-up takes every message a ready
    subscription holds (at most its history depth), in arrival order.
    """

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        self.lock = threading.Lock()
        self._internal_errors = 0
        self._last_warning = {}
        self._inputs = []
        self._input_thread = None
        self._stopping = False
        self._wake = GuardCondition(None, None, context=self.context)

    @property
    def subscriptions(self):
        """Return the subscriptions an executor serves (not the inputs)."""
        return (s for s in super().subscriptions if s not in self._inputs)

    def create_input_subscription(self, *args, **kwargs):
        """Create a subscription read by the input thread (same arguments)."""
        subscription = self.create_subscription(*args, **kwargs)
        self._inputs.append(subscription)
        return subscription

    def start_inputs(self):
        """Start the input thread (once, after the inputs are created)."""
        self._input_thread = threading.Thread(
            target=self._read_inputs, name=f'{self.get_name()} inputs',
            daemon=True)
        self._input_thread.start()

    def declare_settings(self, specs, parse):
        """
        Declare the parameters of ``specs``; return ``parse(their values)``.

        ``parse`` validates a complete ``{name: value}`` set into the
        node's settings, raising ValueError that names the parameter (an
        invalid start-up set: :func:`run` exits 2).
        """
        declare_specs(self, specs)
        self._specs, self._parse = specs, parse
        return parse(spec_values(self, specs))

    def apply_changes_with(self, apply):
        """
        Take run-time parameter changes: validated whole, applied at once.

        A change is refused, with the parse error as the reason, unless the
        whole resulting set parses; an accepted one calls ``apply(new
        settings)`` with :attr:`lock` held, so the next input sees all the
        new values and none of the old. Call it once the entities that
        ``apply`` touches exist.
        """
        self._apply_settings = apply
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    def _validate_parameters(self, parameters):
        try:
            self._parse(spec_values(self, self._specs, parameters))
        except ValueError as error:
            self.get_logger().warning(f'parameter change refused: {error}')
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        settings = self._parse(spec_values(self, self._specs))
        with self.lock:
            self._apply_settings(settings)

    def throttle(self, reason):
        """Say whether a message of this reason may be logged now."""
        now = time.monotonic()
        if now - self._last_warning.get(reason, -1e9) < WARNING_PERIOD:
            return False
        self._last_warning[reason] = now
        return True

    def warn_throttled(self, reason, message):
        """Log a warning, at most one per WARNING_PERIOD for ``reason``."""
        if self.throttle(reason):
            self.get_logger().warning(message)

    @property
    def internal_errors(self):
        """Return how many defects :meth:`report_defect` has counted."""
        return self._internal_errors

    def report_defect(self, where):
        """
        Count an exception that escaped a callback (a defect, not bad input).

        Logged with its traceback at most once a WARNING_PERIOD; the node
        goes on and its diagnostics turn ERROR. Call it from an ``except``.
        """
        self._internal_errors += 1
        if self.throttle('internal'):
            self.get_logger().error(f'internal error {where}:\n'
                                    + traceback.format_exc())

    def on_input_error(self):
        """Handle an exception escaping an input callback: a defect."""
        self.report_defect('in an input callback')

    def publish_diagnostics_with(self, build):
        """
        Publish ``build()`` on ``/diagnostics`` every DIAGNOSTICS_PERIOD.

        ``build`` returns a DiagnosticArray (see :func:`diagnostic_array`)
        and runs with :attr:`lock` held; a defect in it is reported and the
        next period tries again.
        """
        publisher = self.create_publisher(DiagnosticArray, '/diagnostics', 10)

        def publish():
            try:
                with self.lock:
                    message = build()
            except Exception:   # a defect: counted, next period again
                self.report_defect('in the diagnostics')
                return
            publisher.publish(message)
        self.create_timer(DIAGNOSTICS_PERIOD, publish)

    def destroy_node(self):
        """Stop the input thread, then destroy the node."""
        self._stopping = True
        if self._input_thread is not None:
            self._wake.trigger()
            self._input_thread.join()
            self._input_thread = None
        self._wake.destroy()
        super().destroy_node()

    def _read_inputs(self):
        try:
            self._wait_and_take()
        except Exception:   # a defect: no input is read any more
            self.get_logger().fatal('input thread stopped by an error:\n'
                                    + traceback.format_exc())

    def _wait_and_take(self):
        handles = [s.handle for s in self._inputs]
        with ExitStack() as stack:
            # Held for the thread's life: the handles stay valid meanwhile.
            for handle in (*handles, self._wake.handle, self.context.handle):
                stack.enter_context(handle)
            wait_set = _rclpy.WaitSet(len(handles), 1, 0, 0, 0, 0,
                                      self.context.handle)
            timeout = int(INPUT_WAIT * 1e9)
            while not self._stopping and self.context.ok():
                wait_set.clear_entities()
                for handle in handles:
                    wait_set.add_subscription(handle)
                wait_set.add_guard_condition(self._wake.handle)
                try:
                    wait_set.wait(timeout)
                except Exception:   # the context shut down meanwhile
                    if self.context.ok():
                        raise
                    return
                ready = wait_set.get_ready_entities('subscription')
                for subscription, handle in zip(self._inputs, handles):
                    if handle.pointer in ready:
                        self._take_all(subscription, handle)

    def _take_all(self, subscription, handle):
        while not self._stopping:
            taken = handle.take_message(subscription.msg_type,
                                        subscription.raw)
            if taken is None:
                return
            with self.lock:
                try:
                    subscription.callback(taken[0])
                except Exception:   # a defect: report it, keep reading
                    self.on_input_error()


def diagnostic_array(node, title, level, message, values):
    """
    Return a DiagnosticArray holding one status of ``node``.

    Named ``'<node name>: <title>'``, hardware id ``orthoglide``; ``level``
    a DiagnosticStatus level; ``values`` ``(key, value)`` pairs, shown as
    text (booleans in lower case, floats with 6 significant digits).
    """
    status = DiagnosticStatus(
        name=f'{node.get_name()}: {title}', hardware_id='orthoglide',
        level=level, message=message,
        values=[KeyValue(key=k, value=_text(v)) for k, v in values])
    array_message = DiagnosticArray(status=[status])
    array_message.header.stamp = node.get_clock().now().to_msg()
    return array_message


def _text(value):
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)


def run(node_class, name, args=None):
    """
    Run one node until Ctrl-C, SIGTERM or shutdown; return the exit code.

    0 on a normal stop, 2 when the node refuses its start-up parameters
    (ValueError or ParameterException, logged as FATAL) or rcl refuses the
    arguments. Ctrl-C and SIGTERM only set a flag that the spin loop reads
    within SPIN_PERIOD: rclpy's handlers would raise or shut the context
    down inside a callback, breaking off a publish.
    """
    logger = rclpy.logging.get_logger(name)
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
        node = node_class()
        executor = _executor()
        executor.add_node(node)
        # Not executor.spin(): with the EventsExecutor of the rclpy 7.1.6
        # wheels it busy-loops without running callbacks or seeing SIGINT.
        while rclpy.ok() and not stop:
            executor.spin_once(timeout_sec=SPIN_PERIOD)
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
