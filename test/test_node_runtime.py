"""
The input threads of ``managed_node.ManagedNode``, over real DDS.

Their contract: a core's input method runs with ``arrival``, the time the
middleware received the message (monotonic clock), not the time the
callback happens to run, so a slow callback or a busy machine does not make
the inputs behind it look late (the feedforward pairs pose, twist and
accel within ``pairing_timeout`` of arrival; the simulator and the tracking
controller judge their timeouts by it too).
"""

import time

import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Float64

from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.parameters import Table
from orthoglide_testing.probe import spin_until
from orthoglide_ros.ros.managed_node import default_qos, Input, ManagedNode

pytestmark = pytest.mark.ros  # DDS and node processes

SLOW = 0.1      # s spent in each callback


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
        """Make the core; return its one input."""
        self.core = Values()
        return (Input('values', Float64, None, self.core.value),)


def test_arrival_is_reception_time_not_callback_time(ros_context):
    """Three messages sent at once, handled SLOW apart: same arrival."""
    reader = SlowReader(context=ros_context)
    writer = Node('writer', context=ros_context)
    publisher = writer.create_publisher(Float64, 'values', default_qos())
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(writer)
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
