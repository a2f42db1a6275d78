"""
Inputs and periodic work on threads of their own, from rcl wait sets.

:class:`InputThreads`, owned by a node
(:class:`~orthoglide_ros.ros.managed_node.ManagedNode`), reads the node's
inputs, the rows of its input table (:class:`Input`), and runs its
periodic work; the executor of the node serves only its services.

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
node's lock (:func:`fallback_decoder`: the fast reader of
:mod:`orthoglide_ros.formats.cdr`, rclpy for another encoding), and only
the core's rule runs under it. Inputs of different cost are read on
different threads (``group``).
"""

from collections import namedtuple
from contextlib import ExitStack
import functools
import threading
import time

from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.serialization import deserialize_message, serialize_message

from orthoglide_ros.cores.inputs import Rejected, SMALL_MESSAGE_BYTES
from orthoglide_ros.formats import cdr
from orthoglide_ros.formats.text import clip


# Longest wait of an input thread before it looks at its stop flag and the
# context again (a stop also wakes it at once through a guard condition).
INPUT_WAIT = 0.1    # s
# Shortest wait of a periodic thread between two runs (s), however late,
# and of an input thread after a wake-up that found a history full.
MIN_IDLE = 0.0005
# Longest message of another encoding than little-endian CDR that is read.
FALLBACK_BYTES = SMALL_MESSAGE_BYTES
# The encapsulation of the CDR the fast reader reads (the buffer's first
# two bytes): a buffer of it that the reader refuses is malformed.
LITTLE_ENDIAN_CDR = b'\x00\x01'

Input = namedtuple('Input', 'topic type decode method max_bytes source group '
                            'output qos', defaults=(
                                SMALL_MESSAGE_BYTES, None, 'inputs', None,
                                None))
Input.__doc__ = """One row of a node's input table.

``topic`` and ``type`` (the message class) of the subscription;
``decode(bytes)`` returns the message's fields as a tuple, outside the lock
(None: rclpy's deserializer, the message as a 1-tuple);
``method(*fields, arrival)`` is the core's, run with the node's lock held,
and returns what to publish or None; ``output(result)`` publishes it (None:
the input publishes nothing). ``max_bytes``: the byte limit; ``source``:
the input's name in the core's counters (default the topic); ``group``:
the thread that reads it; ``qos``: its profile (default the package's,
with the standard QoS overrides)."""


def fallback_decoder(decode, kind):
    """
    Return ``decode`` that falls back to rclpy for a foreign encoding.

    A buffer that the fast reader refuses (:class:`cdr.CdrError`: not the
    little-endian CDR it knows) is decoded by rclpy and written again in
    the local encoding, if it is at most FALLBACK_BYTES long (rclpy's
    conversion costs ~10 us per kB); a longer one, one in little-endian
    CDR (the reader's own: broken) and one rclpy cannot read either are
    refused (``malformed``). ROS 2 writes little-endian CDR on every
    little-endian host, so the fallback only serves foreign writers.
    """
    def decoded(data):
        try:
            return decode(data)
        except cdr.CdrError as error:
            if data[:2] == LITTLE_ENDIAN_CDR:     # its own encoding: broken
                raise Rejected('malformed', f'{kind.__name__}: {error}') \
                    from None
            if len(data) > FALLBACK_BYTES:
                raise Rejected('malformed', (
                    f'{kind.__name__} of {len(data)} bytes that the fast '
                    f'reader cannot read ({error}): other encodings are '
                    f'read up to {FALLBACK_BYTES} bytes')) from None
            try:
                message = deserialize_message(data, kind)
            except Exception as refused:    # rclpy's RMWError: not a message
                raise Rejected('malformed', (
                    f'{kind.__name__} that neither the fast reader ({error}) '
                    f'nor rclpy ({_first_line(refused)}) can read')) from None
            return decode(serialize_message(message))
    return decoded


def _first_line(error):
    return str(error).strip().split('\n')[0]


class _Reader:
    """One input: its row, its raw subscription, its decoder."""

    def __init__(self, row, subscription):
        self.row = row
        self.subscription = subscription
        kind = row.type
        self.decode = fallback_decoder(row.decode, kind) if row.decode \
            else (lambda data: (deserialize_message(data, kind),))


class _Thread:
    """A thread of the node's, made at start, with a stop flag of its own."""

    def __init__(self, name, target, lasting=False):
        self.name = name
        self.target = target
        self.lasting = lasting
        self.stop = threading.Event()
        self.thread = None

    def start(self):
        """Start the thread unless it runs already."""
        if self.thread is None:
            self.thread = threading.Thread(target=self.target,
                                           name=self.name, daemon=True)
            self.thread.start()


class _Group(_Thread):
    """Inputs read by one thread from one wait set."""

    def __init__(self, key, name, context):
        super().__init__(name, None)
        self.key = key
        self.readers = []
        self.events = []
        self.pending = []   # taken, not handled when a stop came
        self.wake = GuardCondition(None, None, context=context)


class InputThreads:
    """
    Inputs and periodic work of a node, each on a thread of its own.

    Inputs added with :meth:`add` are raw subscriptions hidden from
    executors (:meth:`hides`) and read by one thread per group. For each
    message: the byte limit first, then its decoder (outside the lock),
    then the node's ``take(row, fields, arrival, rejection)`` with the
    node's ``lock`` held, ``arrival`` the time the middleware received
    the message on the ``time.monotonic()`` clock (timeouts that judge
    inputs by arrival use it, so a handler run late does not make its
    input look late). Each wake-up takes every message a ready
    subscription holds (at most its history depth), in arrival order.
    Work added with :meth:`periodic` runs on a thread of its own, on a
    steady schedule. :meth:`start` starts what is not started yet;
    :meth:`release` ends the inputs and the work added at configure,
    :meth:`stop` everything.
    """

    def __init__(self, node):
        self._node = node
        self._groups = {}
        self._readers = {}
        self._periodic = []
        self._hidden = set()

    def hides(self, entity):
        """
        Say whether an executor must leave ``entity`` to these threads.

        The input subscriptions, and their QoS event handlers (incompatible
        QoS or type warnings): with rmw_fastrtps, a reader's events and its
        data share one status condition, and a second wait set holding its
        events (an executor's) masks the data out of the input thread's
        wait (measured: inputs delayed by 100 ms and more while a
        SingleThreadedExecutor spun the node).
        """
        return entity in self._hidden

    def add(self, row, qos, **kwargs):
        """Subscribe to one :class:`Input` row with ``qos``; return it."""
        node = self._node
        if row.source is None:
            row = row._replace(source=row.topic)
        subscription = node.create_subscription(
            row.type, row.topic, lambda data: None, qos, raw=True, **kwargs)
        group = self._groups.get(row.group)
        if group is None:
            group = self._groups[row.group] = _Group(
                row.group, f'{node.get_name()} {row.group}', node.context)
            group.target = functools.partial(self._read_inputs, group)
        reader = _Reader(row, subscription)
        group.readers.append(reader)
        self._readers[row.source] = reader
        group.events.extend(subscription.event_handlers)
        self._hidden.add(subscription)
        self._hidden.update(subscription.event_handlers)
        return subscription

    def deliver(self, source, data, arrival):
        """
        Handle one serialized message of input ``source`` as it came.

        What the input threads do with each message taken: the byte
        limit, the decoder (outside the lock), then the node's ``take``
        with its lock held and ``arrival`` (monotonic s).
        """
        reader = self._readers[source]
        fields, rejection = _decoded(reader, data)
        with self._node.lock:
            self._node.take(reader.row, fields, arrival, rejection)

    def drain(self):
        """
        Handle every message the inputs still hold, once :meth:`stop` ran.

        What the threads had taken but not handled when the stop came,
        then what waits in the subscriptions' histories, in arrival order:
        for a node that must lose nothing it received (the recorder).
        """
        for group in self._groups.values():
            pending, group.pending = group.pending, []
            ready = [(r, r.subscription.handle) for r in group.readers]
            with ExitStack() as stack:
                for _, handle in ready:
                    stack.enter_context(handle)
                self._deliver_all(pending + self._take(ready)[0])

    def periodic(self, period, work, name, lasting=False):
        """
        Run ``work()`` every ``period()`` s on a thread of its own.

        ``period`` is a function, read before each wait, so a parameter
        can change the rate. The schedule is steady (the next run is due
        one period after the last one was due); runs that are more than
        one period late are dropped, not made up, and a run late anyway
        waits MIN_IDLE first, so work that cannot keep up (the simulator
        at 10 kHz) still leaves the inputs their turn. ``work`` takes the
        lock itself when it needs it; what it raises goes to the node's
        ``outcome`` as that of ``name`` (a :class:`Rejected` is warned
        about, anything else is a defect), and the next period runs
        anyway. ``lasting``: kept by :meth:`release` (the diagnostics).
        """
        node = self._node

        def loop():
            due = time.monotonic()
            while not entry.stop.is_set() and node.context.ok():
                step = period()
                due += step
                delay = due - time.monotonic()
                if delay < -step:
                    due = time.monotonic()
                # Even when late: the other threads get the GIL and the
                # lock in between (Python's lock is not fair to a waiter).
                if entry.stop.wait(max(delay, MIN_IDLE)):
                    return
                node.outcome(name, work)
        entry = _Thread(f'{node.get_name()} {name}', loop, lasting)
        self._periodic.append(entry)

    def start(self):
        """Start the input groups' and periodic threads not started yet."""
        for entry in (*self._groups.values(), *self._periodic):
            entry.start()

    def stop(self):
        """Stop every input and periodic thread (before destroying)."""
        self._end([*self._groups.values(), *self._periodic])

    def release(self):
        """
        Stop the inputs and the work that is not lasting; destroy the inputs.

        What a lifecycle cleanup does; new ones can be added.
        """
        self._end([*self._groups.values(),
                   *(p for p in self._periodic if not p.lasting)])
        for group in self._groups.values():
            for reader in group.readers:
                self._node.destroy_subscription(reader.subscription)
        self._groups, self._readers, self._hidden = {}, {}, set()
        self._periodic = [p for p in self._periodic if p.lasting]

    @staticmethod
    def _end(entries):
        # Once per entry: stop() before destroy_node() may follow on_stop's.
        entries = [entry for entry in entries if not entry.stop.is_set()]
        for entry in entries:
            entry.stop.set()
            if isinstance(entry, _Group):
                entry.wake.trigger()
        for entry in entries:
            if entry.thread is not None:
                entry.thread.join()
            if isinstance(entry, _Group):
                entry.wake.destroy()

    def _read_inputs(self, group):
        try:
            self._wait_and_take(group)
        except Exception:   # a defect: no input is read any more
            self._node.log_exception('fatal', f'input thread {group.name} '
                                     'stopped by an error')

    def _wait_and_take(self, group):
        context = self._node.context
        readers = group.readers
        handles = [r.subscription.handle for r in readers]
        events = group.events
        with ExitStack() as stack:
            # Held for the thread's life: the handles stay valid meanwhile.
            for handle in (*handles, *events, group.wake.handle,
                           context.handle):
                stack.enter_context(handle)
            wait_set = _rclpy.WaitSet(len(handles), 1, 0, 0, 0, len(events),
                                      context.handle)
            timeout = int(INPUT_WAIT * 1e9)
            while not group.stop.is_set() and context.ok():
                wait_set.clear_entities()
                for handle in handles:
                    wait_set.add_subscription(handle)
                for event in events:
                    event.add_to_wait_set(wait_set)
                wait_set.add_guard_condition(group.wake.handle)
                try:
                    wait_set.wait(timeout)
                except Exception:   # the context shut down meanwhile
                    if context.ok():
                        raise
                    return
                for event in events:
                    if event.is_ready(wait_set):
                        self._handle_event(event)
                ready = wait_set.get_ready_entities('subscription')
                if ready and self._dispatch(group, [
                        (r, h) for r, h in zip(readers, handles)
                        if h.pointer in ready]):
                    # A flood (or a stall): its CPU is bounded, and the
                    # node's other threads of the same real-time priority
                    # (services, ticks), which a SCHED_FIFO thread that
                    # never blocks would keep off its CPU, get their turn.
                    group.stop.wait(MIN_IDLE)
                elif group.key == 'inputs' and not group.stop.is_set():
                    with self._node.lock:
                        self._node.outcome('inputs idle',
                                           self._node.inputs_idle)

    def _handle_event(self, event):
        """Run a QoS event's callback (rclpy's default: a warning)."""
        data = event.take_data()
        if data:
            with self._node.lock:
                self._node.outcome('input QoS event',
                                   lambda: event.callback(data))

    def _dispatch(self, group, ready):
        """
        Take every message the ready inputs hold; handle them in order.

        Arrival order across inputs (the middleware's reception time): a
        pose, twist and accel published in that order are handled in that
        order even when they wait together. At most the history depth per
        subscription. Each message is checked against its input's byte
        limit and decoded before the lock is taken. Returns whether a
        subscription held its whole history depth (it may have dropped
        messages: a flood, or a stall of this thread). A stop keeps what
        is not handled yet for :meth:`drain`.
        """
        batch, full = self._take(ready)
        group.pending = self._deliver_all(batch, group.stop)
        return full

    @staticmethod
    def _take(ready):
        """
        Take every message the ``(reader, handle)`` pairs hold.

        Returns them in arrival order, and whether a subscription held its
        whole history depth.
        """
        batch, full = [], False
        for reader, handle in ready:
            taken_here = 0
            subscription = reader.subscription
            while True:
                taken = handle.take_message(subscription.msg_type, True)
                if taken is None:
                    break
                taken_here += 1
                batch.append((taken[1]['received_timestamp'], len(batch),
                              reader, taken[0]))
            depth = subscription.qos_profile.depth     # 0: keep-all
            full |= 0 < depth <= taken_here
        batch.sort(key=lambda entry: entry[:2])
        return batch, full

    def _deliver_all(self, batch, stop=None):
        """Deliver a taken ``batch``; return what a set ``stop`` left."""
        # Reception (system clock, ns) to the monotonic clock; never later
        # than now, and now when the middleware gives no reception time.
        monotonic_now = time.monotonic()
        offset = monotonic_now - time.time_ns() * 1e-9
        for index, (received, _, reader, data) in enumerate(batch):
            if stop is not None and stop.is_set():
                return batch[index:]
            self.deliver(reader.row.source, data,
                         min(received * 1e-9 + offset, monotonic_now)
                         if received > 0 else monotonic_now)
        return []


def _decoded(reader, data):
    """Return ``(fields, None)`` or ``(None, Rejected)`` for one message."""
    if len(data) > reader.row.max_bytes:
        return None, Rejected('oversize', (
            f'message of {len(data)} bytes on {reader.row.topic}: the limit '
            f'is {reader.row.max_bytes} bytes'))
    try:
        return reader.decode(data), None
    except Rejected as rejection:
        return None, rejection
    except Exception as error:   # any decoding failure is malformed
        return None, Rejected('malformed', (
            f'unreadable {reader.row.type.__name__}: {clip(error, 200)}'))
