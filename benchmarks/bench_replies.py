#!/usr/bin/env python3
"""
Replies to clients that cannot take them: how long they stop a node.

Two server processes in turn, each a node with one parameter on an
EventsExecutor spun by ``spin_once`` and a thread that sleeps 1 ms in a
loop and records its gaps:

- ``bare``: a plain rclpy Node (the baseline);
- ``guarded``: a ``managed_node.ManagedNode`` (the package's nodes' one
  shape), whose service replies wait for their client without the GIL and
  are dropped when it has gone.

For each, a client process sends ``--requests`` SetParameters requests and
shuts down cleanly at once (``--client departing``), or makes its client
with a TRANSIENT_LOCAL reply reader, which the VOLATILE reply writer never
matches, sends them and stays (``--client lingering``). The report: the
gaps of the sleeping thread over 30 ms (count, total, longest) and the
replies the guarded node dropped. rmw_fastrtps waits up to 100 ms, GIL
held, for a client's reader before it gives up on a reply.

Usage: python benchmarks/bench_replies.py [--requests 100]
       [--client departing|lingering]
"""

import argparse
import os
import subprocess
import sys
import threading
import time

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))

STALL = 0.03        # s: a gap of the sleeping thread counted as a stall


def serve(kind, seconds):
    """Child: run the server for ``seconds``; print its figures."""
    import rclpy
    from rclpy.experimental import EventsExecutor
    from rclpy.node import Node

    from orthoglide_ros.cores.core import Core
    from orthoglide_ros.cores.parameters import Spec, Table
    from orthoglide_ros.ros.managed_node import ManagedNode

    class Victim(ManagedNode):
        NAME = TITLE = 'victim'
        PARAMETERS = Table('VictimSettings', (
            Spec('x', 'double', 1.0, 'a parameter to set'),))

        def build(self, settings):
            self.core = Core(settings)
            return ()
    rclpy.init()
    if kind == 'guarded':
        node = Victim()
    else:
        node = Node('victim')
        node.declare_parameter('x', 1.0)
    gaps, stop = [], []

    def sleeper():
        last = time.monotonic()
        while not stop:
            time.sleep(0.001)
            now = time.monotonic()
            gaps.append(now - last)
            last = now
    thread = threading.Thread(target=sleeper, daemon=True)
    thread.start()
    executor = EventsExecutor()
    executor.add_node(node)
    print('ready', flush=True)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.1)
    stop.append(True)
    thread.join()
    stalls = [g for g in gaps if g > STALL]
    print('result', len(stalls), sum(stalls), max(gaps, default=0.0),
          node.replies.replies_dropped if kind == 'guarded' else 0, flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


def request(count, kind, seconds):
    """Child: send ``count`` SetParameters requests; leave, or stay."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from rcl_interfaces.msg import Parameter, ParameterValue
    from rcl_interfaces.srv import SetParameters
    rclpy.init()
    node = rclpy.create_node(f'{kind}_client')
    if kind == 'departing':
        client = node.create_client(SetParameters, '/victim/set_parameters')
        if not client.wait_for_service(timeout_sec=20.0):
            return 1
    else:
        # wait_for_service would wait for its reader to match: never.
        client = node.create_client(
            SetParameters, '/victim/set_parameters', qos_profile=QoSProfile(
                depth=count, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        while '/victim/set_parameters' not in dict(
                node.get_service_names_and_types()):
            time.sleep(0.1)
        time.sleep(1.0)
    for i in range(count):
        client.call_async(SetParameters.Request(parameters=[Parameter(
            name='x', value=ParameterValue(type=3, double_value=float(i)))]))
    if kind == 'lingering':
        time.sleep(seconds)
    node.destroy_node()
    rclpy.shutdown()
    return 0


def measure(kind, count, client):
    """Run a server and a client; return the server's figures."""
    seconds = 3.0 + 0.15 * count
    server = subprocess.Popen(
        [sys.executable, __file__, 'serve', kind, str(seconds)],
        stdout=subprocess.PIPE, text=True)
    try:
        assert server.stdout.readline().startswith('ready')
        subprocess.run([sys.executable, __file__, 'request', str(count),
                        client, str(seconds)], check=True,
                       timeout=seconds + 60)
        fields = server.stdout.readline().split()
        server.wait(seconds + 30)
    finally:
        if server.poll() is None:
            server.kill()
    return dict(stalls=int(fields[1]), stalled=float(fields[2]),
                longest=float(fields[3]), dropped=int(fields[4]))


def main():
    """Measure both servers; print the figures and the ratio."""
    if len(sys.argv) > 1 and sys.argv[1] in ('serve', 'request'):
        if sys.argv[1] == 'serve':
            return serve(sys.argv[2], float(sys.argv[3]))
        return request(int(sys.argv[2]), sys.argv[3], float(sys.argv[4]))
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--requests', type=int, default=100)
    parser.add_argument('--client', choices=('departing', 'lingering'),
                        default='departing')
    args = parser.parse_args()
    results = {kind: measure(kind, args.requests, args.client)
               for kind in ('bare', 'guarded')}
    what = {'departing': 'a client that left at once',
            'lingering': 'a TRANSIENT_LOCAL client that stayed'}[args.client]
    print(f'{args.requests} SetParameters requests from {what} '
          f'(ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}):')
    for kind, r in results.items():
        print(f'  {kind:8} stalls over {STALL * 1e3:.0f} ms of the other '
              f'thread: {r["stalls"]}, {r["stalled"]:.2f} s in all, '
              f'longest gap {r["longest"] * 1e3:.0f} ms; replies dropped '
              f'{r["dropped"]}')
    bare, guarded = results['bare'], results['guarded']
    print(f'  stalled time guarded / bare: {guarded["stalled"]:.2f} / '
          f'{bare["stalled"]:.2f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
