#!/usr/bin/env python3
"""
Run the full reliability cases of the feedforward node and print a report.

How the reliability targets are shown: the full versions of the flood, reliable,
restart and fuzz tests, with the figures doc/measurements.md quotes. The runs are
those of ``testing/orthoglide_testing/reliability`` (the tests run them
shorter):

- best-effort floods for ``--duration`` s (trajectory and topics inputs);
- a reliable stream at 1 kHz for ``--duration`` s, every setpoint matched
  to its output, with the node's input history at
  ``harness.LOSSLESS_DEPTH`` (nothing may be lost) and at the default
  keep-last 10 (the loss is measured);
- ``--cycles`` SIGKILL/restart cycles of the node at 500 Hz, with the Fast
  DDS profile ``config/fastdds_one_host.xml`` on every process (inside a
  network namespace, as root: ``testing/orthoglide_testing/netns.py``;
  reported as not done where none can be made) and with Fast DDS
  defaults;
- producer restarts (SIGKILL then SIGINT, later then earlier stamps) on
  both inputs; SIGINT and SIGTERM mid-stream;
- ``test/test_fuzz_node.py`` and ``test/test_fuzz_mechanics.py`` (when
  present) through pytest, with the ``thorough`` hypothesis profile,
  ``--hypothesis-seed`` and
  ``ORTHOGLIDE_FUZZ_EXAMPLES`` when the files read it;
- the hostile peers and stalls (``testing/orthoglide_testing/hostile``
  and ``harness.big_messages``), every node, one line each with its
  figures against the target (``--hostile-only`` runs just these).

Run it through ``scripts/reliability_report.sh`` (venv, localhost, own
domain). Exit code 1 on a hard failure (a crash, a non-finite or wrong
output, a setpoint lost under reliable QoS, a fuzz failure, a run that
could not be done), else 0; missed time or memory bounds are reported.
"""

import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
FUZZ_FILES = ('test/test_fuzz_node.py', 'test/test_fuzz_mechanics.py')
FUZZ_VARIABLE = 'ORTHOGLIDE_FUZZ_EXAMPLES'

# Before rclpy is imported (by the harness): this host, a domain of our own.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', os.environ.get(
    'ORTHOGLIDE_TEST_DOMAIN_ID', str(1 + os.getpid() % 232)))
os.environ.setdefault('ROS_LOG_DIR',
                      tempfile.mkdtemp(prefix='orthoglide-ros-log-'))

import numpy as np  # noqa: E402

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing.arguments import script_parser  # noqa: E402
from orthoglide_testing import hostile  # noqa: E402
from orthoglide_testing.hostile import logs as hostile_logs  # noqa: E402
from orthoglide_testing.hostile.streams import \
    mechanism_stamps  # noqa: E402
from orthoglide_testing import live_graph  # noqa: E402
from orthoglide_testing import netns  # noqa: E402
from orthoglide_testing import reliability as harness  # noqa: E402

use_checkout(ROOT)


def say(text):
    """Progress on stderr (the report goes to stdout)."""
    print(text, file=sys.stderr, flush=True)


def runs(args):
    """Yield (label, function, kwargs) of every harness run to do."""
    d = args.duration
    yield 'flood trajectory', harness.flood, dict(duration=d)
    yield 'flood topics', harness.flood, dict(duration=d, kind='topics')
    yield 'reliable 1 kHz', harness.reliable_stream, dict(rate=1000,
                                                          duration=d)
    yield 'reliable 1 kHz, keep-last 10', harness.reliable_stream, dict(
        rate=1000, duration=d, depth=10)
    yield 'kill/restart, profile', in_namespace, dict(
        case='kill_restart', cycles=args.cycles)
    yield 'kill/restart, default', harness.kill_restart, dict(
        cycles=args.cycles, discovery=None)
    yield 'producer restarts trajectory', harness.producer_restart, {}
    yield 'producer restarts topics', harness.producer_restart, dict(
        kind='topics')
    yield 'SIGINT/SIGTERM mid-stream', harness.stop_mid_stream, {}


def in_namespace(case, say, **kwargs):
    """Run an ``orthoglide_testing.live_graph`` case in a namespace of its own."""
    reason = netns.unavailable()
    if reason:
        raise harness.HarnessError(reason)
    return live_graph.in_namespace(case, **kwargs)


def run_fuzz(args, domain):
    """Run the fuzz test files through pytest; return a result dict."""
    files = [f for f in FUZZ_FILES if os.path.exists(os.path.join(ROOT, f))]
    if not files or args.skip_fuzz:
        return dict(case='fuzz', files=files, skipped=True)
    env = dict(os.environ, ORTHOGLIDE_TEST_DOMAIN_ID=str(domain))
    reads = [f for f in files if FUZZ_VARIABLE in open(
        os.path.join(ROOT, f)).read()]
    if reads:
        env[FUZZ_VARIABLE] = str(args.fuzz_examples)
    command = [sys.executable, '-m', 'pytest', '-q', '-p', 'no:cacheprovider',
               '--hypothesis-profile=thorough', f'--hypothesis-seed={args.seed}',
               '--hypothesis-show-statistics'] + files
    say('fuzz: ' + ' '.join(command[2:]))
    start = time.monotonic()
    proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=args.fuzz_timeout)
    out = proc.stdout + proc.stderr
    counts = {word: int(n) for n, word in re.findall(
        r'(\d+) (passed|failed|error|errors|skipped|xfailed)', out)}
    # --hypothesis-show-statistics: "400 passing, 0 failing, and 35 invalid
    # test cases" (older hypothesis: "400 passing examples, 0 failing ...").
    examples = sum(int(n) for n in re.findall(r'(\d+) passing\b', out))
    failing = sum(int(n) for n in re.findall(r'(\d+) failing\b', out))
    return dict(case='fuzz', files=files, skipped=False,
                code=proc.returncode, counts=counts, examples=examples,
                failing_examples=failing, seconds=time.monotonic() - start,
                examples_variable=reads,
                tail=out.strip().splitlines()[-15:])


def report(results, fuzz, args, elapsed):
    """Return the report's lines and whether a hard failure was seen."""
    by = {label: r for label, r in results}
    ok = [r for _, r in results if 'error' not in r]
    lines = [f'Reliability report: feedforward node, ROS_DOMAIN_ID '
             f'{os.environ["ROS_DOMAIN_ID"]}, LOCALHOST, {os.cpu_count()} '
             f'CPUs, load {os.getloadavg()[0]:.2f}, {elapsed:.0f} s', '']
    sent = sum(r.get('sent', 0) for r in ok)
    restarts = sum(len(r.get('recovery_s', ())) for r in ok)
    stops = sum(len(r.get('stops', ())) for r in ok)
    lines.append(f'cases tried: {len(results)} runs, {sent} setpoints '
                 f'streamed, {restarts} restarts (node and producer), '
                 f'{stops} signal stops'
                 + ('' if fuzz.get('skipped') else
                    f', fuzz {sum(fuzz["counts"].values())} tests with '
                    f'{fuzz["examples"]} passing hypothesis examples'))
    crashes = sum(r.get('crashes', 0) for r in ok)
    nonfinite = sum(r.get('nonfinite', 0) for r in ok)
    wrong = sum(r.get('wrong', 0) for r in ok)
    lines.append(f'crashes: {crashes} (node exits other than 0 on SIGINT/'
                 'SIGTERM, or unexpected)')
    lines.append(f'non-finite outputs: {nonfinite}; outputs differing from '
                 f'mechanics.solve: {wrong}')
    rel = by.get('reliable 1 kHz', {})
    if 'missing' in rel:
        lines.append(f'reliable 1 kHz, input depth {rel["depth"]}, '
                     f'{rel["sent"]} setpoints: lost {rel["missing"]}, '
                     f'duplicates {rel["duplicates"]}, extra {rel["extra"]}')
    shallow = by.get('reliable 1 kHz, keep-last 10', {})
    if 'missing' in shallow:
        lines.append(f'reliable 1 kHz, input depth 10 (the default), '
                     f'{shallow["sent"]} setpoints: lost '
                     f'{shallow["missing"]} (measured, not a failure: see '
                     'doc/measurements.md)')
    for label in ('flood trajectory', 'flood topics'):
        r = by.get(label, {})
        if 'growth_mb' in r:
            lines.append(
                f'{label}: memory growth {r["growth_mb"]:+.2f} MB after '
                f'warm-up ({r["rss_slope_mb_s"]:+.2f} MB/s), node CPU '
                f'{r["node_cpu"]:.0%} of a core')
    for label in ('kill/restart, profile', 'kill/restart, default'):
        r = by.get(label, {})
        if 'recovery_s' in r:
            t = r['recovery_s']
            lines.append(
                f'{label}: recovery after kill (start to first output) min '
                f'{min(t):.2f} / median {float(np.median(t)):.2f} / max '
                f'{max(t):.2f} s, {sum(x > harness.RECOVERY_LIMIT for x in t)}'
                f'/{len(t)} over {harness.RECOVERY_LIMIT:g} s')
    recovery = [x for label, r in results if label.startswith('producer')
                for x in r.get('recovery_s', ())]
    if recovery:
        lost = [n for label, r in results if label.startswith('producer')
                for n in r.get('lost', ())]
        lines.append(f'producer-restart recovery: min {min(recovery):.2f} / '
                     f'median {float(np.median(recovery)):.2f} / max '
                     f'{max(recovery):.2f} s; setpoints without output per '
                     f'stopped producer (reliable keep-last 10): {lost}')
    lines += ['', 'Runs:']
    hard = crashes or nonfinite or wrong or rel.get('missing', 1) \
        or rel.get('duplicates', 1)
    for label, r in results:
        if 'error' in r:
            lines.append(f'- {label}: NOT DONE: {r["error"]}')
            hard = True
            continue
        lines += ['- ' + line for line in
                  harness.summary_lines(r).splitlines()[:1]]
        lines += ['  ' + line for line in
                  harness.summary_lines(r).splitlines()[1:]]
        for problem in harness.problems(r):
            lines.append(f'  MISSED: {problem}')
    if fuzz.get('skipped'):
        lines.append(f'- fuzz: skipped (files present: {fuzz["files"]})')
    else:
        lines.append(
            f'- fuzz ({", ".join(fuzz["files"])}; seed {args.seed}; '
            + (f'{FUZZ_VARIABLE}={args.fuzz_examples}'
               if fuzz['examples_variable'] else 'their own example counts')
            + f'): exit {fuzz["code"]}, {fuzz["counts"]}, '
            f'{fuzz["examples"]} passing / {fuzz["failing_examples"]} '
            f'failing examples, {fuzz["seconds"]:.0f} s')
        if fuzz['code'] != 0:
            hard = True
            lines += ['    ' + line for line in fuzz['tail']]
    lines += ['', 'hard failures: ' + ('YES' if hard else 'none')]
    return lines, bool(hard)


def _parameter_requests(r):
    return (all(o.refused and o.alive and o.answers_after and o.code == 0
                for o in r.values()),
            'malformed parameter request (type 200), set and atomic: '
            + ', '.join(n + (' refused, up' if o.refused and o.alive
                             else ' FAILED') for n, o in r.items()))


def _absurd_parameters(r):
    refused = all(not ok for changes in r.runtime.values()
                  for ok, _ in changes.values())
    return (refused and all(r.alive.values()) and all(
        code == 2 for code, _ in r.startup.values()),
        f'absurd values ({", ".join(hostile.ABSURD["simulator"])}, ...): '
        f'refused at run time {refused}, nodes up {all(r.alive.values())}; '
        '-p robot.l3:=1e200 at start: exit '
        f'{[code for code, _ in r.startup.values()]}')


def _big_messages(r):
    return (r['missing'] == 0 and r['crashes'] == 0
            and r['latency_during_max'] <= r['latency_outside_max'] + 0.1,
            f'{r["attacks"]} messages of 3-16 MB on setpoint/trajectory '
            f'beside a reliable {r["rate"]} Hz stream: {r["sent"]} sent, '
            f'{r["missing"]} lost; latency max '
            f'{r["latency_outside_max"] * 1e3:.1f} ms without, '
            f'{r["latency_during_max"] * 1e3:.1f} ms during the attack (p99 '
            f'{r["latency_outside_p99"] * 1e3:.1f} / '
            f'{r["latency_during_p99"] * 1e3:.1f}); {r["rejected"]}')


def _stall_resume(r):
    worst_f = max(s.max_force for s in r.stalls.values())
    worst_v = max(s.max_speed for s in r.stalls.values())
    return (worst_f < r.max_effort and worst_v <= 2 * r.peak_speed,
            f'2 s SIGSTOP of each process of the closed loop: largest '
            f'|command| {worst_f:.0f} N (limit {r.max_effort:.0f}), largest '
            f'|lambdadot| {worst_v:.3f} m/s (trajectory peak '
            f'{r.peak_speed:.3f}); per process '
            + ', '.join(f'{n} {s.max_force:.0f} N {s.max_speed:.3f} m/s'
                        for n, s in r.stalls.items()))


def _stamps(r):
    return (r.outputs == 0 and r.good == 2,
            f'nanosec >= 1e9 on every input: {r.outputs} outputs, '
            f'{r.rejected_stamp} rejected (stamp); the same instants '
            f'written right: {r.good} of 2 served')


def _startup_signals(r):
    bad = [(t.name, t.signal, t.delay, t.code) for t in r
           if t.code != 0 or not hostile.quiet(t.stderr)]
    return (not bad, 'SIGINT/SIGTERM 0-0.3 s after the first line, every '
            f'node, and at the end of a pass: {len(r)} tries, {len(bad)} '
            f'not exit 0 quietly {bad[:3]}')


def _log_amplification(r):
    return (all(o.longest <= hostile.LOG_LINE_LIMIT for o in r.values()),
            'long text and malformed floods: longest log line '
            + ', '.join(f'{n} {o.longest} chars ({o.lines} lines)'
                        for n, o in r.items()))


def _departed_clients(r):
    return (max(r.gaps.values()) <= 0.2,
            f'{r.requests} requests then gone, x3 (simulator set and '
            '~/reset, feedforward set): longest output gap '
            + ', '.join(f'{n} {g * 1e3:.0f} ms' for n, g in r.gaps.items())
            + f'; replies dropped {r.dropped}; while the clients joined '
            '(apart): ' + ', '.join(f'{n} {g * 1e3:.0f} ms'
                                    for n, g in r.joining.items()))


def _isolated_clients(r):
    return (all(n == r.fresh for n in r.answered.values())
            and all(n == r.stalls for n in r.after_stalls.values()),
            'a TRANSIENT_LOCAL client stays: fresh clients answered '
            f'{r.answered} of {r.fresh}; after {r.stalls} 150 ms stalls '
            f'{r.after_stalls} of {r.stalls}; its requests carried out '
            f'{r.carried_out}')


def _fast_simulator(r):
    spurious = r.timeouts - 1 - r.stall_brakes - r.sender_stalls
    return (r.received == r.sent and spurious <= 0,
            'simulator rate_hz 10000, commands at 500 Hz: '
            f'{r.received}/{r.sent} taken, {max(spurious, 0)} spurious '
            f'timeouts ({r.stall_brakes} after its own stalls, '
            f'{r.sender_stalls} stalls of the sender), {r.step_rate:.0f} '
            f'steps/s, status {r.message!r}')


def _setpoint_loop(r):
    return (r.jump_p <= r.jump_p_bound and r.jump_v <= r.jump_v_bound,
            f'looping setpoint publisher, {r.passes} passes: largest step '
            f'{r.jump_p * 1e3:.3f} mm (bound {r.jump_p_bound * 1e3:.3f}), '
            f'largest velocity step {r.jump_v * 1e3:.3f} mm/s (bound '
            f'{r.jump_v_bound * 1e3:.3f})')


def _trajectory_flood(r):
    return (r.saturated == 0 and r.max_speed <= 0.5
            and r.mode == 'following' and r.final_error < 1e-3,
            f'a new joint trajectory every ms ({r.sent}), targets 0/10 mm: '
            f'{r.saturated} of {r.commands} commands saturated, largest '
            f'{r.max_force:.0f} N, {r.max_speed:.3f} m/s; {r.superseded} '
            f'superseded; then home within {r.final_error * 1e3:.3f} mm '
            f'({r.mode})')


def _absurd_values(r):
    return (r.feedforward_outputs == 0 and r.commands == 0,
            f'1e200 m/s^2, 1e300 N and m/s, 5 m: {r.feedforward_outputs} '
            f'outputs, {r.commands} commands; {r.feedforward_rejected}, '
            f'{r.controller_rejected}')


def _fast_client(label):
    def judge(r):
        return (r.code == 0 and r.after and r.lines <= int(r.seconds) + 1,
                f'{label}, one client as fast as answered: {r.answered} in '
                f'{r.seconds:.1f} s, {r.lines} log lines (said left out '
                f'{r.left_out}), the service still works {r.after}')
    return judge


def _forged_text(r):
    return (not r.not_log_lines and not r.control,
            '"\\n[FATAL] ... FORGED" as a label, a parameter value, a frame '
            f'id: {len(r.not_log_lines)} forged lines, {len(r.control)} with '
            'a control character')


def _mechanism_stamps(r):
    return (r.bad_outputs == 0 and r.stamps_out == [(0, 0), (9, 5)],
            'nanosec 2e9, negative seconds at the mechanism state '
            f'publisher: {r.bad_outputs} outputs, {r.rejected_stamp} '
            f'rejected (stamp); zero and valid stamps served {r.stamps_out}')


def hostile_cases():
    """Return the hostile-peer cases: (label, run, kwargs, judge) rows."""
    return (
        ('malformed parameter requests', hostile.malformed_parameters, {},
         _parameter_requests),
        ('absurd parameters', hostile.absurd_parameters, {},
         _absurd_parameters),
        ('big messages', harness.big_messages, {'say': say}, _big_messages),
        ('stall and resume', hostile.stall_resume, {}, _stall_resume),
        ('stamps', hostile.stamps, {}, _stamps),
        ('signals while starting', hostile.startup_signals, {},
         _startup_signals),
        ('log amplification', hostile.log_amplification, {},
         _log_amplification),
        ('departed clients', hostile.departed_clients, {}, _departed_clients),
        ('isolated clients', hostile.isolated_clients, {}, _isolated_clients),
        ('simulator at 10 kHz', hostile.fast_simulator, {}, _fast_simulator),
        ('setpoint loop', hostile.setpoint_loop, {}, _setpoint_loop),
        ('trajectory flood', hostile.trajectory_flood, {}, _trajectory_flood),
        ('absurd values', hostile.absurd_values, {}, _absurd_values),
        ('refused transitions', hostile_logs.refused_transitions, {},
         _fast_client('refused transitions')),
        ('resets', hostile_logs.resets, {}, _fast_client('resets')),
        ('forged log lines', hostile_logs.forged_text, {}, _forged_text),
        ('mechanism state stamps', mechanism_stamps, {}, _mechanism_stamps))


def hostile_report():
    """Run the hostile-peer cases; return the report's lines and a failure."""
    lines, hard = ['', 'Hostile peers and stalls:'], False
    for label, function, kwargs, judge in hostile_cases():
        say(f'{label} ...')
        try:
            ok, text = judge(function(**kwargs))
        except (hostile.HarnessError, harness.HarnessError) as error:
            ok, text = False, f'{label}: NOT DONE: {error}'
        hard = hard or not ok
        lines.append(f'- {"ok    " if ok else "MISSED"} {text}')
    return lines, hard


def main():
    """Run everything; print the report; return the exit code."""
    parser = script_parser(
        __doc__, ('--duration', 10.0, 'seconds of each flood and stream'),
        ('--cycles', 5, 'kill/restart cycles per discovery setting'),
        ('--seed', 20240404, 'hypothesis seed of the fuzz tests'),
        ('--fuzz-examples', 2000,
         f'{FUZZ_VARIABLE} when the fuzz files read it'),
        ('--fuzz-timeout', 1800.0, 'seconds the fuzz tests may take'))
    parser.add_argument('--skip-fuzz', action='store_true')
    parser.add_argument('--hostile-only', action='store_true',
                        help='run only the hostile peers and stalls')
    args = parser.parse_args()
    start = time.monotonic()
    if args.hostile_only:
        lines, hard = hostile_report()
        print('\n'.join(lines))
        return 1 if hard else 0
    results = []
    for label, function, kwargs in runs(args):
        say(f'{label} ...')
        try:
            results.append((label, function(say=say, **kwargs)))
        except harness.HarnessError as error:
            results.append((label, dict(case=label, error=str(error))))
    fuzz = run_fuzz(args, int(os.environ['ROS_DOMAIN_ID']))
    lines, hard = report(results, fuzz, args, time.monotonic() - start)
    more, worse = hostile_report()
    print('\n'.join(lines + more))
    return 1 if hard or worse else 0


if __name__ == '__main__':
    sys.exit(main())
