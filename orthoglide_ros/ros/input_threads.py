"""
Inputs and periodic work on threads of their own, from rcl wait sets.

:class:`InputThreads` is the part of :class:`~orthoglide_ros.ros.node_runtime.InputNode`
that reads the node's inputs and runs its periodic work; the executor of
the node serves only its services.

Upstream behaviour it works around:

- rclpy's EventsExecutor queues one event per message received, whatever
  the subscription's history depth: when messages come faster than the
  callbacks run, the queue (and the memory) grows without bound and the
  timers and services wait behind it. A wait set is level triggered: it
  says *that* a subscription holds messages, and the reader takes what the
  middleware kept, at most the history depth
  ([measured](../../doc/measurements.md#reliability)).
- With rmw_fastrtps a reader's QoS events and its data share one status
  condition: a second wait set holding the events (an executor's) masks
  the data out of the input thread's wait, so the events are waited on
  here too (:attr:`InputThreads.waitables`).
- Periodic work on the executor's thread waits behind a service reply that
  rmw_fastrtps holds, GIL held, for a departed client (see
  :mod:`reply_guard`).

How to tell when it can go: when rclpy's executors bound their queue by
the history depth (test_flood.py keeps its memory and latency bounds on
a plain ``create_subscription`` with the default executor), and a
reader's events no longer mask its data (test_node_runtime.py's input
with a second executor spinning the node).

Every input is taken raw: a message longer than its input's byte limit is
refused (``oversize``) before any decoding, the decoding runs outside the
node's lock, and only the core's rule runs under it. Inputs of different
cost are read on different threads (``group``).
"""

from contextlib import ExitStack
import threading
import time
import traceback

from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.serialization import deserialize_message

from orthoglide_ros.formats.text import clip
from orthoglide_ros.cores.inputs import Rejected, SMALL_MESSAGE_BYTES


# Longest wait of an input thread before it looks at its stop flag and the
# context again (a stop also wakes it at once through a guard condition).
INPUT_WAIT = 0.1    # s
# Shortest wait of a periodic thread between two runs (s), however late,
# and of an input thread after a wake-up that found a history full.
MIN_IDLE = 0.0005


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


class InputThreads:
    """
    Inputs and periodic work of a Node, each on a thread of its own.

    Inputs made with :meth:`create_input` are raw subscriptions hidden from
    executors (:attr:`subscriptions` leaves them out) and read by one
    thread per group, started by :meth:`start_threads` and stopped by
    :meth:`stop_threads`. For each message: the byte limit first, then its
    decoder (outside the lock), then its handler with :attr:`lock` held.
    Each wake-up takes every message a ready subscription holds (at most
    its history depth), in arrival order. Work made with
    :meth:`create_periodic` runs on a thread of its own, on a steady
    schedule.

    :attr:`arrival` is, during an input handler, the time the middleware
    received that message on the ``time.monotonic()`` clock: timeouts
    that judge inputs by arrival use it, so a handler run late (a busy
    machine, a batch of messages) does not make its input look late.

    The node provides ``lock``, ``take(source, handle, value,
    rejection)`` (the one place an input's outcome is handled) and
    ``report_defect``; it calls :meth:`_init_threads` first.
    """

    def _init_threads(self):
        self._groups = {}
        self._sources = {}
        self._hidden = set()
        self._hidden_events = set()
        self._periodic = []
        self._stopping = threading.Event()
        self.arrival = None

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

    def read_input(self, msg_type, topic, handle, qos, source, *,
                   decode=None, max_bytes=SMALL_MESSAGE_BYTES,
                   group='inputs', **kwargs):
        """
        Create an input: a raw subscription read by ``group``'s thread.

        ``handle(value)`` runs with :attr:`lock` held on ``decode(bytes)``
        (default: rclpy's deserializer to ``msg_type``), which runs
        outside it. A message over ``max_bytes``, or one ``decode`` cannot
        read, goes to the node's ``take_input`` as a :class:`Rejected`
        (``oversize``, ``malformed``). Other arguments as for
        ``create_subscription``.
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
        """Start the input groups' and periodic threads not started yet."""
        for group in self._groups.values():
            if group.thread is None:
                group.thread = threading.Thread(
                    target=self._read_inputs, args=(group,),
                    name=f'{self.get_name()} {group.name}', daemon=True)
                group.thread.start()
        for thread in self._periodic:
            if thread.ident is None:
                thread.start()

    def deliver(self, source, data, arrival):
        """
        Handle one serialized message of input ``source`` as it came.

        What the input threads do with each message taken: the byte
        limit, the decoder (outside :attr:`lock`), then the node's
        ``take_input`` with :attr:`lock` held and :attr:`arrival` set to
        ``arrival`` (monotonic s).
        """
        item = self._sources[source]
        value, rejection = _decoded(item, data)
        with self.lock:
            self.arrival = arrival
            self.take_input(item.source, item.handle, value, rejection)

    def create_periodic(self, period, work, name):
        """
        Run ``work()`` every ``period()`` s on a thread of its own.

        ``period`` is a function, read before each wait, so a parameter
        can change the rate. The schedule is steady (the next run is due
        one period after the last one was due); runs that are more than
        one period late are dropped, not made up, and a run late anyway
        waits MIN_IDLE first, so work that cannot keep up (the simulator
        at 10 kHz) still leaves the inputs their turn. ``work`` takes
        :attr:`lock` itself when it needs it; what it raises goes to the
        node's ``take_input`` as the outcome of input ``name`` (a
        :class:`Rejected` is warned about, anything else is a defect), and
        the next period runs anyway.
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
                self.take_input(name, lambda _: work(), None, None)
        thread = threading.Thread(target=loop,
                                  name=f'{self.get_name()} {name}',
                                  daemon=True)
        self._periodic.append(thread)
        return thread

    def stop_threads(self):
        """Stop the input and periodic threads (before destroying)."""
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

    def release_threads(self):
        """
        Stop every thread and destroy the inputs; new ones can be made.

        What a lifecycle cleanup does (:mod:`lifecycle`); the input
        subscriptions go with their threads.
        """
        self.stop_threads()
        for group in self._groups.values():
            for item in group.inputs:
                self.destroy_subscription(item.subscription)
        self._init_threads()

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
                if ready and self._dispatch([
                        (item, handle) for item, handle in zip(inputs, handles)
                        if handle.pointer in ready]):
                    # A flood (or a stall): its CPU is bounded, and the
                    # node's other threads of the same real-time priority
                    # (services, ticks), which a SCHED_FIFO thread that
                    # never blocks would keep off its CPU, get their turn.
                    self._stopping.wait(MIN_IDLE)
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
        limit and decoded before the lock is taken. Returns whether a
        subscription held its whole history depth (it may have dropped
        messages: a flood, or a stall of this thread).
        """
        batch, full = [], False
        for item, handle in ready:
            taken_here = 0
            while True:
                taken = handle.take_message(item.subscription.msg_type, True)
                if taken is None:
                    break
                taken_here += 1
                batch.append((taken[1]['received_timestamp'], len(batch),
                              item, taken[0]))
            depth = item.subscription.qos_profile.depth     # 0: keep-all
            full |= 0 < depth <= taken_here
        batch.sort(key=lambda entry: entry[:2])
        # Reception (system clock, ns) to the monotonic clock; never later
        # than now, and now when the middleware gives no reception time.
        monotonic_now = time.monotonic()
        offset = monotonic_now - time.time_ns() * 1e-9
        for received, _, item, data in batch:
            if self._stopping.is_set():
                return full
            self.deliver(item.source, data,
                         min(received * 1e-9 + offset, monotonic_now)
                         if received > 0 else monotonic_now)
        return full


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
