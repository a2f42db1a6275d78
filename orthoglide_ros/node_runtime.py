"""
The ROS glue shared by the package's nodes: inputs, parameters, main loop.

- :class:`InputNode`: a Node whose input subscriptions are read on a thread
  of their own from an rcl wait set, so a flood cannot pile up work;
- :func:`declare_specs` and :func:`spec_values`: ROS parameters declared
  from a node's :class:`orthoglide_ros.parameters.Table` and read back as
  plain Python values; :meth:`InputNode.declare_settings` and
  :meth:`InputNode.apply_changes_with`: run-time changes validated as a
  whole set and applied at once;
- :func:`default_qos`: the reliable keep-last 10 profile of every topic;
- :meth:`InputNode.publish_status`: a core's
  :class:`orthoglide_ros.status.Status` on ``/diagnostics`` once a second;
- :func:`run`: ``main()`` of a node: start-up errors, signals, spinning;
- :func:`freeze_start_up_objects`: no garbage-collector stalls over the
  start-up objects (called by :func:`run`).

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
import gc
import signal
import threading
import time
import traceback

import rclpy
from rclpy.exceptions import (InvalidParameterValueException,
                              ParameterException,
                              ParameterUninitializedException)
from rclpy.executors import ExternalShutdownException
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange,
                                ParameterDescriptor, SetParametersResult)

from orthoglide_ros.parameters import ParameterError

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
          'integer': Parameter.Type.INTEGER,
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
    """
    Declare one ROS parameter per Spec (type, default, range, text).

    A start-up value that rclpy refuses against its descriptor (out of
    range) raises :class:`ParameterError` naming it, as the table would.
    """
    for spec in specs:
        descriptor = ParameterDescriptor(
            description=spec.description, type=_TYPES[spec.type].value,
            read_only=spec.read_only)
        if spec.range is not None and spec.type == 'double':
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=spec.range[0], to_value=spec.range[1])]
        elif spec.range is not None and spec.type == 'integer':
            descriptor.integer_range = [IntegerRange(
                from_value=spec.range[0], to_value=spec.range[1])]
        try:
            node.declare_parameter(
                spec.name, _TYPES[spec.type] if spec.default is None
                else spec.default, descriptor)
        except InvalidParameterValueException as error:
            raise ParameterError(spec.name, str(error.args[0])) from None


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

    :attr:`arrival` is, during an input callback, the time the middleware
    received that message on the ``time.monotonic()`` clock: timeouts
    that judge inputs by arrival use it, so a callback run late (a busy
    machine, a batch of messages) does not make its input look late.
    """

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        self.lock = threading.Lock()
        self._internal_errors = 0
        self._last_warning = {}
        self._inputs = []
        self._input_events = []
        self._input_thread = None
        self._stopping = False
        self.arrival = None
        self._wake = GuardCondition(None, None, context=self.context)

    @property
    def subscriptions(self):
        """Return the subscriptions an executor serves (not the inputs)."""
        return (s for s in super().subscriptions if s not in self._inputs)

    @property
    def waitables(self):
        """
        Return the waitables an executor serves (not the inputs' events).

        The QoS event handlers of the inputs (incompatible QoS or type
        warnings) are waited on by the input thread: with rmw_fastrtps, a
        reader's events and its data share one status condition, and a
        second wait set holding its events (an executor's) masks the data
        out of the input thread's wait (measured: inputs delayed by 100 ms
        and more while a SingleThreadedExecutor spun the node).
        """
        return (w for w in super().waitables
                if w not in self._input_events)

    def create_input_subscription(self, *args, **kwargs):
        """Create a subscription read by the input thread (same arguments)."""
        subscription = self.create_subscription(*args, **kwargs)
        self._inputs.append(subscription)
        self._input_events.extend(subscription.event_handlers)
        return subscription

    def start_inputs(self):
        """Start the input thread (once, after the inputs are created)."""
        self._input_thread = threading.Thread(
            target=self._read_inputs, name=f'{self.get_name()} inputs',
            daemon=True)
        self._input_thread.start()

    def declare_settings(self, table):
        """
        Declare the parameters of ``table``; return its parsed settings.

        ``table``: the node's :class:`orthoglide_ros.parameters.Table`. An
        invalid start-up set raises ValueError naming the parameter
        (:func:`run` exits 2).
        """
        declare_specs(self, table.specs)
        self._table = table
        return table.parse(spec_values(self, table.specs))

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
            self._table.parse(spec_values(self, self._table.specs,
                                          parameters))
        except ValueError as error:
            self.get_logger().warning(f'parameter change refused: {error}')
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        settings = self._table.parse(spec_values(self, self._table.specs))
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

    @property
    def finished(self):
        """Override: whether the node's work is over (:func:`run` stops)."""
        return False

    def on_stop(self, interrupted):
        """
        Override: run by :func:`run` before the node is destroyed.

        ``interrupted``: stopped by a signal (else the node finished).
        """

    def on_input_error(self):
        """Handle an exception escaping an input callback: a defect."""
        self.report_defect('in an input callback')

    def publish_status(self, title, core):
        """
        Publish ``core.status(now, internal errors)`` on ``/diagnostics``.

        Every DIAGNOSTICS_PERIOD, as one DiagnosticStatus named
        ``'<node name>: <title>'`` (:func:`diagnostic_array`); ``status``
        runs with :attr:`lock` held. A defect in it is reported and the
        next period tries again.
        """
        publisher = self.create_publisher(DiagnosticArray, '/diagnostics', 10)

        def publish():
            try:
                with self.lock:
                    status = core.status(time.monotonic(),
                                         self.internal_errors)
                message = diagnostic_array(self, title, status)
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
        events = self._input_events
        with ExitStack() as stack:
            # Held for the thread's life: the handles stay valid meanwhile.
            for handle in (*handles, *events, self._wake.handle,
                           self.context.handle):
                stack.enter_context(handle)
            wait_set = _rclpy.WaitSet(len(handles), 1, 0, 0, 0, len(events),
                                      self.context.handle)
            timeout = int(INPUT_WAIT * 1e9)
            while not self._stopping and self.context.ok():
                wait_set.clear_entities()
                for handle in handles:
                    wait_set.add_subscription(handle)
                for event in events:
                    event.add_to_wait_set(wait_set)
                wait_set.add_guard_condition(self._wake.handle)
                try:
                    wait_set.wait(timeout)
                except Exception:   # the context shut down meanwhile
                    if self.context.ok():
                        raise
                    return
                for event in events:
                    if event.is_ready(wait_set):
                        self._handle_event(event)
                ready = wait_set.get_ready_entities('subscription')
                if ready:
                    self._dispatch([
                        (subscription, handle)
                        for subscription, handle in zip(self._inputs, handles)
                        if handle.pointer in ready])
                elif not self._stopping:
                    self._idle()

    def on_inputs_idle(self):
        """
        Override: run when a wait of the input thread ends with no input.

        That is after INPUT_WAIT without input, or a QoS event alone; the
        lock is held. Every message the middleware had received is handled by then, so
        a timeout judged here by ``time.monotonic()`` cannot drop what a
        message still waiting in a queue would have completed (a timer on
        the executor could: its thread may run while this one is stalled).
        """

    def _idle(self):
        with self.lock:
            try:
                self.on_inputs_idle()
            except Exception:   # a defect: report it, keep reading
                self.on_input_error()

    def _handle_event(self, event):
        """Run a QoS event's callback (rclpy's default: a warning)."""
        data = event.take_data()
        if data:
            with self.lock:
                try:
                    event.callback(data)
                except Exception:   # a defect: report it, keep reading
                    self.on_input_error()

    def _dispatch(self, ready):
        """
        Take every message the ready subscriptions hold; call back in order.

        Arrival order across subscriptions (the middleware's reception
        time): a pose, twist and accel published in that order are handled
        in that order even when they wait together. At most the history
        depth per subscription.
        """
        batch = []
        for subscription, handle in ready:
            while True:
                taken = handle.take_message(subscription.msg_type,
                                            subscription.raw)
                if taken is None:
                    break
                batch.append((taken[1]['received_timestamp'], len(batch),
                              subscription.callback, taken[0]))
        batch.sort(key=lambda item: item[:2])
        # Reception (system clock, ns) to the monotonic clock; never later
        # than now, and now when the middleware gives no reception time.
        monotonic_now = time.monotonic()
        offset = monotonic_now - time.time_ns() * 1e-9
        for received, _, callback, message in batch:
            if self._stopping:
                return
            with self.lock:
                self.arrival = (min(received * 1e-9 + offset, monotonic_now)
                                if received > 0 else monotonic_now)
                try:
                    callback(message)
                except Exception:   # a defect: report it, keep reading
                    self.on_input_error()


def diagnostic_array(node, title, status):
    """
    Return a DiagnosticArray holding one :class:`Status` of ``node``.

    Named ``'<node name>: <title>'``, hardware id ``orthoglide``; the
    values shown as text (booleans in lower case, floats with 6
    significant digits).
    """
    level, message, values = status
    diagnostic = DiagnosticStatus(
        name=f'{node.get_name()}: {title}', hardware_id='orthoglide',
        level=bytes((level,)), message=message,
        values=[KeyValue(key=k, value=_text(v)) for k, v in values])
    array_message = DiagnosticArray(status=[diagnostic])
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
        freeze_start_up_objects()
        # Not executor.spin(): with the EventsExecutor of the rclpy 7.1.6
        # wheels it busy-loops without running callbacks or seeing SIGINT.
        while rclpy.ok() and not stop and not node.finished:
            executor.spin_once(timeout_sec=SPIN_PERIOD)
        node.on_stop(interrupted=bool(stop) or not rclpy.ok())
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


def freeze_start_up_objects():
    """
    Keep the start-up objects out of the garbage collector's full passes.

    After the imports and the node's construction a process tracks ~37,000
    objects (rclpy, numpy, the messages); a full (generation 2) collection
    walks them all with the GIL held, 11-16 ms measured here, a stall of
    every thread of the node that a 500 Hz-1 kHz loop sees as a hiccup.
    ``gc.freeze()`` moves them to a permanent generation: collections then
    walk only what was allocated since (0.01 ms measured after it).
    """
    gc.collect()
    gc.freeze()


def _executor():
    """Return the EventsExecutor (2.5x less CPU per message here) if any."""
    try:
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    except ImportError:
        return rclpy.executors.SingleThreadedExecutor()
