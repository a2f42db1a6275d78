#!/usr/bin/env python3
"""
The memory of each node, with and without ``lock_memory``, as it runs.

The five nodes run as a robot's computer runs them: a closed loop of
processes started from their console scripts on real Fast DDS (LOCALHOST,
a domain of their own), ``setpoint_publisher`` (``--rate`` setpoints per
second, looped) -> ``feedforward`` -> ``tracking_controller`` ->
``simulator`` -> ``mechanism_state_publisher``, all with ``-p
lock_memory:=true`` in one round and without it in another (``--rounds``).
Once the feedforward's output flows, the loop settles for ``--settle`` s;
then over a window of ``--window`` s this process reads, for each node,
``/proc/PID/status`` (VmLck, VmRSS, Threads), ``smaps_rollup`` (Pss,
private pages, locked pages) at the end, and the page faults of the
window (``/proc/PID/stat`` minflt, majflt): a loop whose pages stay
locked takes none once it runs. It counts the feedforward's outputs over
the window (the rate it served) and stops every process (SIGINT) at the
end. ``--scripts DIR`` runs the console scripts of another checkout's
environment (``/path/.venv/bin``: its figures before a change).

Usage: python benchmarks/bench_memory.py [--rate 1000] [--settle 5]
       [--window 10] [--rounds lock,plain] [--engine builtin|mujoco]
       [--scripts DIR] [--json FILE]
"""

import json
import os
import platform
import sys
import time

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(100 + os.getpid() % 100))

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing.arguments import script_parser  # noqa: E402
from orthoglide_testing.messages import qos_profile  # noqa: E402
from orthoglide_testing.probe import spin_until  # noqa: E402
from orthoglide_testing.processes import (memory_kb,  # noqa: E402
                                          node_executable, page_faults,
                                          start_node_process,
                                          stop_process)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
use_checkout(ROOT)

NODES = ('feedforward', 'simulator', 'tracking_controller',
         'setpoint_publisher', 'mechanism_state_publisher')
ROUNDS = {'lock': ['-p', 'lock_memory:=true'], 'plain': []}
START_TIMEOUT = 60.0    # s for the loop to start flowing
SAMPLE = 0.5            # s between two readings of /proc


def node_args(name, rate, engine):
    """Return the node's arguments in the loop (beside the round's)."""
    return {
        'setpoint_publisher': ['-p', f'rate_hz:={float(rate)}',
                               '-p', 'loop:=true'],
        'tracking_controller': [
            '-r', 'joint_trajectory:=feedforward/joint_trajectory'],
        'simulator': ['-p', f'engine:={engine}'],
    }.get(name, [])


class Counter(Node):
    """Count the feedforward's joint states."""

    def __init__(self):
        super().__init__('bench_memory')
        self.count = 0
        self.create_subscription(JointState, 'feedforward/joint_states',
                                 self._on_joints, qos_profile('reliable'))

    def _on_joints(self, msg):
        self.count += 1


def run_round(label, extra, args, counter, executor, say):
    """Run the loop with ``extra`` arguments; return {node: figures}."""
    procs = {}
    try:
        for name in NODES:
            procs[name] = start_node_process(
                ['--ros-args', *node_args(name, args.rate, args.engine),
                 *extra], command=[os.path.join(args.scripts, name)])
        counter.count = 0
        if not spin_until(executor, lambda: counter.count > 100,
                          START_TIMEOUT):
            raise RuntimeError(f'{label}: the feedforward never published')
        spin_until(executor, lambda: False, args.settle)
        faults = {n: page_faults(p.pid) for n, p in procs.items()}
        peak = {n: {} for n in procs}
        first = counter.count
        start = time.monotonic()
        while time.monotonic() - start < args.window:
            for name, proc in procs.items():
                held = memory_kb(proc.pid) or {}
                for key, value in held.items():
                    peak[name][key] = max(peak[name].get(key, 0), value)
            spin_until(executor, lambda: False, SAMPLE)
        served = (counter.count - first) / (time.monotonic() - start)
        figures = {}
        for name, proc in procs.items():
            end = page_faults(proc.pid)
            if end is None or proc.poll() is not None:
                raise RuntimeError(f'{label}: {name} exited')
            figures[name] = dict(
                peak[name], minflt=end[0] - faults[name][0],
                majflt=end[1] - faults[name][1])
        say(f'{label}: the feedforward served {served:.0f} setpoints/s')
        figures['feedforward']['served_hz'] = served
        return figures
    finally:
        for name, proc in procs.items():
            code, stderr = stop_process(proc)
            if code != 0:
                say(f'{label}: {name} exited {code}: {stderr[-500:]}')


def table(results, window):
    """Return the figures as Markdown lines (MB = 1000 kB)."""
    lines = ['| node | lock_memory | locked (VmLck) | resident (VmRSS) | '
             'Pss | private | threads | minor / major faults in '
             f'{window:g} s |', '|---|---|---|---|---|---|---|---|']
    for name in NODES:
        for label, figures in results.items():
            f = figures[name]
            lines.append(
                f'| `{name}` | {"true" if label == "lock" else "false"} | '
                f'{f["locked"] / 1000:.0f} MB | {f["resident"] / 1000:.0f} '
                f'MB | {f["proportional"] / 1000:.0f} MB | '
                f'{f["private"] / 1000:.0f} MB | {f["threads"]} | '
                f'{f["minflt"]} / {f["majflt"]} |')
    return lines


def main():
    """Run the benchmark; return the exit code."""
    parser = script_parser(
        __doc__, ('--rate', 1000.0, 'setpoints per second'),
        ('--settle', 5.0, 'seconds of flow before the window'),
        ('--window', 10.0, 'seconds measured'),
        ('--rounds', 'lock,plain', 'lock and/or plain, comma-separated'))
    parser.add_argument('--engine', default='builtin',
                        choices=('builtin', 'mujoco'),
                        help="the simulator's engine (default builtin)")
    parser.add_argument('--scripts', metavar='DIR', default=os.path.dirname(
        node_executable()), help="the nodes' console scripts (default: "
        "this Python's)")
    parser.add_argument('--json', metavar='FILE', help='save the figures')
    args = parser.parse_args()
    rounds = [r for r in args.rounds.split(',') if r]
    if not rounds or set(rounds) - set(ROUNDS):
        parser.error('--rounds: lock and/or plain')
    if not (0.1 <= args.rate <= 10000.0 and args.window > 0.0
            and args.settle >= 0.0):
        parser.error('--rate within [0.1, 10000], --window above 0, '
                     '--settle at least 0')

    def say(text):
        print(text, file=sys.stderr, flush=True)

    rclpy.init()
    counter = Counter()
    executor = SingleThreadedExecutor()
    executor.add_node(counter)
    results = {}
    try:
        for label in rounds:
            results[label] = run_round(label, ROUNDS[label], args, counter,
                                       executor, say)
    finally:
        executor.shutdown()
        counter.destroy_node()
        rclpy.try_shutdown()
    print(f'bench_memory: {platform.node()}, {os.cpu_count()} CPUs, '
          f'Linux {platform.release()}, Python '
          f'{platform.python_version()}; setpoints at {args.rate:g} Hz, '
          f'simulator engine {args.engine}; peaks over {args.window:g} s '
          f'after {args.settle:g} s of flow; nodes from {args.scripts}')
    print('\n'.join(table(results, args.window)))
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(dict(args=vars(args), results=results), f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
