#!/usr/bin/env python3
"""
End-to-end benchmark of the ``feedforward`` node, cross-process, over DDS.

For each input form (``trajectory``: one MultiDOFJointTrajectory per
setpoint; ``topics``: pose, twist and accel paired by stamp) and each
target process:

- ``node``: ``.venv/bin/feedforward --ros-args --params-file
  config/orthoglide.yaml -p setpoint_timeout:=1.0`` (EventsExecutor spun by
  ``spin_once`` in a loop);
- ``echo-single``, ``echo-events``: the baseline ``echo_node.py``, a bare
  rclpy node that only echoes the stamp, spun by rclpy's default
  SingleThreadedExecutor and by the EventsExecutor (``spin_once`` loop);

this process (the producer) publishes N setpoints of the paper trajectory
at a steady rate (sleep until each deadline, no bursts; unique nonzero
stamps) and a separate recorder process (this script with ``--record``,
EventsExecutor, so producer and recorder do not share one GIL) stamps the
arrival of each ``feedforward/joint_states`` with CLOCK_MONOTONIC, the
clock the producer uses for the publish times (system-wide on Linux).
Latency = receive time - publish time of the setpoint with that stamp
(for ``topics``, the publish time of its pose, published first). Each
target process first echoes one start-up setpoint and gets a 0.5 s
pre-roll, both unmeasured. CPU per tick = utime + stime of the target
process over the run (first publish to end of the drain) / setpoints sent.

A rate scan then finds, per target and input, the highest rate of the scan
list that is sustained: loss <= 0.1 % and p99 latency < 20 ms.

Under load: ``--load N`` starts N busy loops (``while True: pass``, normal
scheduling) for the whole benchmark and ends them; ``--thread-priority P``
runs every target twice, as it is and real-time: the node with ``-p
thread_priority:=P`` (every thread SCHED_FIFO P, checked in
``/proc/PID/task`` during the run), the echo baselines under ``chrt -f
P``. The producer (this process) and the recorder then run SCHED_FIFO
``--client-priority`` (default 60, as a ros2_control loop's client; 0:
normal), their children reset to normal scheduling. The real-time check:
the node's p99 at most 2x the real-time echo's and at most 3 ms, at most
0.2 % of the setpoints lost, every thread SCHED_FIFO.

Usage: python benchmarks/bench_node.py [--rate 1000] [--duration 10]
       [--inputs trajectory,topics] [--qos reliable[,best_effort]]
       [--rates-scan 500,1000,1500,2000,3000] [--scan-duration S]
       [--targets node,echo-single,echo-events] [--json FILE]
       [--load N] [--thread-priority P] [--client-priority C]
"""

import argparse
import array
import json
import math
import os
import platform
import select
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

import rclpy
from rclpy.executors import ExternalShutdownException

from sensor_msgs.msg import JointState

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing.load import (busy_loops, client as fifo_client,  # noqa: E402
                                     granted, normal)
from orthoglide_testing.messages import (INPUT_TOPICS,  # noqa: E402
                                         Producer, qos_profile)
from orthoglide_testing.processes import (cpu_seconds,  # noqa: E402
                                          interrupt)
from orthoglide_ros.model.trajectory import PAPER_DURATION  # noqa: E402
from orthoglide_ros.model.trajectory import paper_sample  # noqa: E402

use_checkout(ROOT)

TARGETS = ('node', 'echo-single', 'echo-events')
NODES = ('node',)
EXECUTORS = {'echo-single': 'single', 'echo-events': 'events'}
BASELINES = ('echo-single', 'echo-events')
SUSTAINED_LOSS = 0.001      # fraction of the setpoints sent
SUSTAINED_P99_MS = 20.0
TARGET_RATE, TARGET_DURATION = 1000, 10.0
SEGMENT_S = 10000           # stamps of run k start at (k + 1) * SEGMENT_S s
DRAIN_S = 0.5
PREROLL_S = 0.5
START_TIMEOUT_S = 20.0
# The real-time check (--thread-priority): p99 at most this times the
# real-time echo's and at most RT_P99_MS, loss at most RT_LOSS.
RT_P99_FACTOR, RT_P99_MS, RT_LOSS = 2.0, 3.0, 0.002


# Recorder process --------------------------------------------------------
def record(path, qos):
    """Log (sec, nanosec, monotonic ns) of each joint state to ``path``."""
    from rclpy.experimental import EventsExecutor
    rclpy.init()
    node = rclpy.create_node('bench_recorder')
    log = array.array('q')
    clock = time.monotonic_ns
    out = sys.stdout

    def on_joints(msg):
        stamp = msg.header.stamp
        log.extend((stamp.sec, stamp.nanosec, clock()))
        if stamp.sec == 1:      # a start-up setpoint came through
            out.write(f'echo {stamp.sec} {stamp.nanosec}\n')
            out.flush()

    # Depth 1000 so that the recorder's own queue is not what loses data.
    sub = node.create_subscription(JointState, 'feedforward/joint_states',
                                   on_joints, qos_profile(qos, 1000))

    def matched():
        if sub.get_publisher_count() > 0:
            timer.cancel()
            out.write('matched\n')
            out.flush()

    timer = node.create_timer(0.01, matched)
    executor = EventsExecutor()
    executor.add_node(node)
    try:
        while rclpy.ok():   # not spin(): it busy-polls and ignores SIGINT
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        with open(path, 'wb') as f:
            log.tofile(f)
        node.destroy_node()
        rclpy.try_shutdown()


# Target processes --------------------------------------------------------
def target_command(target, kind, qos, priority=0):
    """Command line of a target process (``priority``: real-time)."""
    if target in NODES:
        cmd = [os.path.join(os.path.dirname(sys.executable), 'feedforward')]
        cmd += ['--ros-args', '--params-file',
                os.path.join(ROOT, 'config', 'orthoglide.yaml'),
                '-p', 'setpoint_timeout:=1.0']
        if priority:
            cmd += ['-p', f'thread_priority:={priority}']
        if qos != 'reliable':
            for topic in INPUT_TOPICS[kind]:
                cmd += ['-p', f'qos_overrides./setpoint/{topic}.subscription'
                        f'.reliability:={qos}']
            for topic in ('joint_states', 'forces', 'power'):
                cmd += ['-p', f'qos_overrides./feedforward/{topic}.publisher'
                        f'.reliability:={qos}']
        return cmd
    return chrt(priority) + [
        sys.executable, os.path.join(HERE, 'echo_node.py'), '--input', kind,
        '--executor', EXECUTORS[target], '--qos', qos]


def chrt(priority):
    """Return the command prefix that starts a process SCHED_FIFO P."""
    return ['chrt', '-f', str(priority)] if priority else []


def fifo_threads(pid, priority):
    """Return (threads at SCHED_FIFO ``priority``, threads) of ``pid``."""
    held = []
    for name in os.listdir(f'/proc/{pid}/task'):
        try:
            held.append((os.sched_getscheduler(int(name)),
                         os.sched_getparam(int(name)).sched_priority))
        except ProcessLookupError:
            continue
    return sum(1 for h in held if h == (os.SCHED_FIFO, priority)), len(held)


def stop(proc):
    """Stop a child (processes.interrupt); return how it ended."""
    if proc.poll() is not None:
        return f'had exited ({proc.returncode})'
    if interrupt(proc, 3.0):
        return f'exited on SIGINT ({proc.returncode})'
    return 'ignored SIGINT for 3 s, killed'


class Failed(RuntimeError):
    """A target or the recorder exited or does not answer."""


def produce(producer, rate, count, base_ns, check):
    """Publish ``count`` setpoints at ``rate``; return stamps and times."""
    step = 1e9 / rate
    stamps = [base_ns + round(i * step) for i in range(count)]
    samples = [paper_sample((i / rate) % PAPER_DURATION)
               for i in range(count)]
    published = np.zeros(count, dtype=np.int64)
    late = np.zeros(count, dtype=np.int64)
    clock, sleep = time.monotonic_ns, time.sleep
    start = clock() + 10000000
    for i in range(count):
        producer.fill(stamps[i], samples[i])
        deadline = start + round(i * step)
        wait = deadline - clock()
        if wait > 0:
            sleep(wait / 1e9)
        now = clock()
        producer.publish()
        published[i] = now
        late[i] = now - deadline
        if i % 200 == 199:
            check()
    return np.asarray(stamps, dtype=np.int64), published, late


# One target process, several runs -----------------------------------------
def run_group(target, kind, qos, runs, domain, say, priority=0,
              client=0):
    """
    Start a target and a recorder, do ``runs`` [(rate, s)], stop both.

    ``priority``: the target's real-time priority (0: as it is);
    ``client``: the producer's and the recorder's (0: normal).
    """
    tmp = tempfile.mkdtemp(prefix='bench-node-')
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain),
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               ROS_LOG_DIR=os.path.join(tmp, 'log'))
    log_path = os.path.join(tmp, 'recorder.bin')
    err = open(os.path.join(tmp, 'target.err'), 'w+')
    procs = {}
    context = node = None
    results = [dict(target=target, input=kind, qos=qos, rate=rate,
                    duration=duration, priority=priority, status='not run')
               for rate, duration in runs]
    try:
        t0 = time.monotonic()
        procs['target'] = subprocess.Popen(
            target_command(target, kind, qos, priority), env=env, cwd=ROOT,
            stdin=subprocess.DEVNULL, stdout=err, stderr=err)
        procs['recorder'] = subprocess.Popen(
            chrt(client) + [sys.executable, os.path.abspath(__file__),
                            '--record', log_path, '--qos', qos],
            env=env, cwd=ROOT,
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True)

        def check():
            for name, proc in procs.items():
                if proc.poll() is not None:
                    raise Failed(f'{name} exited with code {proc.returncode}')

        context = rclpy.Context()
        rclpy.init(context=context, domain_id=domain)
        node = rclpy.create_node('bench_producer', context=context)
        producer = Producer(node, kind, qos)
        if client:      # this process's DDS threads exist now
            for warning in fifo_client(client):
                say(f'  {warning}')
        _start(producer, procs['recorder'], check, runs[0][0])
        for k, (rate, duration) in enumerate(runs):
            result = results[k]
            count = max(1, round(rate * duration))
            pid = procs['target'].pid
            cpu = (cpu_seconds(pid), cpu_seconds(procs['recorder'].pid),
                   time.process_time())
            try:
                stamps, published, late = produce(
                    producer, rate, count, (k + 1) * SEGMENT_S * 10**9,
                    check)
                time.sleep(DRAIN_S)
                check()
            except Failed as error:
                result['status'] = f'failed: {error}'
                raise
            end = (cpu_seconds(pid), cpu_seconds(procs['recorder'].pid),
                   time.process_time())
            result['fifo_threads'] = fifo_threads(pid, priority) \
                if priority else None
            result.update(status='ok', stamps=stamps, published=published,
                          late=late, sent=count,
                          cpu_us=_per_tick(cpu[0], end[0], count),
                          recorder_cpu_us=_per_tick(cpu[1], end[1], count),
                          producer_cpu_us=_per_tick(cpu[2], end[2], count))
            say(f'  {label(result):14} {kind:10} {qos:11} {rate:5d} Hz done')
    except Failed as error:
        pid = procs['target'].pid
        busy = cpu_seconds(pid)
        if busy is not None:
            share = busy / (time.monotonic() - t0)
            error = f'{error}; target used {share:.0%} of a core'
        for result in results:
            if result['status'] == 'not run':
                result['status'] = f'failed: {error}'
    finally:
        if client:
            normal()
        ends = {name: stop(proc) for name, proc in procs.items()}
        if node is not None:
            node.destroy_node()
        if context is not None:
            rclpy.try_shutdown(context=context)
        err.seek(0)
        tail = err.read()[-600:]
        err.close()
        try:
            log = np.fromfile(log_path, dtype=np.int64).reshape(-1, 3)
        except (OSError, ValueError):
            log = None
        shutil.rmtree(tmp, ignore_errors=True)
    for result in results:
        result['stop'] = ends
        if result['status'].startswith('failed'):
            result['target_stderr'] = tail
        if 'stamps' in result:
            _latencies(result, log)
    return results


def _start(producer, recorder, check, rate):
    """Wait for discovery and one setpoint's echo; then a pre-roll."""
    deadline = time.monotonic() + START_TIMEOUT_S
    matched = False
    while not (matched and producer.matched()):
        check()
        if time.monotonic() > deadline:
            raise Failed('discovery timed out')
        ready, _, _ = select.select([recorder.stdout], [], [], 0.05)
        if ready and recorder.stdout.readline().startswith('matched'):
            matched = True
    warmup = 0
    while True:
        check()
        if time.monotonic() > deadline:
            raise Failed('unresponsive: no warm-up setpoint came back '
                         f'in {START_TIMEOUT_S:g} s')
        warmup += 1
        producer.fill(10**9 + warmup * 1000, paper_sample(0.0))
        producer.publish()
        ready, _, _ = select.select([recorder.stdout], [], [], 0.1)
        if ready and recorder.stdout.readline().startswith('echo'):
            break
    # Pre-roll, not measured: PREROLL_S at the rate of the first run.
    produce(producer, rate, round(rate * PREROLL_S), 2 * 10**9, check)
    time.sleep(0.2)


def _per_tick(start, end, count):
    if start is None or end is None:
        return None
    return (end - start) / count * 1e6


def _latencies(result, log):
    """Match received stamps to published ones; add loss and latency."""
    stamps = result.pop('stamps')
    published = result.pop('published')
    late = result.pop('late')
    result['late_p99_ms'] = float(np.percentile(late, 99)) / 1e6
    if log is None:
        log = np.zeros((0, 3), dtype=np.int64)
    got = log[:, 0] * 10**9 + log[:, 1]
    inside = (got >= stamps[0]) & (got <= stamps[-1])
    got, received = got[inside], log[inside, 2]
    index = np.searchsorted(stamps, got)
    hit = stamps[np.minimum(index, len(stamps) - 1)] == got
    _, first = np.unique(got[hit], return_index=True)
    matched = len(first)
    latency = (received[hit][first] - published[index[hit][first]]) / 1e6
    seen = np.zeros(len(stamps), dtype=bool)
    seen[index[hit]] = True
    result.update(received=int(inside.sum()), matched=matched,
                  lost=result['sent'] - matched,
                  first_lost=np.flatnonzero(~seen)[:10].tolist(),
                  loss=(result['sent'] - matched) / result['sent'])
    if matched:
        p50, p99 = np.percentile(latency, (50, 99))
        result.update(p50_ms=float(p50), p99_ms=float(p99),
                      max_ms=float(latency.max()))
    result['sustained'] = bool(
        matched and result['loss'] <= SUSTAINED_LOSS
        and result['p99_ms'] < SUSTAINED_P99_MS)


# Report -------------------------------------------------------------------
def _f(value, form='.2f'):
    return '-' if value is None else format(value, form)


def label(result):
    """Return a target's name in the tables: ``node``, ``node fifo 50``."""
    priority = result.get('priority')
    return result['target'] + (f' fifo {priority}' if priority else '')


def table(results):
    """Lines of the main table."""
    head = (f'{"target":14} {"input":10} {"qos":11} {"rate":>5} '
            f'{"sent":>6} {"recv":>6} {"lost":>5} {"p50":>6} {"p99":>6} '
            f'{"max":>7} {"cpu/tick":>8} {"rec/tk":>6} {"late99":>6}')
    lines = [head, f'{"":53}{"(ms)":>20}{"(us)":>17}{"(us)":>7}'
             f'{"(ms)":>7}', '-' * len(head)]
    for r in results:
        row = (f'{label(r):14} {r["input"]:10} {r["qos"]:11} '
               f'{r["rate"]:5d} ')
        if r['status'] != 'ok':
            lines.append(row + r['status'])
            continue
        lines.append(
            row + f'{r["sent"]:6d} {r["received"]:6d} {r["lost"]:5d} '
            f'{_f(r.get("p50_ms")):>6} {_f(r.get("p99_ms")):>6} '
            f'{_f(r.get("max_ms")):>7} {_f(r["cpu_us"], ".0f"):>8} '
            f'{_f(r["recorder_cpu_us"], ".0f"):>6} '
            f'{_f(r["late_p99_ms"]):>6}')
    return lines


def _find(results, target, kind, qos, rate, duration, ok=True, priority=0):
    for r in results:
        if (r['target'], r['input'], r['qos'], r['rate'], r['duration'],
                r['priority']) == (target, kind, qos, rate, duration,
                                   priority) \
                and (r['status'] == 'ok' or not ok):
            return r
    return None


def _ratio(a, b):
    if a is None or b is None:
        return '-'
    return f'{a / b:.2f}' if b else ('1.00' if a == 0 else 'inf')


def ratios(results, nodes, kinds, qoses, rate, duration):
    """Lines comparing each node target to each baseline."""
    lines = [f'node / echo at {rate} Hz (p99 latency, CPU per tick; loss as '
             'node vs echo setpoints lost):']
    for node_target in nodes:
        for kind in kinds:
            for qos in qoses:
                node = _find(results, node_target, kind, qos, rate,
                             duration, ok=False)
                for base in BASELINES:
                    echo = _find(results, base, kind, qos, rate, duration)
                    row = f'  {node_target:9} {kind:10} {qos:11} vs ' \
                        f'{base:11}: '
                    if node is None or echo is None:
                        lines.append(row + 'missing run')
                    elif node['status'] != 'ok':
                        lines.append(row + node['status'])
                    else:
                        lines.append(row + 'p99 x' + _ratio(
                            node.get('p99_ms'), echo.get('p99_ms'))
                            + ', CPU x'
                            + _ratio(node['cpu_us'], echo['cpu_us'])
                            + f', lost {node["lost"]} vs {echo["lost"]}')
    return lines


def checks(results, nodes, args):
    """Check the targets for the trajectory input: (lines, verdicts)."""
    lines, verdicts = [], {}
    full = args.rate == TARGET_RATE and args.duration >= TARGET_DURATION
    lines.append(
        f'Target (trajectory, reliable): {TARGET_RATE} Hz sustained '
        f'for {TARGET_DURATION:g} s, loss <= echo, p99 <= 2x echo'
        + ('' if full else f' [INDICATIVE: this run is {args.rate} Hz for '
           f'{args.duration:g} s]'))
    for node_target in nodes:
        node = _find(results, node_target, 'trajectory', 'reliable',
                     args.rate, args.duration, ok=False)
        for base in BASELINES:
            echo = _find(results, base, 'trajectory', 'reliable',
                         args.rate, args.duration)
            row = f'  {node_target:9} vs {base:11}: '
            if node is None or echo is None:
                lines.append(row + 'no result')
                continue
            verdict, why = _judge(node, lambda: {
                'sustained': node['sustained'],
                'loss<=echo': node['lost'] <= echo['lost'],
                'p99<=2x': ('p99_ms' in node and 'p99_ms' in echo
                            and node['p99_ms'] <= 2 * echo['p99_ms'])})
            verdicts[f'{node_target} vs {base}'] = verdict
            lines.append(row + f'{verdict}  ({why})')
    return lines, verdicts


def _judge(node, parts):
    """
    Return (verdict, why) of one ``node`` result.

    ``parts()`` gives its named checks (called only for a result whose
    run ended ``ok``): PASS when all hold, else MISS.
    """
    if node['status'] != 'ok':
        return 'MISS', node['status']
    checks = parts()
    return ('PASS' if all(checks.values()) else 'MISS',
            ', '.join(f'{k} {"ok" if v else "NO"}' for k, v in checks.items()))


def _realtime_parts(node, echo):
    """Return the real-time checks of a node result against the echo's."""
    fifo, threads = node['fifo_threads']
    p99 = node.get('p99_ms', math.inf)
    return {
        f'p99 {p99:.2f} ms <= {RT_P99_FACTOR:g}x '
        f'{echo.get("p99_ms", math.nan):.2f}':
            p99 <= RT_P99_FACTOR * echo.get('p99_ms', 0.0),
        f'<= {RT_P99_MS:g} ms': p99 <= RT_P99_MS,
        f'loss {node["loss"]:.2%}': node['loss'] <= RT_LOSS,
        f'threads FIFO {fifo} of {threads}': fifo == threads}


def realtime_checks(results, nodes, kinds, qoses, args):
    """
    Check each node run at ``--thread-priority`` for real time.

    Against the echo-single baseline under ``chrt -f P`` in the same run:
    p99 <= RT_P99_FACTOR x its p99 and <= RT_P99_MS, loss <= RT_LOSS,
    every thread of the node SCHED_FIFO P. Returns (lines, verdicts).
    """
    priority = args.thread_priority
    lines = [f'Real-time check, {args.load} busy loop(s), client SCHED_FIFO '
             f'{args.client_priority or "off"}: node fifo {priority} p99 <= '
             f'{RT_P99_FACTOR:g}x echo-single fifo {priority} and <= '
             f'{RT_P99_MS:g} ms, loss <= {RT_LOSS:.1%}, every thread '
             'SCHED_FIFO']
    verdicts = {}
    for node_target in nodes:
        for kind in kinds:
            for qos in qoses:
                node = _find(results, node_target, kind, qos, args.rate,
                             args.duration, ok=False, priority=priority)
                echo = _find(results, 'echo-single', kind, qos, args.rate,
                             args.duration, priority=priority)
                row = f'  {node_target} {kind:10} {qos:11}: '
                if node is None or echo is None:
                    lines.append(row + 'no result')
                    continue
                verdict, why = _judge(node, lambda: _realtime_parts(
                    node, echo))
                verdicts[f'{node_target} {kind} {qos} fifo {priority}'] = \
                    verdict
                lines.append(row + f'{verdict}  ({why})')
    return lines, verdicts


def scan_lines(results, targets, kinds, qos, rates, duration):
    """Lines of the rate scan: highest sustained rate, mark per rate."""
    lines = [f'Rate scan ({qos}); sustained = loss <= '
             f'{SUSTAINED_LOSS:.1%} and p99 latency < '
             f'{SUSTAINED_P99_MS:g} ms over the run:']
    summary = {}
    for kind in kinds:
        for target in targets:
            marks, best = [], None
            for rate in rates:
                r = _find(results, target, kind, qos, rate, duration)
                if r is None:
                    marks.append(f'{rate}:failed')
                    continue
                if r['sustained']:
                    best = rate
                    marks.append(f'{rate}:ok')
                else:
                    why = [w for w, bad in (
                        ('loss', r['loss'] > SUSTAINED_LOSS),
                        ('p99', r.get('p99_ms', 1e9) >= SUSTAINED_P99_MS))
                        if bad]
                    marks.append(f'{rate}:' + '+'.join(why))
            summary[f'{target}/{kind}'] = best
            lines.append(f'  {target:11} {kind:10} highest '
                         f'{_f(best, "d"):>5} Hz   ' + ' '.join(marks))
    return lines, summary


def main():
    """Run the benchmark; return the exit code."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n')[0])
    parser.add_argument('--rate', type=int, default=TARGET_RATE,
                        help='setpoints per second (default 1000)')
    parser.add_argument('--duration', type=float, default=TARGET_DURATION,
                        help='seconds per run (default 10)')
    parser.add_argument('--inputs', default='trajectory,topics')
    parser.add_argument('--targets', default=','.join(TARGETS))
    parser.add_argument('--qos', default='reliable',
                        help='reliable and/or best_effort, comma-separated')
    parser.add_argument('--rates-scan', default='500,1000,1500,2000,3000',
                        help='rates (Hz) to scan; empty to skip the scan')
    parser.add_argument('--scan-duration', type=float,
                        help='seconds per scan run (default --duration)')
    parser.add_argument('--domain', type=int, default=200,
                        help='first ROS_DOMAIN_ID, one per target process, '
                        'wrapping within 200-230')
    parser.add_argument('--json', metavar='FILE', help='save the results')
    parser.add_argument('--load', type=int, default=0, metavar='N',
                        help='busy loops to run during the benchmark '
                        '(default 0)')
    parser.add_argument('--thread-priority', type=int, default=0,
                        metavar='P', help='also run every target at '
                        'SCHED_FIFO P (the node by its thread_priority, '
                        'the echo under chrt); 0: only as it is')
    parser.add_argument('--client-priority', type=int, default=60,
                        metavar='C', help='with --thread-priority: the '
                        'producer and the recorder at SCHED_FIFO C '
                        '(default 60; 0: normal)')
    parser.add_argument('--record', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.record:
        record(args.record, args.qos)
        return 0
    kinds = [k for k in args.inputs.split(',') if k]
    targets = [t for t in args.targets.split(',') if t]
    qoses = [q for q in args.qos.split(',') if q]
    scan = sorted({int(r) for r in args.rates_scan.split(',') if r})
    scan_duration = args.scan_duration or args.duration
    for value, allowed in ((kinds, INPUT_TOPICS),
                           (targets, NODES + tuple(EXECUTORS)),
                           (qoses, ('reliable', 'best_effort'))):
        bad = set(value) - set(allowed)
        if bad:
            parser.error(f'unknown {", ".join(sorted(bad))}')
    for name, value in (('thread-priority', args.thread_priority),
                        ('client-priority', args.client_priority)):
        if not 0 <= value <= 99:
            parser.error(f'--{name} must lie in [0, 99]')
    priorities = [0] + ([args.thread_priority] if args.thread_priority
                        else [])
    client = args.client_priority if args.thread_priority else 0
    if (args.thread_priority or client) and not granted(
            max(args.thread_priority, client)):
        parser.error('SCHED_FIFO is not granted here (CAP_SYS_NICE or an '
                     'RLIMIT_RTPRIO): see doc/deployment.md#real-time')
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'

    def say(text):
        print(text, file=sys.stderr, flush=True)

    load = os.getloadavg()
    results, group = [], 0
    with busy_loops(args.load):
        for priority in priorities:
            for qos in qoses:
                for kind in kinds:
                    for target in targets:
                        runs = [(args.rate, args.duration)]
                        if qos == qoses[0] and not priority:
                            runs += [(r, scan_duration) for r in scan
                                     if (r, scan_duration) != runs[0]]
                        domain = 200 + (args.domain - 200 + group) % 31
                        group += 1
                        results += run_group(target, kind, qos, runs, domain,
                                             say, priority, client)
    main_runs = [r for r in results if r['rate'] == args.rate
                 and r['duration'] == args.duration]
    out = [f'bench_node: {platform.node()}, {os.cpu_count()} CPUs, load '
           f'{load[0]:.2f} -> {os.getloadavg()[0]:.2f}, {args.load} busy '
           f'loop(s) started; client SCHED_FIFO {client or "off"}; recorder '
           'in its own process (EventsExecutor); latency = recorder receive '
           '- producer publish, CLOCK_MONOTONIC', '']
    out += table(main_runs)
    out += ['', 'cpu/tick: target process utime+stime / setpoints sent; '
            'rec/tk: the recorder\'s; late99: producer p99 lateness', '']
    stops = sorted({(label(r), r['stop']['target']) for r in results
                    if 'stop' in r})
    out += [f'{t} process: {how}' for t, how in stops] + ['']
    nodes = [t for t in targets if t in NODES]
    out += ratios(results, nodes, kinds, qoses, args.rate, args.duration)
    check_lines, verdicts = checks(results, nodes, args)
    out += [''] + check_lines
    if args.thread_priority:
        rt_lines, rt_verdicts = realtime_checks(results, nodes, kinds,
                                                qoses, args)
        out += [''] + rt_lines
        verdicts.update(rt_verdicts)
    summary = {}
    if scan:
        lines, summary = scan_lines(results, targets, kinds, qoses[0],
                                    scan, scan_duration)
        out += [''] + lines
        out += ['', 'Scan runs:'] + table(
            [r for r in results if r['qos'] == qoses[0]
             and r['rate'] in scan and r['duration'] == scan_duration])
    print('\n'.join(out))
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(dict(args=vars(args), cpus=os.cpu_count(),
                           python=platform.python_version(),
                           results=results, checks=verdicts,
                           scan_highest=summary), f, indent=1)
    dead = [r for r in results if r['status'] != 'ok']
    return 1 if dead else 0


if __name__ == '__main__':
    sys.exit(main())
