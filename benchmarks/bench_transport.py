#!/usr/bin/env python3
"""
Latency of one host's transports: shared memory against the one-host profile.

Two processes in a network namespace of their own
(``testing/orthoglide_testing/netns.py``: the profile needs the range
SYSTEM_DEFAULT, which runs only there; root needed): ``pong`` sends
back every message ``ping`` sends, serialized bytes of a
``std_msgs/UInt8MultiArray`` of 200 B to 4 MiB, reliable,
keep-last 10, one at a time. Printed per size: the one-way latency (half
the round trip) median and 99th percentile, for plain LOCALHOST settings
(Fast DDS's shared memory) and for ``config/fastdds_one_host.xml`` (UDP on
127.0.0.1).

Usage: sudo .venv/bin/python benchmarks/bench_transport.py [--count N]
"""

import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing import netns  # noqa: E402

use_checkout(ROOT)

SIZES = (200, 64 * 1024, 1024 * 1024, 4 * 1024 * 1024)
PROFILE = os.path.join(ROOT, 'config', 'fastdds_one_host.xml')
DOMAIN = 229


def _node(name):
    import rclpy
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    rclpy.init()
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                     reliability=ReliabilityPolicy.RELIABLE)
    return rclpy, rclpy.create_node(name), qos


def pong():
    """Send every message of ``ping`` back, as it came (raw bytes)."""
    from std_msgs.msg import UInt8MultiArray
    rclpy, node, qos = _node('pong')
    back = node.create_publisher(UInt8MultiArray, 'pong', qos)
    node.create_subscription(UInt8MultiArray, 'ping', back.publish, qos,
                             raw=True)
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass


def ping(count):
    """Time ``count`` round trips per size; print JSON (one-way, s)."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import UInt8MultiArray
    rclpy, node, qos = _node('ping')
    got = []
    out = node.create_publisher(UInt8MultiArray, 'ping', qos)
    node.create_subscription(UInt8MultiArray, 'pong',
                             lambda data: got.append(time.perf_counter()),
                             qos, raw=True)
    deadline = time.monotonic() + 30.0
    while out.get_subscription_count() == 0 or \
            node.count_publishers('pong') == 0:
        rclpy.spin_once(node, timeout_sec=0.05)
        if time.monotonic() > deadline:
            raise SystemExit('pong not found')
    rclpy.spin_once(node, timeout_sec=1.0)
    results = {}
    for size in SIZES:
        data = serialize_message(UInt8MultiArray(data=bytes(size)))
        times = []
        for k in range(count + 3):      # three to warm up
            got.clear()
            start = time.perf_counter()
            out.publish(data)
            while not got:
                rclpy.spin_once(node, timeout_sec=1.0)
            if k >= 3:
                times.append((got[0] - start) / 2)
        times.sort()
        results[size] = (times[len(times) // 2],
                         times[int(0.99 * (len(times) - 1))])
    print(json.dumps(results), flush=True)


def measure(profile, count):
    """Run pong and ping in a new namespace; return ping's results."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN),
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    env.pop('FASTRTPS_DEFAULT_PROFILES_FILE', None)
    if profile:
        env.update(FASTRTPS_DEFAULT_PROFILES_FILE=profile,
                   ROS_AUTOMATIC_DISCOVERY_RANGE='SYSTEM_DEFAULT')
    me = os.path.abspath(__file__)
    with netns.Namespace() as ns:
        server = subprocess.Popen(ns.command([sys.executable, me, 'pong']),
                                  env=env, stderr=subprocess.DEVNULL)
        try:
            out = subprocess.run(
                ns.command([sys.executable, me, 'ping', '--count',
                            str(count)]), env=env, capture_output=True,
                text=True, timeout=600)
        finally:
            server.terminate()
            server.wait(10)
    if out.returncode:
        raise SystemExit(out.stderr[-2000:])
    return {int(k): v for k, v in json.loads(out.stdout).items()}


def main():
    """Measure both settings and print a table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('role', nargs='?', choices=('ping', 'pong'))
    parser.add_argument('--count', type=int, default=200)
    args = parser.parse_args()
    if args.role == 'pong':
        return pong()
    if args.role == 'ping':
        return ping(args.count)
    reason = netns.unavailable()
    if reason:
        raise SystemExit(f'bench_transport: {reason}')
    plain, profile = measure(None, args.count), measure(PROFILE, args.count)
    print(f'one-way latency, {args.count} round trips per size '
          '(median / p99, ms)')
    print(f'{"size":>9}  {"shared memory":>17}  {"one-host profile":>17}')
    for size in SIZES:
        cells = [f'{m * 1e3:7.3f} / {p * 1e3:7.3f}'
                 for m, p in (plain[size], profile[size])]
        print(f'{size:>9}  {cells[0]:>17}  {cells[1]:>17}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
