#!/usr/bin/env python3
"""
CPU of the feedforward's input thread per setpoint, in one process.

The ``feedforward`` node (``pose_only``, ``rate_hz`` 0.0) and a publisher
share this process and talk over Fast DDS: ``--count`` PoseStamped at
``--rate`` Hz, each a setpoint solved and published. The figure is the
input thread's own CPU time (utime + stime of its ``/proc`` task) over
the setpoints it computed: the path of doc/feedforward.md ("How a
setpoint becomes forces") from the wait set to the publications, without
the other threads or the publisher. ``--calls N``: instead, this thread's
CPU per call of ``InputThreads.deliver`` alone, N calls, the core
inactive (decoded, checked and solved; nothing published).

Usage: python benchmarks/bench_input_path.py [--count 10000] [--rate 1000]
       [--calls N]
"""

import argparse
import os
import threading
import time

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(100 + os.getpid() % 100))


def thread_cpu(native_id):
    """Return a thread's utime + stime (s) from /proc."""
    with open(f'/proc/self/task/{native_id}/stat') as stat:
        fields = stat.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def main():
    """Stream the setpoints; print the input thread's CPU per setpoint."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--count', type=int, default=10000)
    parser.add_argument('--rate', type=float, default=1000.0)
    parser.add_argument('--calls', type=int, default=0)
    args = parser.parse_args()
    import rclpy
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from orthoglide_ros.ros.feedforward_node import FeedforwardNode
    rclpy.init()
    node = FeedforwardNode(parameter_overrides=[
        Parameter('pose_only', value=True),
        Parameter('setpoint_timeout', value=60.0)])
    peer = Node('bench_input_path')
    publisher = peer.create_publisher(PoseStamped, 'setpoint/pose', 10)
    try:
        if args.calls:
            return deliver_alone(node, args.calls)
        while publisher.get_subscription_count() == 0:
            time.sleep(0.01)
        time.sleep(0.5)
        inputs = next(t.native_id for t in threading.enumerate()
                      if t.name == 'feedforward inputs')
        message = PoseStamped()
        message.pose.orientation.w = 1.0
        computed, cpu = node.core.computed, thread_cpu(inputs)
        start = time.monotonic()
        for k in range(args.count):
            stamp = message.header.stamp
            stamp.sec, stamp.nanosec = 1 + k // 1000, k % 1000 * 10**6
            message.pose.position.z = 0.001 * (k % 50)      # m, below home
            publisher.publish(message)
            time.sleep(max(0.0, start + (k + 1) / args.rate
                           - time.monotonic()))
        time.sleep(0.5)
        computed = node.core.computed - computed
        cpu = thread_cpu(inputs) - cpu
        print(f'{computed} of {args.count} setpoints computed; input thread '
              f'{cpu / max(1, computed) * 1e6:.1f} us CPU per setpoint')
    finally:
        node.destroy_node()
        peer.destroy_node()
        rclpy.try_shutdown()
    return 0


def deliver_alone(node, calls):
    """Print this thread's CPU per ``deliver`` of a PoseStamped (us)."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.serialization import serialize_message
    node.core.active = False        # solved, counted, not published
    pose = node.inputs.sources['pose']
    messages = []
    for k in range(1000):
        message = PoseStamped()
        message.pose.orientation.w = 1.0
        message.header.stamp.sec = 1 + k
        message.pose.position.z = 0.001 * (k % 50)
        messages.append(serialize_message(message))
    start = time.thread_time()
    for k in range(calls):
        node.inputs.deliver(pose, messages[k % 1000], 1.0)
    print(f'deliver: {(time.thread_time() - start) / calls * 1e6:.2f} us '
          f'CPU per call ({node.core.computed} computed)')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
