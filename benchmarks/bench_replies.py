#!/usr/bin/env python3
"""
Replies to a departed client: how long they stop a node's other threads.

Two server processes in turn, each a node with one parameter on an
EventsExecutor spun by ``spin_once`` and a thread that sleeps 1 ms in a
loop and records its gaps:

- ``bare``: a plain rclpy Node (the baseline);
- ``guarded``: a ``managed_node.ManagedNode`` (the package's nodes' one
  shape), whose service replies wait for their client without the GIL and
  are dropped when it has gone.

For each, a client process sends ``--requests`` SetParameters requests and
shuts down cleanly at once. The report: the gaps of the sleeping thread
over 30 ms (count, total, longest) and the replies the guarded node
dropped. rmw_fastrtps waits up to 100 ms, GIL held, for a departed
client's reader before it gives up on a reply.

Usage: python benchmarks/bench_replies.py [--requests 100]
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


def request(count):
    """Child: send ``count`` SetParameters requests, then leave at once."""
    import rclpy
    from rcl_interfaces.msg import Parameter, ParameterValue
    from rcl_interfaces.srv import SetParameters
    rclpy.init()
    node = rclpy.create_node('departing_client')
    client = node.create_client(SetParameters, '/victim/set_parameters')
    if not client.wait_for_service(timeout_sec=20.0):
        return 1
    for i in range(count):
        client.call_async(SetParameters.Request(parameters=[Parameter(
            name='x', value=ParameterValue(type=3, double_value=float(i)))]))
    node.destroy_node()
    rclpy.shutdown()
    return 0


def measure(kind, count):
    """Run a server and a client; return the server's figures."""
    seconds = 3.0 + 0.15 * count
    server = subprocess.Popen(
        [sys.executable, __file__, 'serve', kind, str(seconds)],
        stdout=subprocess.PIPE, text=True)
    try:
        assert server.stdout.readline().startswith('ready')
        subprocess.run([sys.executable, __file__, 'request', str(count)],
                       check=True, timeout=60)
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
        return request(int(sys.argv[2]))
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--requests', type=int, default=100)
    args = parser.parse_args()
    results = {kind: measure(kind, args.requests)
               for kind in ('bare', 'guarded')}
    print(f'{args.requests} SetParameters requests from a client that left '
          f'at once (ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}):')
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
