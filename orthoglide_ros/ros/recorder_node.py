"""
The recorder behind ``orthoglide record``: topics into a rosbag2 bag.

Each message's bytes go unchanged, through a queue, to the thread that
owns the bag (:class:`BagThread`: sqlite3 refuses a connection used from
another thread, and the input thread never waits for the disk)
(doc/cli.md#record).
"""

import functools
import importlib
import queue
import threading
import time

from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from orthoglide_ros.cores.inputs import RECORD_MESSAGE_BYTES
from orthoglide_ros.cores.parameters import Table
from orthoglide_ros.cores.recording import LOSSY, Recording
from orthoglide_ros.ros import console
from orthoglide_ros.ros.managed_node import ManagedNode
from orthoglide_ros.ros.node_runtime import run

# History of each subscription: the messages that may wait for the writer.
RECORD_DEPTH = 1000
BAG_VERSION = 9
GRAPH_POLL = 0.05   # s between two looks at the graph while waiting


class BagThread(threading.Thread):
    """
    The thread that owns the bag: opens it, writes the queue, closes it.

    :attr:`queue` takes ``(connection index, stamp ns, bytes)`` and None
    to close. :attr:`ready` is set once the bag is open (or could not be:
    :attr:`error`); a write the writer refuses goes to
    ``failed(index, error)``.
    """

    def __init__(self, output, storage, topics, typestore, failed):
        """Prepare the thread; ``topics``: ``(topic, type)`` pairs."""
        super().__init__(name='orthoglide_record bag', daemon=True)
        self.output = output
        self.storage = storage
        self.topics = topics
        self.typestore = typestore
        self.failed = failed
        self.queue = queue.SimpleQueue()
        self.ready = threading.Event()
        self.error = None

    def run(self):
        """Open the bag, write what comes, close it on None."""
        from rosbags.rosbag2 import StoragePlugin, Writer
        plugin = {'mcap': StoragePlugin.MCAP,
                  'sqlite3': StoragePlugin.SQLITE3}[self.storage]
        try:
            writer = Writer(self.output, version=BAG_VERSION,
                            storage_plugin=plugin)
            writer.open()
            connections = [writer.add_connection(t, kind,
                                                 typestore=self.typestore)
                           for t, kind in self.topics]
        except Exception as error:  # rosbags' WriterError: exists, etc.
            self.error = error
            self.ready.set()
            return
        self.ready.set()
        while True:
            item = self.queue.get()
            if item is None:
                break
            index, stamp, data = item
            try:
                writer.write(connections[index], stamp, data)
            except Exception as error:  # the disk, the writer: counted
                self.failed(index, error)
        writer.close()


class Recorder(ManagedNode):
    """Node ``orthoglide_record``: writes ``topics`` into the bag ``output``."""

    NAME = 'orthoglide_record'
    TITLE = 'orthoglide record'
    PARAMETERS = Table('RecorderSettings', ())

    def __init__(self, output, topics, storage='mcap', duration=None,
                 wait=10.0, **kwargs):
        self._request = (output, topics, storage, wait)
        self._bag = None
        self._recording = None  # the core, kept after a cleanup drops it
        self._duration = duration
        self._end = None        # set once recording: the wait is not in it
        super().__init__(**kwargs)

    def build(self, settings):
        """Configure: find the topics' types, open the bag, the inputs."""
        from rosbags.typesys import get_typestore, Stores
        output, topics, storage, wait = self._request
        typestore = get_typestore(Stores.ROS2_JAZZY)
        found = self._topic_types(topics, wait)
        for topic, type_name in found.items():
            if type_name not in typestore.types:
                raise ValueError(f'{topic}: type {type_name!r} is not in '
                                 'the ROS 2 Jazzy type store of rosbags')
        bag = BagThread(output, storage, list(found.items()), typestore,
                        self._write_failed)
        bag.start()
        bag.ready.wait()
        if bag.error is not None:
            raise ValueError(f'cannot write the bag {output}: {bag.error}')
        self._bag = bag
        self._index = {topic: i for i, topic in enumerate(found)}
        self.core = self._recording = Recording(found, time.monotonic())
        if self._duration is not None:
            self._end = time.monotonic() + self._duration
        self.log('info', (
            f'recording {", ".join(f"{t} ({n})" for t, n in found.items())}'
            f' into {output} ({storage})'))
        for topic, type_name in found.items():
            # The publishers' QoS, not the package's.
            self.inputs.subscribe(
                topic, _message_class(type_name), _raw,
                functools.partial(self.core.message, topic), self._write,
                max_bytes=RECORD_MESSAGE_BYTES, qos=self._qos(topic))

    def _topic_types(self, topics, wait):
        """Return ``{resolved topic: type}`` once each has a publisher."""
        names = [self.resolve_topic_name(t) for t in topics]
        deadline = time.monotonic() + wait
        while True:
            graph = dict(self.get_topic_names_and_types())
            published = {n: graph[n] for n in names
                         if n in graph and self.count_publishers(n)}
            if len(published) == len(names):
                break
            if console.STOP or time.monotonic() > deadline:
                missing = [n for n in names if n not in published]
                raise ValueError(f'no publisher of {", ".join(missing)} '
                                 f'after {wait:g} s')
            time.sleep(GRAPH_POLL)
        for name, types in published.items():
            if len(types) != 1:
                raise ValueError(f'{name} has several types: {types}')
        return {name: published[name][0] for name in names}

    def _qos(self, topic):
        """Reliable keep-last RECORD_DEPTH, best effort if a publisher is."""
        best_effort = any(
            info.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
            for info in self.get_publishers_info_by_topic(topic))
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=RECORD_DEPTH,
            reliability=ReliabilityPolicy.BEST_EFFORT if best_effort
            else ReliabilityPolicy.RELIABLE)

    def _write(self, item):
        """Queue one message for the bag (runs with the lock held)."""
        topic, data = item
        self._bag.queue.put((self._index[topic],
                             self.get_clock().now().nanoseconds, data))

    def _write_failed(self, index, error):
        """Count a message the bag's writer refused (the bag's thread)."""
        topic = self._recording.INPUTS[index]
        with self.lock:
            self._recording.write_failed(topic, error)
        self.warn_throttled(('bag', 'write_failed'),
                            f'{topic}: the bag\'s writer refused a message: '
                            f'{error}')

    @property
    def lossy(self):
        """Whether a message received was not written into the bag."""
        return self._recording is not None and bool(self._recording.dropped)

    @property
    def finished(self):
        """Whether ``duration`` has passed."""
        return self._end is not None and time.monotonic() >= self._end

    def on_stop(self, interrupted):
        """
        Close the bag (complete, whatever stopped the recording).

        Every message received goes in: those the input thread had not
        handled yet, and those still in the subscriptions' histories. The
        last line says what was written and what was dropped (a warning
        when any was).
        """
        if self._bag is None:
            return
        self.inputs.stop()
        self.inputs.drain()
        self._bag.queue.put(None)
        self._bag.join()
        with self.lock:
            lossy = self.lossy
            summary = self._recording.summary(self._request[0])
        self.log('warning' if lossy else 'info', summary)


def _raw(data):
    """Keep a message's bytes as they came (its one field)."""
    return (data,)


def _message_class(type_name):
    """Return the rclpy message class of ``pkg/msg/Name``."""
    package, kind, name = type_name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def main(output, topics, storage='mcap', duration=None, wait=10.0,
         report=None):
    """
    Record until ``duration`` (s), Ctrl-C or SIGTERM; return the code.

    0, or LOSSY when a message received was dropped (the bag complete all
    the same). A refusal to start (no publisher within ``wait``, a bad
    output) goes to ``report(reason)`` when given (the tool's one-line
    error), else FATAL, and returns 2.
    """
    made = []

    def make():
        made.append(Recorder(output, topics, storage, duration, wait))
        return made[-1]
    code = run(make, 'orthoglide_record', console.install_signal_handlers(),
               args=[], report=report)
    return LOSSY if code == 0 and made and made[-1].lossy else code
