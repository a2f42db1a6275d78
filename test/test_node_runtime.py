"""
The input threads of ``managed_node.ManagedNode``, over real DDS.

Their contract: a core's input method runs with ``arrival``, the time the
middleware received the message (monotonic clock), not the time the
callback happens to run, so a slow callback or a busy machine does not make
the inputs behind it look late (the feedforward pairs pose, twist and
accel within ``pairing_timeout`` of arrival; the simulator and the tracking
controller judge their timeouts by it too). A message is decoded before the
node's lock is taken: a long decoding holds no other thread of the node.
"""

import threading
import time

import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Float64

from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.parameters import Table
from orthoglide_testing.probe import spin_until
from orthoglide_ros.ros.input_threads import rclpy_decoder
from orthoglide_ros.ros.managed_node import default_qos, ManagedNode

pytestmark = pytest.mark.ros  # DDS and node processes

# s spent in each callback: longer than this process is ever descheduled,
# so that the later messages arrive within the first callback.
SLOW = 0.5
WAIT = 10.0     # s: generous, the machine is shared


class Values(Core):
    """A core whose one input takes SLOW seconds per message."""

    INPUTS = ('values',)

    def __init__(self):
        super().__init__(None)
        self.seen = []      # (value, arrival, monotonic time of the call)

    def value(self, msg, now):
        """Record one value with its arrival."""
        self.seen.append((msg.data, now, time.monotonic()))
        time.sleep(SLOW)


class SlowReader(ManagedNode):
    """A node of one input, read with rclpy's deserializer, and slow."""

    NAME = TITLE = 'slow_reader'
    PARAMETERS = Table('SlowReaderSettings', ())

    def build(self, settings):
        """Make the core and its one input."""
        self.core = Values()
        self.inputs.subscribe('values', Float64, self.decode, self.core.value)

    def decode(self, data):
        """Read one message (rclpy's deserializer)."""
        return rclpy_decoder(Float64)(data)


class BlockedDecoder(SlowReader):
    """A node whose decoder waits, once it is called, until released."""

    NAME = TITLE = 'blocked_decoder'

    def __init__(self, **kwargs):
        self.decoding = threading.Event()
        self.release = threading.Event()
        super().__init__(**kwargs)

    def decode(self, data):
        """Say that decoding began; wait until the test releases it."""
        self.decoding.set()
        self.release.wait(WAIT)
        return super().decode(data)


def writer_of(ros_context):
    """Return a writer node, its Float64 publisher on 'values', its executor."""
    writer = Node('writer', context=ros_context)
    publisher = writer.create_publisher(Float64, 'values', default_qos())
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(writer)
    return writer, publisher, executor


def test_arrival_is_reception_time_not_callback_time(ros_context):
    """Three messages sent at once, handled SLOW apart: same arrival."""
    reader = SlowReader(context=ros_context)
    writer, publisher, executor = writer_of(ros_context)
    try:
        assert spin_until(executor, lambda: publisher.get_subscription_count()
                          == 1, 10.0)
        sent = time.monotonic()
        for value in (1.0, 2.0, 3.0):
            publisher.publish(Float64(data=value))
        assert spin_until(executor, lambda: len(reader.core.seen) == 3, 10.0)
        values, arrivals, calls = zip(*reader.core.seen)
        assert values == (1.0, 2.0, 3.0)
        # The callbacks ran SLOW apart, later than the messages arrived ...
        assert calls[2] - calls[0] >= 2 * SLOW
        # ... but each arrival lies between its publish and its callback,
        # in order, and all three arrived before the second callback ran.
        assert sent <= arrivals[0] <= arrivals[1] <= arrivals[2]
        for arrival, call in zip(arrivals, calls):
            assert arrival <= call
        assert arrivals[2] < calls[1], (sent, arrivals, calls)
    finally:
        executor.shutdown()
        writer.destroy_node()
        reader.destroy_node()


def test_decoding_runs_outside_the_nodes_lock(ros_context):
    """
    While a message is being decoded, another thread takes the lock.

    The decoder blocks until released; the test, another thread of the
    node's process as the tick or the diagnostics are, must get the lock
    meanwhile (at once: decoding under the lock would hold it until the
    release, WAIT later). Released, the message reaches the core.
    """
    reader = BlockedDecoder(context=ros_context)
    writer, publisher, executor = writer_of(ros_context)
    try:
        assert spin_until(executor, lambda: publisher.get_subscription_count()
                          == 1, WAIT)
        publisher.publish(Float64(data=7.0))
        assert reader.decoding.wait(WAIT)
        assert reader.lock.acquire(timeout=WAIT / 2), 'decoded under the lock'
        reader.lock.release()
        reader.release.set()
        assert spin_until(executor, lambda: len(reader.core.seen) == 1, WAIT)
        assert reader.core.seen[0][0] == 7.0
    finally:
        reader.release.set()
        executor.shutdown()
        writer.destroy_node()
        reader.destroy_node()
