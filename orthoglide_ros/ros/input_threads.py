"""
A node's inputs and periodic work, on threads of their own.

:class:`InputThreads`, owned by every node, reads the inputs subscribed
with :meth:`InputThreads.subscribe` from rcl wait sets and runs the work
added with :meth:`InputThreads.periodic`; the executor serves only the
services. Why and the rules: doc/decisions.md#runtime-and-middleware,
doc/robustness.md#inputs. Each upstream behaviour worked around can go
when its check in ``benchmarks/upstream_checks.py`` says so:

- EventsExecutor's unbounded queue: when an executor is bounded and within
  1.3x of the wait-set thread's CPU per message (``executor_queue``);
- rmw_fastrtps's QoS events masking the data (:meth:`InputThreads.hides`):
  when a wait-set executor spinning the node no longer delays the inputs
  (``events_mask``);
- timers behind a flood of requests: when a timer on the EventsExecutor
  keeps within 3 periods under one (``timer_behind_services``).
"""

from contextlib import ExitStack
from copy import copy
import threading
import time

from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.serialization import deserialize_message

from orthoglide_ros.cores.inputs import Rejected, SMALL_MESSAGE_BYTES
from orthoglide_ros.formats.text import clip

# Longest wait of an input thread before it looks at its stop flag and the
# context again (a stop also wakes it at once through a guard condition).
INPUT_WAIT = 0.1    # s
# Shortest wait of a periodic thread between two runs (s), however late,
# and of an input thread after a wake-up that found a history full.
MIN_IDLE = 0.0005

# Reliable, keep-last 10 on every input and output; users override it with
# the standard qos_overrides.<topic>.<publisher|subscription>.* parameters.
_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                  reliability=ReliabilityPolicy.RELIABLE)


def default_qos():
    """
    Return a new reliable keep-last 10 profile.

    A new one per entity: rclpy writes the QoS overrides into the profile
    it is given, so a shared one would leak them between entities (still
    so in rclpy 7.1.6: ``benchmarks/upstream_checks.py``, ``qos_profile``).
    """
    return copy(_QOS)


def rclpy_decoder(msg_type):
    """Return a decoder that gives rclpy's message as the one field."""
    return lambda data: (deserialize_message(data, msg_type),)


class _Input:
    """One input: its subscription and where each message goes."""

    __slots__ = ('topic', 'type', 'decode', 'core_method', 'publish',
                 'max_bytes', 'source', 'subscription', 'handle', 'depth')

    def __init__(self, topic, msg_type, decode, core_method, publish,
                 max_bytes, source):
        self.topic, self.type, self.decode = topic, msg_type, decode
        self.core_method, self.publish = core_method, publish
        self.max_bytes, self.source = max_bytes, source


class _NodeThread:
    """A thread of the node's, made at start, with a stop flag of its own."""

    def __init__(self, name, target, keep_on_cleanup=False):
        self.name = name
        self.target = target
        self.keep_on_cleanup = keep_on_cleanup
        self.stop = threading.Event()
        self.thread = None

    def start(self):
        """Start the thread unless it runs already."""
        if self.thread is None:
            self.thread = threading.Thread(target=self.target,
                                           name=self.name, daemon=True)
            self.thread.start()


class _InputThread(_NodeThread):
    """Inputs read by one thread from one wait set."""

    def __init__(self, key, name, context):
        super().__init__(name, None)
        self.key = key
        self.inputs = []
        self.events = []
        self.pending = []   # taken, not handled when a stop came
        self.wake = GuardCondition(None, None, context=context)


class InputThreads:
    """
    Inputs and periodic work of a node, each on a thread of its own.

    :meth:`subscribe` declares one input, :meth:`periodic` one periodic
    work; :meth:`start` starts what is not started yet; :meth:`release`
    ends the inputs and the work added at configure, :meth:`stop`
    everything, and :meth:`drain` then handles what the inputs still hold.
    """

    def __init__(self, node):
        self._node = node
        self._threads = {}
        self._periodic = []
        self._hidden = set()
        self.sources = {}       # source name: its input

    def subscribe(self, topic, msg_type, decode, core_method, publish=None,
                  *, source=None, max_bytes=SMALL_MESSAGE_BYTES,
                  thread='inputs', qos=None):
        """
        Subscribe to ``topic``: messages to ``core_method``, results out.

        ``decode(bytes)`` returns the message's fields as a tuple (a
        reader of :mod:`orthoglide_ros.formats.cdr`, or
        :func:`rclpy_decoder`), run outside the node's lock;
        ``core_method(*fields, arrival)`` returns what ``publish`` takes,
        or None (``publish`` None: nothing to publish). ``source``: the
        input's name in the core's counters (default the topic);
        ``max_bytes``: the byte limit; ``thread``: the input thread that
        reads it; ``qos``: its profile (default :func:`default_qos` with
        the standard QoS overrides).
        """
        node = self._node
        entry = _Input(topic, msg_type, decode, core_method, publish,
                       max_bytes, source or topic)
        entry.subscription = node.create_subscription(
            msg_type, topic, lambda data: None, qos or default_qos(),
            raw=True, qos_overriding_options=None if qos else
            QoSOverridingOptions.with_default_policies())
        entry.handle = entry.subscription.handle
        entry.depth = entry.subscription.qos_profile.depth  # 0: keep-all
        group = self._threads.get(thread)
        if group is None:
            group = self._threads[thread] = _InputThread(
                thread, f'{node.get_name()} {thread}', node.context)
            group.target = lambda: self._serve(group)
        group.inputs.append(entry)
        group.events.extend(entry.subscription.event_handlers)
        self.sources[entry.source] = entry
        self._hidden.add(entry.subscription)
        self._hidden.update(entry.subscription.event_handlers)

    def hides(self, entity):
        """
        Say whether an executor must leave ``entity`` to these threads.

        The input subscriptions and their QoS event handlers: waited on
        here, so that an executor's wait set does not mask their data
        (see the module docstring).
        """
        return entity in self._hidden

    def deliver(self, entry, data, arrival):
        """
        Handle one serialized message of input ``entry`` as it came.

        The byte limit, then the decoder, outside the lock; with the
        node's lock held, the core's method with the fields and
        ``arrival`` (monotonic s), and its result to the publisher. A
        message refused (``oversize``, ``malformed``, or a
        :class:`Rejected` of the core's, which counts it) becomes a
        warning, at most one a second per input and reason; any other
        exception is a defect: nothing is published, the node goes on.
        """
        if len(data) > entry.max_bytes:
            refused = Rejected('oversize', (
                f'message of {len(data)} bytes on {entry.topic}: the limit '
                f'is {entry.max_bytes} bytes'))
        else:
            try:
                fields, refused = entry.decode(data), None
            except Rejected as rejection:
                refused = rejection
            except Exception as error:   # any decoding failure: malformed
                refused = Rejected('malformed', (
                    f'unreadable {entry.type.__name__}: {clip(error, 200)}'))
        node = self._node
        with node.lock:
            try:
                if refused is None:
                    result = entry.core_method(*fields, arrival)
                    if result is not None:
                        entry.publish(result)
                    return
                node.core.reject(entry.source, refused)
            except Rejected as rejection:   # counted by the core
                refused = rejection
            except Exception:   # a defect: nothing published, the node goes on
                node.report_defect(f'on {entry.source}, nothing published')
                return
        node.warn_throttled((entry.source, refused.reason),
                            f'{entry.source} rejected ({refused.reason}): '
                            f'{refused}')

    def drain(self):
        """
        Handle every message the inputs still hold, once :meth:`stop` ran.

        What the threads had taken but not handled when the stop came,
        then what waits in the subscriptions' histories, in arrival order:
        for a node that must lose nothing it received (the recorder).
        """
        for group in self._threads.values():
            self._serve(group, draining=True)

    def periodic(self, period, work, name, keep_on_cleanup=False):
        """
        Run ``work()`` every ``period()`` s on a thread of its own.

        ``period`` is a function, read before each wait, so a parameter
        can change the rate. The schedule is steady (the next run is due
        one period after the last one was due); runs that are more than
        one period late are dropped, not made up, and a run late anyway
        waits MIN_IDLE first, so work that cannot keep up (the simulator
        at 10 kHz) still leaves the inputs their turn. ``work`` takes the
        lock itself when it needs it; a :class:`Rejected` it raises is
        warned about, anything else is a defect, and the next period runs
        anyway. ``keep_on_cleanup``: kept by :meth:`release` (the
        diagnostics).
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
                try:
                    work()
                except Rejected as refused:
                    node.warn_throttled((name, refused.reason),
                                        f'{name} rejected ({refused.reason})'
                                        f': {refused}')
                except Exception:   # a defect: report it, keep running
                    node.report_defect(f'in {name}')
        entry = _NodeThread(f'{node.get_name()} {name}', loop,
                            keep_on_cleanup)
        self._periodic.append(entry)

    def start(self):
        """Start the input and periodic threads not started yet."""
        for entry in (*self._threads.values(), *self._periodic):
            entry.start()

    def stop(self):
        """Stop every input and periodic thread (before destroying)."""
        self._end([*self._threads.values(), *self._periodic])

    def release(self):
        """
        Stop the inputs and the work not kept on cleanup; destroy the inputs.

        What a lifecycle cleanup does; new ones can be added.
        """
        self._end([*self._threads.values(),
                   *(p for p in self._periodic if not p.keep_on_cleanup)])
        for entry in self.sources.values():
            self._node.destroy_subscription(entry.subscription)
        self._threads, self.sources, self._hidden = {}, {}, set()
        self._periodic = [p for p in self._periodic if p.keep_on_cleanup]

    @staticmethod
    def _end(entries):
        # Once per entry: stop() before destroy_node() may follow on_stop's.
        entries = [entry for entry in entries if not entry.stop.is_set()]
        for entry in entries:
            entry.stop.set()
            if isinstance(entry, _InputThread):
                entry.wake.trigger()
        for entry in entries:
            if entry.thread is not None:
                entry.thread.join()
            if isinstance(entry, _InputThread):
                entry.wake.destroy()

    def _serve(self, group, draining=False):
        """
        Read the inputs of one input thread (``group``) until its stop.

        Each wake-up takes every message a ready input holds (at most its
        history depth), orders them by reception time across the inputs
        and delivers them (:meth:`deliver`) with their reception time on
        the ``time.monotonic()`` clock as ``arrival``. After a wake-up
        that found a history full (a flood or a stall), a MIN_IDLE pause:
        the node's other threads of the same real-time priority get their
        turn. A stop keeps what is taken, not handled; ``draining``: one
        pass over every input after the stop, that included.
        """
        context = self._node.context
        handles = [entry.handle for entry in group.inputs]
        waited = () if draining else (*group.events, group.wake.handle)
        try:
            with ExitStack() as stack:
                # Held meanwhile: the handles stay valid.
                for handle in (*handles, *waited, context.handle):
                    stack.enter_context(handle)
                wait_set = None if draining else _rclpy.WaitSet(
                    len(handles), 1, 0, 0, 0, len(group.events),
                    context.handle)
                while draining or (not group.stop.is_set()
                                   and context.ok()):
                    if draining:
                        ready = group.inputs
                    elif not self._wait(group, wait_set):
                        return      # the context shut down meanwhile
                    else:
                        pointers = wait_set.get_ready_entities('subscription')
                        ready = [entry for entry in group.inputs
                                 if entry.handle.pointer in pointers]
                    batch, full = group.pending, False
                    group.pending = []
                    for entry in ready:
                        taken_here = 0
                        while (taken := entry.handle.take_message(
                                entry.type, True)) is not None:
                            taken_here += 1
                            batch.append((taken[1]['received_timestamp'],
                                          len(batch), entry, taken[0]))
                        full |= 0 < entry.depth <= taken_here
                    batch.sort(key=lambda item: item[:2])
                    # Reception (system clock, ns) to the monotonic clock;
                    # never later than now, now without a reception time.
                    now = time.monotonic()
                    offset = now - time.time_ns() * 1e-9
                    for index, (received, _, entry, data) in enumerate(batch):
                        if group.stop.is_set() and not draining:
                            group.pending = batch[index:]
                            break
                        self.deliver(entry, data, min(
                            received * 1e-9 + offset, now)
                            if received > 0 else now)
                    if draining:
                        return
                    if full:
                        group.stop.wait(MIN_IDLE)
                    else:
                        self._idle(group)
        except Exception:   # a defect: no input is read any more
            self._node.log_exception('fatal', f'input thread {group.name} '
                                     'stopped by an error')

    def _wait(self, group, wait_set):
        """Wait on the inputs, their QoS events and the wake-up; run events."""
        context = self._node.context
        wait_set.clear_entities()
        for entry in group.inputs:
            wait_set.add_subscription(entry.handle)
        for event in group.events:
            event.add_to_wait_set(wait_set)
        wait_set.add_guard_condition(group.wake.handle)
        try:
            wait_set.wait(int(INPUT_WAIT * 1e9))
        except Exception:   # the context shut down meanwhile
            if context.ok():
                raise
            return False
        for event in group.events:
            data = event.take_data() if event.is_ready(wait_set) else None
            if data:    # rclpy's default callback: a warning
                with self._node.lock:
                    try:
                        event.callback(data)
                    except Exception:   # a defect: report it, go on
                        self._node.report_defect('in an input QoS event')
        return True

    def _idle(self, group):
        """Run ``inputs_idle`` (lock held) after a wake-up of ``inputs``."""
        node = self._node
        if group.key == 'inputs' and not group.stop.is_set():
            with node.lock:
                try:
                    node.inputs_idle()
                except Exception:   # a defect: report it, go on
                    node.report_defect('in inputs idle')
