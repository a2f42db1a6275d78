#!/usr/bin/env python3
"""
Whole Cartesian trajectories into JointTrajectories: how long it takes.

For 100, 1,000 and 10,000 points of the paper's trajectory:

- kernel side (this process, no ROS graph): ``mechanics.solve_batch`` of
  the points; the whole conversion path of the node without DDS (reading
  the serialized MultiDOFJointTrajectory, ``convert_trajectory``, writing
  the JointTrajectory); and, as the baseline, rclpy's own deserializer and
  serializer of the same messages;
- node side: the installed ``feedforward`` process receives each
  trajectory on ``cartesian_trajectory`` and publishes
  ``feedforward/joint_trajectory``; it reports the time from the reception
  of the message to its publication in ``/diagnostics`` (``trajectory
  receive to publish``), and this process measures the round trip too.

Medians of ``--repeat`` runs (default 20, 5 for the node side).

Usage: python benchmarks/bench_trajectory.py [--repeat N]
"""

import argparse
import os
import sys
import time

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
from rclpy.serialization import (deserialize_message,  # noqa: E402
                                 serialize_message)
from trajectory_msgs.msg import (JointTrajectory,  # noqa: E402
                                 MultiDOFJointTrajectory)

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing.hostile import Nodes, Peer  # noqa: E402
from orthoglide_testing.messages import cartesian_message  # noqa: E402
from orthoglide_ros.model import trajectory  # noqa: E402
from orthoglide_ros.formats import cdr  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.cores.feedforward import (convert_trajectory,  # noqa: E402
                                              PARAMETERS)
from orthoglide_ros.model.robot import Robot  # noqa: E402

use_checkout(ROOT)

SIZES = (100, 1000, 10000)


def median_ms(call, repeat):
    """Median wall time of ``call()`` over ``repeat`` runs (ms)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def paper(n):
    """Return the paper's 2 s trajectory in ``n`` points and its message."""
    times = np.linspace(0.0, 2.0, n)
    return times, cartesian_message(times, *trajectory.paper_batch(times),
                                    (0, 0))


def kernel_side(repeat):
    """Return {n: (solve_batch, node path, rclpy baseline)} in ms."""
    settings = PARAMETERS.parse({})
    robot = Robot()
    results = {}
    for n in SIZES:
        times, msg = paper(n)
        p, v, a = trajectory.paper_batch(times)
        data = serialize_message(msg)

        def node_path():
            c = convert_trajectory(settings, cdr.cartesian_trajectory(data))
            s = c.solution
            return cdr.joint_trajectory(c.stamp, c.frame,
                                        settings.joint_names, c.time,
                                        s.lambda_, s.lambdadot, s.lambdaddot,
                                        s.force)
        out = node_path()

        def rclpy_path():
            deserialize_message(data, MultiDOFJointTrajectory)
            serialize_message(deserialize_message(out, JointTrajectory))
        results[n] = (median_ms(lambda: mechanics.solve_batch(robot, p, v, a),
                                repeat),
                      median_ms(node_path, repeat),
                      median_ms(rclpy_path, max(3, repeat // 4)))
    return results


def node_side(repeat):
    """Return {n: (receive to publish, round trip)} in ms, medians."""
    results = {}
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward')
        pub = peer.publisher(MultiDOFJointTrajectory, 'cartesian_trajectory')
        out = peer.record('feedforward/joint_trajectory', JointTrajectory,
                          depth=10)
        if not peer.wait(lambda: pub.get_subscription_count() > 0, 20.0):
            raise RuntimeError('the feedforward did not subscribe')
        time.sleep(1.0)
        for n in SIZES:
            _, msg = paper(n)
            trips, inside = [], []
            for _ in range(repeat):
                before = len(out)
                start = time.monotonic()
                pub.publish(msg)
                if not peer.wait(lambda: len(out) > before, 20.0):
                    raise RuntimeError(f'no output for {n} points')
                trips.append(out[-1][0] - start)
                status = peer.status('feedforward', timeout=3.0)
                inside.append(float(status[2][
                    'trajectory receive to publish last (ms)']))
            results[n] = (float(np.median(inside)),
                          1e3 * float(np.median(trips)))
    return results


def main():
    """Measure and print both sides."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--repeat', type=int, default=20)
    args = parser.parse_args()
    kernel = kernel_side(args.repeat)
    node = node_side(max(3, args.repeat // 4))
    print(f'Cartesian trajectory -> JointTrajectory, medians (ms), '
          f'ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}:')
    print(f'{"points":>7} {"solve_batch":>12} {"node path":>10} '
          f'{"rclpy (de)ser":>14} {"node: receive->publish":>23} '
          f'{"round trip":>11}')
    for n in SIZES:
        k, (inside, trip) = kernel[n], node[n]
        print(f'{n:>7} {k[0]:12.2f} {k[1]:10.2f} {k[2]:14.2f} '
              f'{inside:23.2f} {trip:11.2f}')
    print('node path: read + convert_trajectory + write, no DDS; rclpy '
          '(de)ser: rclpy deserializing the input and serializing the '
          'output, the baseline the node path replaces')
    return 0


if __name__ == '__main__':
    sys.exit(main())
