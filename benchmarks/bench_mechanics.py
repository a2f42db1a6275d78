#!/usr/bin/env python3
"""
Benchmark the inverse kinematics and dynamics (mechanics.solve*).

Measures, in one run, on the paper trajectory of eq. (6):

- single sample: ``mechanics.solve`` on Python floats, each call timed with
  ``time.perf_counter_ns`` after a warm-up; median and p99 in microseconds;
- batch: ``mechanics.solve_batch`` on N samples, best of several repeats,
  in samples per second;

and the same figures for the straightforward ways kept as baselines:
(a) one sample through ``solve_batch`` on (1, 3) arrays, (b) a batch as a
per-sample Python loop over ``solve``. Targets: single <= 25 us median,
batch >= 1,000,000 samples/s at N = 10,000. No ROS import.

Usage: python benchmarks/bench_mechanics.py [--samples N] [--repeat R]
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..'))

from orthoglide_ros import mechanics, trajectory  # noqa: E402
from orthoglide_ros.robot import Robot  # noqa: E402

SINGLE_TARGET_US = 25.0
BATCH_TARGET = 1_000_000.0
BATCH_TARGET_N = 10_000


def time_calls(call, samples, calls, warmup):
    """Time ``call(*sample)`` cycling over ``samples``; return ns per call."""
    n = len(samples)
    for i in range(warmup):
        call(*samples[i % n])
    clock = time.perf_counter_ns
    out = np.empty(calls, dtype=np.int64)
    for i in range(calls):
        sample = samples[i % n]
        start = clock()
        call(*sample)
        out[i] = clock() - start
    return out


def best_time(call, repeat):
    """Return the best wall time (s) of ``call()`` over ``repeat`` runs."""
    best = float('inf')
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def timer_overhead_ns(calls=10000):
    """Median cost (ns) of two back-to-back perf_counter_ns calls."""
    clock = time.perf_counter_ns
    deltas = []
    for _ in range(calls):
        start = clock()
        deltas.append(clock() - start)
    return float(np.median(deltas))


def verdict(ok):
    """Return PASS or MISS."""
    return 'PASS' if ok else 'MISS'


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--samples', type=int, default=BATCH_TARGET_N,
                        help='batch size N (default %(default)s)')
    parser.add_argument('--repeat', type=int, default=7,
                        help='batch repeats, best kept (default %(default)s;'
                        ' the slow loop baseline runs min(3, R))')
    parser.add_argument('--calls', type=int, default=20000,
                        help='timed single-sample calls (default '
                        '%(default)s)')
    parser.add_argument('--warmup', type=int, default=2000,
                        help='untimed warm-up calls (default %(default)s)')
    args = parser.parse_args(argv)

    robot = Robot()
    p, v, a = trajectory.paper_batch(trajectory.paper_times(args.samples))
    floats = [(robot, tuple(pi), tuple(vi), tuple(ai)) for pi, vi, ai in zip(
        p.tolist(), v.tolist(), a.tolist())]
    rows = [(robot, p[i:i + 1], v[i:i + 1], a[i:i + 1])
            for i in range(min(len(p), 2000))]

    print(f'Python {platform.python_version()}, numpy {np.__version__}, '
          f'{platform.machine()}, {os.cpu_count()} CPUs; timer overhead '
          f'{timer_overhead_ns():.0f} ns (included below)')

    single = time_calls(mechanics.solve, floats, args.calls, args.warmup)
    base_a = time_calls(mechanics.solve_batch, rows, args.calls // 4,
                        args.warmup // 4)
    s_med, s_p99 = np.percentile(single, [50, 99]) / 1e3
    a_med, a_p99 = np.percentile(base_a, [50, 99]) / 1e3
    print(f'\nSingle sample, paper trajectory points ({args.calls} calls):')
    print(f'  ours  solve (Python floats)      median {s_med:8.2f} us   '
          f'p99 {s_p99:8.2f} us')
    print(f'  base  solve_batch on (1, 3)      median {a_med:8.2f} us   '
          f'p99 {a_p99:8.2f} us')
    print(f'  ratio ours/base (time)           median {s_med / a_med:8.3f}'
          f'      p99 {s_p99 / a_p99:8.3f}')

    n = len(p)
    t_batch = best_time(lambda: mechanics.solve_batch(robot, p, v, a),
                        args.repeat)
    t_loop = best_time(lambda: [mechanics.solve(*s) for s in floats],
                       min(3, args.repeat))
    batch_rate, loop_rate = n / t_batch, n / t_loop
    print(f'\nBatch, N = {n} (best of {args.repeat}):')
    print(f'  ours  solve_batch                {batch_rate:14,.0f} samples/s'
          f'  ({t_batch * 1e3:.2f} ms)')
    print(f'  base  loop over solve            {loop_rate:14,.0f} samples/s'
          f'  ({t_loop * 1e3:.2f} ms)')
    print(f'  ratio ours/base (throughput)     {batch_rate / loop_rate:14.1f}')

    print('\nTargets:')
    print(f'  single median <= {SINGLE_TARGET_US:g} us: {s_med:.2f} us  '
          f'{verdict(s_med <= SINGLE_TARGET_US)}')
    if n == BATCH_TARGET_N:
        print(f'  batch >= {BATCH_TARGET:,.0f} samples/s at N = '
              f'{BATCH_TARGET_N:,}: {batch_rate:,.0f}  '
              f'{verdict(batch_rate >= BATCH_TARGET)}')
    else:
        print(f'  batch target applies at N = {BATCH_TARGET_N:,} only '
              f'(ran N = {n:,})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
