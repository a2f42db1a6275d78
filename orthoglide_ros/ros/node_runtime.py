"""
The ROS glue shared by the package's nodes: threads, parameters, main loop.

- :class:`InputNode`: a Node whose inputs are read on threads of their own
  from rcl wait sets, whose periodic work (the feedforward's tick, the
  simulator's steps, ``/diagnostics``) runs on threads of its own too, and
  whose executor serves only the services (parameters, ``~/reset``);
- :func:`declare_specs` and :func:`spec_values`: ROS parameters declared
  from a node's :class:`orthoglide_ros.cores.parameters.Table` and read back as
  plain Python values; :meth:`InputNode.declare_settings` and
  :meth:`InputNode.apply_changes_with`: run-time changes validated as a
  whole set and applied at once;
- :func:`default_qos`: the reliable keep-last 10 profile of every topic;
- :meth:`InputNode.publish_status`: a core's
  :class:`orthoglide_ros.cores.status.Status` on ``/diagnostics`` once a second;
- :func:`clip`: the one place that shortens text taken from messages
  before it reaches a log line or a reply;
- :func:`run`: ``main()`` of a node: start-up errors, signals, spinning;
- :func:`freeze_start_up_objects`: no garbage-collector stalls over the
  start-up objects (called by :func:`run`).

Why wait sets for the inputs. rclpy's EventsExecutor queues one event per
message received, whatever the subscription's history depth: when messages
arrive faster than the callbacks run, the queue (and the process memory)
grows without bound and timers and services wait behind it (measured:
+10.7 MB over a 10 s flood, /diagnostics silent). A wait set is level
triggered instead: it says *that* a subscription holds messages, and the
reader takes what the middleware kept, at most the history depth.

What another process sends cannot stall a node. Every input is taken raw
(serialized bytes): a message longer than its input's byte limit is
refused (``oversize``) before any decoding, the decoding runs outside
:attr:`InputNode.lock`, and only the core's rule runs under it. Inputs of
different cost read on different threads (``group``), so a long message on
one input does not delay another. Periodic work does not share the
executor's thread with the services: rmw_fastrtps holds a reply for up to
100 ms, with the GIL held, when the requesting client has gone (measured:
100 requests, then a clean exit, stalled every thread of the process for
6.3 s), so each reply first waits, without the GIL, for its client to
listen on the reply topic and is dropped once that client has gone (see
:meth:`InputNode._guard_service` and ``service_replies``).
"""

import array
from contextlib import ExitStack
from copy import copy
import gc
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
from rclpy.serialization import deserialize_message
from rclpy.signals import SignalHandlerOptions

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange,
                                ParameterDescriptor, ParameterType,
                                SetParametersResult)
from rcl_interfaces.srv import SetParameters, SetParametersAtomically

from orthoglide_ros.ros.console import install_signal_handlers
from orthoglide_ros.cores.inputs import Rejected, SMALL_MESSAGE_BYTES
from orthoglide_ros.cores.parameters import ParameterError
from orthoglide_ros.ros.service_replies import (DROP, REPLY_POLL, REPLY_TIMED_OUT,
                                                ReplyRoutes, SEND)

# Reliable, keep-last 10 on every input and output; users override it with
# the standard qos_overrides.<topic>.<publisher|subscription>.* parameters.
_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                  reliability=ReliabilityPolicy.RELIABLE)
# Longest wait of an input thread before it looks at its stop flag and the
# context again (a stop also wakes it at once through a guard condition).
INPUT_WAIT = 0.1    # s
SPIN_PERIOD = 0.1   # s: the main loop sees a signal within this time
DIAGNOSTICS_PERIOD = 1.0    # s between two /diagnostics messages
WARNING_PERIOD = 1.0        # s between two warnings of the same reason
# Shortest wait of a periodic thread between two runs (s), however late.
MIN_IDLE = 0.0005
# Longest log line or reply reason made from a message's text (characters).
TEXT_LIMIT = 2000
# Parameter value types a request may carry (ParameterType's constants).
_PARAMETER_TYPES = frozenset(range(ParameterType.PARAMETER_NOT_SET,
                                   ParameterType.PARAMETER_STRING_ARRAY + 1))

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


def clip(text, limit=TEXT_LIMIT):
    """
    Return ``text`` cut to about ``limit`` characters (its middle dropped).

    The one place where text that a message or a request carries (a frame
    id, joint names, a parameter value) is shortened before it is logged or
    sent back, so no input can make a log line longer than ``limit`` plus
    a few dozen characters.
    """
    text = str(text)
    if len(text) <= limit:
        return text
    half = limit // 2
    return (f'{text[:half]} ... [{len(text) - 2 * half} characters cut] ... '
            f'{text[-half:]}')


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
            raise ParameterError(spec.name, clip(error.args[0])) from None


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


class _Input:
    """One raw input subscription: its limit, its decoder, its handler."""

    def __init__(self, subscription, source, decode, handle, max_bytes):
        self.subscription = subscription
        self.source = source
        self.decode = decode
        self.handle = handle
        self.max_bytes = max_bytes


class _InputGroup:
    """Inputs read by one thread from one wait set."""

    def __init__(self, name, context):
        self.name = name
        self.inputs = []
        self.events = []
        self.wake = GuardCondition(None, None, context=context)
        self.thread = None


class InputNode(Node):
    """
    A Node whose inputs and periodic work run on threads of their own.

    Inputs made with :meth:`create_input` are raw subscriptions hidden from
    executors (:attr:`subscriptions` leaves them out) and read by one
    thread per group, started by :meth:`start_threads` and stopped by
    :meth:`destroy_node`. For each message: the byte limit first, then its
    decoder (outside the lock), then its handler with :attr:`lock` held.
    Each wake-up takes every message a ready subscription holds (at most
    its history depth), in arrival order. Work made with
    :meth:`create_periodic` runs on a thread of its own, on a steady
    schedule. The executor serves what is left: the services, whose
    callbacks cannot end the node and whose replies cannot stall it
    (:meth:`_guard_service`).

    :attr:`arrival` is, during an input handler, the time the middleware
    received that message on the ``time.monotonic()`` clock: timeouts
    that judge inputs by arrival use it, so a handler run late (a busy
    machine, a batch of messages) does not make its input look late.
    """

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        self.lock = threading.Lock()
        self._internal_errors = 0
        self._last_warning = {}
        self._groups = {}
        self._sources = {}
        self._hidden = set()
        self._hidden_events = set()
        self._periodic = []
        self._stopping = threading.Event()
        self.replies_dropped = 0
        self.arrival = None
        for service in self.services:   # the parameter services
            self._guard_service(service)

    # Entities ---------------------------------------------------------------
    @property
    def subscriptions(self):
        """Return the subscriptions an executor serves (not the inputs)."""
        return (s for s in super().subscriptions if s not in self._hidden)

    @property
    def waitables(self):
        """
        Return the waitables an executor serves (not the inputs' events).

        The QoS event handlers of the inputs (incompatible QoS or type
        warnings) are waited on by the input threads: with rmw_fastrtps, a
        reader's events and its data share one status condition, and a
        second wait set holding its events (an executor's) masks the data
        out of the input thread's wait (measured: inputs delayed by 100 ms
        and more while a SingleThreadedExecutor spun the node).
        """
        return (w for w in super().waitables
                if w not in self._hidden_events)

    def create_input(self, msg_type, topic, handle, qos, source, *,
                     decode=None, max_bytes=SMALL_MESSAGE_BYTES,
                     group='inputs', **kwargs):
        """
        Create an input: a raw subscription read by ``group``'s thread.

        ``handle(value)`` runs with :attr:`lock` held on ``decode(bytes)``
        (default: rclpy's deserializer to ``msg_type``), which runs
        outside it. A message over ``max_bytes``, or one ``decode`` cannot
        read, goes to :meth:`on_input_rejected` with ``source`` and a
        :class:`Rejected` (``oversize``, ``malformed``). Other arguments
        as for ``create_subscription``.
        """
        subscription = self.create_subscription(
            msg_type, topic, lambda data: None, qos, raw=True, **kwargs)
        group = self._groups.setdefault(
            group, _InputGroup(group, self.context))
        item = _Input(subscription, source,
                      decode or (lambda data: deserialize_message(
                          data, msg_type)),
                      handle, max_bytes)
        group.inputs.append(item)
        self._sources[source] = item
        group.events.extend(subscription.event_handlers)
        self._hidden.add(subscription)
        self._hidden_events.update(subscription.event_handlers)
        return subscription

    def start_threads(self):
        """Start the input groups' and the periodic threads (once, last)."""
        for group in self._groups.values():
            group.thread = threading.Thread(
                target=self._read_inputs, args=(group,),
                name=f'{self.get_name()} {group.name}', daemon=True)
            group.thread.start()
        for thread in self._periodic:
            thread.start()

    def deliver(self, source, data, arrival):
        """
        Handle one serialized message of input ``source`` as it came.

        What the input threads do with each message taken: the byte
        limit, the decoder (outside :attr:`lock`), then the handler or
        :meth:`on_input_rejected` with :attr:`lock` held and
        :attr:`arrival` set to ``arrival`` (monotonic s).
        """
        item = self._sources[source]
        value, rejection = _decoded(item, data)
        with self.lock:
            self.arrival = arrival
            try:
                if rejection is None:
                    item.handle(value)
                else:
                    self.on_input_rejected(item.source, rejection)
            except Exception:   # a defect: report it, keep reading
                self.report_defect('in an input callback')

    def create_periodic(self, period, work, name):
        """
        Run ``work()`` every ``period()`` s on a thread of its own.

        ``period`` is a function, read before each wait, so a parameter
        can change the rate. The schedule is steady (the next run is due
        one period after the last one was due); runs that are more than
        one period late are dropped, not made up, and a run late anyway
        waits MIN_IDLE first, so work that cannot keep up (the simulator
        at 10 kHz) still leaves the inputs their turn. ``work`` takes
        :attr:`lock` itself when it needs it; an exception in it is a
        defect (:meth:`report_defect`), and the next period runs anyway.
        """
        def loop():
            due = time.monotonic()
            while not self._stopping.is_set() and self.context.ok():
                step = period()
                due += step
                delay = due - time.monotonic()
                if delay < -step:
                    due = time.monotonic()
                # Even when late: the other threads get the GIL and the
                # lock in between (Python's lock is not fair to a waiter).
                if self._stopping.wait(max(delay, MIN_IDLE)):
                    return
                try:
                    work()
                except Exception:   # a defect: count it, go on
                    self.report_defect(f'in the periodic {name}')
        thread = threading.Thread(target=loop,
                                  name=f'{self.get_name()} {name}',
                                  daemon=True)
        self._periodic.append(thread)
        return thread

    def create_service(self, *args, **kwargs):
        """Create a service whose callback and reply are guarded."""
        service = super().create_service(*args, **kwargs)
        self._guard_service(service)
        return service

    # Parameters -------------------------------------------------------------
    def declare_settings(self, table):
        """
        Declare the parameters of ``table``; return its parsed settings.

        ``table``: the node's :class:`orthoglide_ros.cores.parameters.Table`. An
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
            reason = clip(error)
            self.log('warning', f'parameter change refused: {reason}')
            return SetParametersResult(successful=False, reason=reason)
        except Exception:   # a defect: refuse the change, report it
            self.report_defect('validating a parameter change')
            return SetParametersResult(
                successful=False, reason='internal error: see the log')
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        settings = self._table.parse(spec_values(self, self._table.specs))
        with self.lock:
            self._apply_settings(settings)

    # Logging ----------------------------------------------------------------
    def log(self, level, text):
        """
        Log ``text``, clipped (:func:`clip`), at ``level``.

        ``level``: ``'info'``, ``'warning'``, ``'error'`` or ``'fatal'``.
        One call per level: rclpy's logger keys its state by call site and
        refuses two severities from one line.
        """
        logger, text = self.get_logger(), clip(text)
        if level == 'info':
            logger.info(text)
        elif level == 'warning':
            logger.warning(text)
        elif level == 'error':
            logger.error(text)
        else:
            logger.fatal(text)

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
            self.log('warning', message)

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
            self.log('error', f'internal error {where}:\n'
                     + traceback.format_exc())

    # Overrides --------------------------------------------------------------
    @property
    def finished(self):
        """Override: whether the node's work is over (:func:`run` stops)."""
        return False

    def on_stop(self, interrupted):
        """
        Override: run by :func:`run` before the node is destroyed.

        ``interrupted``: stopped by a signal (else the node finished).
        """

    def on_input_rejected(self, source, rejection):
        """
        Override: count and warn about a message refused before its handler.

        Runs with :attr:`lock` held; ``source`` as given to
        :meth:`create_input`, ``rejection`` a :class:`Rejected`.
        """
        self.warn_throttled((source, rejection.reason),
                            f'{source} rejected ({rejection.reason}): '
                            f'{rejection}')

    def on_inputs_idle(self):
        """
        Override: run when a wait of the ``inputs`` group ends with no input.

        That is after INPUT_WAIT without input, or a QoS event alone; the
        lock is held. Every message the middleware had received is handled
        by then, so a timeout judged here by ``time.monotonic()`` cannot
        drop what a message still waiting in a queue would have completed
        (a timer could: its thread may run while this one is stalled).
        """

    def publish_status(self, title, core):
        """
        Publish ``core.status(now, internal errors)`` on ``/diagnostics``.

        Every DIAGNOSTICS_PERIOD, from a periodic thread, as one
        DiagnosticStatus named ``'<node name>: <title>'``
        (:func:`diagnostic_array`); ``status`` runs with :attr:`lock` held.
        The node adds one value of its own: ``replies dropped (client
        gone)``, the service replies no client waited for.
        """
        publisher = self.create_publisher(DiagnosticArray, '/diagnostics', 10)

        def publish():
            with self.lock:
                status = core.status(time.monotonic(), self.internal_errors)
            status.values.append(('replies dropped (client gone)',
                                  self.replies_dropped))
            publisher.publish(diagnostic_array(self, title, status))
        self.create_periodic(lambda: DIAGNOSTICS_PERIOD, publish,
                             'diagnostics')

    def destroy_node(self):
        """Stop the input and periodic threads, then destroy the node."""
        self._stopping.set()
        for group in self._groups.values():
            if group.thread is not None:
                group.wake.trigger()
                group.thread.join()
                group.thread = None
            group.wake.destroy()
        for thread in self._periodic:
            if thread.is_alive():
                thread.join()
        super().destroy_node()

    # Services ---------------------------------------------------------------
    def _guard_service(self, service):
        """
        Keep a service from ending or stalling the node.

        The callback: a set-parameters request naming a value type that
        does not exist (rclpy raises on it, outside its own error handling)
        is refused whole with the reason; any other exception is a defect,
        answered with the default response.

        The reply waits, without the GIL, polling the graph, until
        :class:`~orthoglide_ros.ros.service_replies.ReplyRoutes` (the rule)
        says it may go to rmw, which would otherwise wait for a departed
        client's reader up to 100 ms with the GIL held; a reply the rule
        drops is counted in :attr:`replies_dropped`.
        """
        callback, send = service.callback, service.send_response
        reply_topic = f'rr{service.service_name}Reply'
        request_topic = f'rq{service.service_name}Request'
        srv_type = service.srv_type
        routes = ReplyRoutes()

        def guarded_callback(request, response):
            try:
                refusal = _malformed_parameters(srv_type, request)
                if refusal is None:
                    return callback(request, response)
            except Exception:   # a defect: answer, keep the node
                self.report_defect(f'in the service {service.service_name}')
                return srv_type.Response()
            self.warn_throttled('malformed request', refusal)
            result = SetParametersResult(successful=False, reason=refusal)
            if srv_type is SetParameters:
                response.results = [result] * len(request.parameters)
            else:
                response.result = result
            return response

        def guarded_send(response, header):
            # An rmw_service_info_t says when the request was received.
            received = getattr(header, 'received_timestamp', 0) * 1e-9 \
                or None
            begin = time.monotonic()
            while True:
                now = time.monotonic()
                routes.poll(
                    time.time(), now,
                    [info.endpoint_gid for info in
                     self.get_publishers_info_by_topic(
                         request_topic, no_mangle=True)],
                    [info.endpoint_gid for info in
                     self.get_subscriptions_info_by_topic(
                         reply_topic, no_mangle=True)])
                decision = routes.decide(received, now, begin)
                if decision == SEND:
                    break
                if decision == DROP:
                    self.replies_dropped += 1
                    return
                time.sleep(REPLY_POLL)
            start = time.monotonic()
            send(response, header)
            if time.monotonic() - start >= REPLY_TIMED_OUT:
                routes.timed_out(received)

        service.callback = guarded_callback
        service.send_response = guarded_send

    # Input threads ----------------------------------------------------------
    def _read_inputs(self, group):
        try:
            self._wait_and_take(group)
        except Exception:   # a defect: no input is read any more
            self.log('fatal', f'input thread {group.name} stopped by an '
                     'error:\n' + traceback.format_exc())

    def _wait_and_take(self, group):
        inputs = group.inputs
        handles = [i.subscription.handle for i in inputs]
        events = group.events
        with ExitStack() as stack:
            # Held for the thread's life: the handles stay valid meanwhile.
            for handle in (*handles, *events, group.wake.handle,
                           self.context.handle):
                stack.enter_context(handle)
            wait_set = _rclpy.WaitSet(len(handles), 1, 0, 0, 0, len(events),
                                      self.context.handle)
            timeout = int(INPUT_WAIT * 1e9)
            while not self._stopping.is_set() and self.context.ok():
                wait_set.clear_entities()
                for handle in handles:
                    wait_set.add_subscription(handle)
                for event in events:
                    event.add_to_wait_set(wait_set)
                wait_set.add_guard_condition(group.wake.handle)
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
                        (item, handle) for item, handle in zip(inputs, handles)
                        if handle.pointer in ready])
                elif group.name == 'inputs' and not self._stopping.is_set():
                    self._idle()

    def _idle(self):
        with self.lock:
            try:
                self.on_inputs_idle()
            except Exception:   # a defect: report it, keep reading
                self.report_defect('in an input callback')

    def _handle_event(self, event):
        """Run a QoS event's callback (rclpy's default: a warning)."""
        data = event.take_data()
        if data:
            with self.lock:
                try:
                    event.callback(data)
                except Exception:   # a defect: report it, keep reading
                    self.report_defect('in an input QoS event')

    def _dispatch(self, ready):
        """
        Take every message the ready inputs hold; handle them in order.

        Arrival order across inputs (the middleware's reception time): a
        pose, twist and accel published in that order are handled in that
        order even when they wait together. At most the history depth per
        subscription. Each message is checked against its input's byte
        limit and decoded before the lock is taken.
        """
        batch = []
        for item, handle in ready:
            while True:
                taken = handle.take_message(item.subscription.msg_type, True)
                if taken is None:
                    break
                batch.append((taken[1]['received_timestamp'], len(batch),
                              item, taken[0]))
        batch.sort(key=lambda entry: entry[:2])
        # Reception (system clock, ns) to the monotonic clock; never later
        # than now, and now when the middleware gives no reception time.
        monotonic_now = time.monotonic()
        offset = monotonic_now - time.time_ns() * 1e-9
        for received, _, item, data in batch:
            if self._stopping.is_set():
                return
            self.deliver(item.source, data,
                         min(received * 1e-9 + offset, monotonic_now)
                         if received > 0 else monotonic_now)


def _decoded(item, data):
    """Return ``(value, None)`` or ``(None, Rejected)`` for one message."""
    if len(data) > item.max_bytes:
        return None, Rejected('oversize', (
            f'message of {len(data)} bytes on {item.subscription.topic_name}'
            f': the limit is {item.max_bytes} bytes'))
    try:
        return item.decode(data), None
    except Rejected as rejection:
        return None, rejection
    except Exception as error:   # any decoding failure is malformed
        return None, Rejected('malformed', (
            f'unreadable {item.subscription.msg_type.__name__}: '
            f'{clip(error, 200)}'))


def _malformed_parameters(srv_type, request):
    """Return why a set-parameters request is malformed, or None."""
    if srv_type not in (SetParameters, SetParametersAtomically):
        return None
    for parameter in request.parameters:
        if parameter.value.type not in _PARAMETER_TYPES:
            return (f'malformed request: parameter {clip(parameter.name, 100)}'
                    f' has value type {parameter.value.type}, which is not '
                    'a ParameterType; nothing set')
    return None


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
        level=bytes((level,)), message=clip(message),
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

    0 on a normal stop, also when a signal comes during start-up; 2 when
    the node refuses its start-up parameters (ValueError or
    ParameterException, logged as FATAL) or rcl refuses the arguments.
    Ctrl-C and SIGTERM only set a flag (``console.STOP``) that this loop
    reads within SPIN_PERIOD: rclpy's handlers would raise or shut the
    context down inside a callback, breaking off a publish. An exception
    out of the executor once the node runs (a defect of a callback) is
    counted and the node goes on.
    """
    stop = install_signal_handlers()
    if stop:
        return 0
    logger = rclpy.logging.get_logger(name)
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as error:   # rcl refuses the arguments or file
        if stop:
            return 0
        logger.fatal(clip(f'cannot start: {error}'))
        return 2
    node = None
    try:
        try:
            node = node_class()
        except (ValueError, ParameterException) as error:
            if not stop:
                logger.fatal(clip(f'invalid parameters, not starting: '
                                  f'{error}'))
                return 2
            return 0
        executor = _executor()
        executor.add_node(node)
        freeze_start_up_objects()
        # Not executor.spin(): with the EventsExecutor of the rclpy 7.1.6
        # wheels it busy-loops without running callbacks or seeing SIGINT.
        while rclpy.ok() and not stop and not node.finished:
            try:
                executor.spin_once(timeout_sec=SPIN_PERIOD)
            except ExternalShutdownException:
                break
            except Exception:   # a defect of a callback: the node goes on
                node.report_defect('in a callback of the executor')
        node.on_stop(interrupted=bool(stop) or not rclpy.ok())
    except RuntimeError:
        if rclpy.ok() and not stop:
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
