"""
What a reliability run must show: its outputs right, its figures in bounds.

:func:`check_outputs` checks outputs against ``mechanics.solve`` of their
setpoints; :func:`problems` lists what a run's figures break of the
bounds below; :func:`summary_lines` writes them as a report does.
"""

from collections import Counter
import math

import numpy as np

from orthoglide_ros.formats.params_file import load_robot
from orthoglide_testing.checkout import params_file
from orthoglide_testing.reliability.runs import (
    EPOCH_NS, LOSSLESS_DEPTH, RECOVERY_LIMIT, sample_at, TOL)
from orthoglide_ros.model import mechanics


def check_outputs(outputs, robot=None):
    """
    Check outputs against mechanics.solve of their setpoints.

    Returns (non-finite outputs, wrong outputs, first wrong stamp or None);
    an output is wrong when a value differs from mechanics.solve of
    :func:`sample_at` its stamp by more than 1e-9 (relative above 1).
    """
    robot = robot or load_robot(params_file())
    expected = {}
    nonfinite = wrong = 0
    first_wrong = None
    for row in outputs:
        values = row[2:11]
        if not np.isfinite(values).all():
            nonfinite += 1
            continue
        stamp = int(row[0])
        if stamp not in expected:
            s = mechanics.solve(robot, *sample_at(stamp))
            expected[stamp] = np.array(s.lambda_ + s.lambdadot + s.force)
        want = expected[stamp]
        if (np.abs(values - want) > TOL * np.maximum(1.0, np.abs(want))).any():
            wrong += 1
            if first_wrong is None:
                first_wrong = stamp
    return nonfinite, wrong, first_wrong


def match_stamps(sent, outputs):
    """Return (missing, duplicates, extra) of outputs against stamps sent."""
    counts = Counter(int(s) for s in outputs[:, 0])
    sent_set = set(int(s) for s in sent)
    missing = sum(1 for s in sent_set if s not in counts)
    duplicates = sum(c - 1 for s, c in counts.items() if s in sent_set)
    extra = sum(c for s, c in counts.items() if s not in sent_set)
    return missing, duplicates, extra


def in_epoch(outputs, epoch):
    """Return the outputs whose stamp lies in ``epoch``."""
    return outputs[(outputs[:, 0] // EPOCH_NS).astype(np.int64) == epoch]


def slope(samples):
    """Least-squares slope of (t, value) samples; 0.0 for fewer than 3."""
    if len(samples) < 3:
        return 0.0
    t, v = np.array(samples, dtype=float).T
    return float(np.polyfit(t, v, 1)[0])


def percentile(values, q):
    """Return the ``q`` th percentile of ``values``; NaN if there are none."""
    return float(np.percentile(values, q)) if len(values) else math.nan


# The node's RSS may grow by less than this during a flood, after warm-up.
# Nothing in its own state grows per setpoint (trajectory setpoints are not
# held, partial ones at most MAX_PENDING, DDS histories keep-last 10): a
# leak of 100 bytes per message received would pass 20 MB within a 10 s
# flood (~20000 messages/s here); settling after warm-up stays within a few
# MB (0.0-0.1 MB measured while the node keeps up with its producer).
RSS_GROWTH_LIMIT_MB = 20.0
# ... and not keep growing: least-squares slope after warm-up.
RSS_SLOPE_LIMIT = 0.2           # MB/s
DIAGNOSTICS_GAP_LIMIT = 2.5     # s between two statuses (period 1 s)
PARAMETER_LIMIT = 2.0           # s for the node to answer a parameter get
# Setpoint to output during a flood: keep-last 10 means a bounded backlog,
# a few ms here; a node working off a growing queue would pass 1 s at once.
LATENCY_LIMIT_MS = 1000.0
# Longest publish call of a reliable producer while the node is dead or
# starting. Fast DDS may stall one call ~0.34 s when it re-opens the dead
# node's shared-memory port (doc/deployment.md); a producer blocked by the dead
# reader would stall every call or hang.
STALL_LIMIT_MS = 500.0
STOP_LIMIT = 5.0                # s from SIGINT/SIGTERM to exit


def stalled_by(result):
    """
    Return how the machine stalled a reliable run (text), None if it did not.

    The producer runs at the run's highest priority: late by more than the
    node's input history covers (depth / rate), everything below it was
    stalled as long, and what was lost then is the machine's, not the
    node's (:func:`cases.reliable_stream` runs it again).
    """
    cover_ms = 1e3 * result['depth'] / result['rate']
    if result['late_max_ms'] > cover_ms:
        return (f'the producer was {result["late_max_ms"]:.0f} ms late, past '
                f'the {cover_ms:.0f} ms the input history covers')
    return None


def problems(result, only=None, skip=()):
    """
    Return the expectations a run's result does not meet (strings).

    Every node restart must give its first output within RECOVERY_LIMIT
    of its start. Expectations carry a tag: ``backlog`` for what a flood
    beyond the node's capacity could upset (diagnostics, parameter
    answers, memory), else ``main``; ``only`` keeps
    one tag, ``skip`` leaves tags out.
    """
    out = []

    def expect(ok, text, tag='main'):
        if not ok and tag not in skip and only in (None, tag):
            out.append(text)

    case = result['case']
    expect(result.get('crashes', 0) == 0,
           f'{result.get("crashes")} node crash(es): {result.get("exits")}')
    expect(result.get('nonfinite', 0) == 0,
           f'{result.get("nonfinite")} non-finite output(s)')
    expect(result.get('wrong', 0) == 0,
           f'{result.get("wrong")} output(s) differ from mechanics.solve '
           f'(first at stamp {result.get("first_wrong")})')
    if case == 'flood':
        expect(result['outputs'] > 0, 'no output during the flood')
        expect(result['last_output'] == result['last_sent'],
               f'last output {result["last_output"]} is not the last '
               f'setpoint sent {result["last_sent"]}')
        expect(result['increasing'], 'output stamps went back')
        expect(result['latency_max_ms'] <= LATENCY_LIMIT_MS,
               f'latency up to {result["latency_max_ms"]:.0f} ms')
        expect(result['growth_mb'] < RSS_GROWTH_LIMIT_MB,
               f'RSS grew {result["growth_mb"]:.1f} MB', 'backlog')
        expect(result['diagnostics_max_gap_s'] <= DIAGNOSTICS_GAP_LIMIT
               and result['diagnostics'] >= int(result['duration']) - 1,
               f'{result["diagnostics"]} diagnostics in '
               f'{result["duration"]:g} s, longest gap '
               f'{result["diagnostics_max_gap_s"]:.1f} s', 'backlog')
        expect(result['parameter_gets'] > 0
               and result['parameter_unanswered'] == 0
               and result['parameter_max_s'] <= PARAMETER_LIMIT,
               f'parameter gets: {result["parameter_gets"]} answered '
               f'(slowest {result["parameter_max_s"]:.2f} s), '
               f'{result["parameter_unanswered"]} unanswered', 'backlog')
        expect(result['rss_slope_mb_s'] < RSS_SLOPE_LIMIT,
               f'RSS grows {result["rss_slope_mb_s"]:.2f} MB/s', 'backlog')
        expect(result['internal_errors'] == 0,
               f'{result["internal_errors"]} internal error(s)')
    elif case == 'reliable':
        # Lossless is promised with a history covering the stalls only.
        keys = ('missing', 'duplicates', 'extra') \
            if result['depth'] >= LOSSLESS_DEPTH else ('duplicates', 'extra')
        for key in keys:
            expect(result[key] == 0, f'{result[key]} {key} output(s)')
    elif case == 'kill_restart':
        recovery = result['recovery_s']
        late = [r for r in recovery if r > RECOVERY_LIMIT]
        expect(not late, f'{len(late)}/{len(recovery)} restart(s) over '
               f'{RECOVERY_LIMIT:g} s: ' + ', '.join(f'{r:.2f}' for r in late))
        expect(result['outage_call_max_ms'] < STALL_LIMIT_MS,
               f'a publish call took {result["outage_call_max_ms"]:.0f} ms '
               'while the node was dead')
        expect(result['outage_sent'] >= 0.5 * result['outage_expected'],
               f'{result["outage_sent"]} setpoints published during the '
               f'outages, {result["outage_expected"]} due')
    elif case == 'producer_restart':
        expect(all(n >= 0 for n in result['lost']),
               f'a producer got no output through: lost {result["lost"]}')
        expect(result['internal_errors'] == 0,
               f'{result["internal_errors"]} internal error(s)')
    elif case == 'stop_mid_stream':
        for name, code, took, unclean in result['stops']:
            expect(code == 0 and took < STOP_LIMIT and not unclean,
                   f'{name}: exit code {code} after {took:.2f} s'
                   + (', FATAL or Traceback on stderr' if unclean else ''))
    return out


def _ms(value):
    return '-' if value is None or value != value else f'{value:.1f} ms'


def summary_lines(result):
    """Return a result's figures as a few lines of text."""
    case = result['case']
    if case == 'flood':
        r = result
        text = (
            f'flood {r["kind"]} {r["qos"]} {r["duration"]:g} s: '
            f'{r["sent"]} setpoints sent ({r["rate"]:.0f}/s), '
            f'{r["outputs"]} outputs; last output = last sent: '
            f'{r["last_output"] == r["last_sent"]}; lag p50 '
            f'{_ms(r["latency_p50_ms"])}, max {_ms(r["latency_max_ms"])}\n'
            f'  RSS {r["rss_warm_mb"]:.1f} MB after warm-up -> '
            f'{r["rss_end_mb"]:.1f} MB at the end (growth '
            f'{r["growth_mb"]:+.2f} MB, {r["rss_slope_mb_s"]:+.2f} MB/s, max '
            f'{r["rss_max_mb"]:.1f}); node CPU '
            f'{r["node_cpu"]:.0%} of a core; diagnostics {r["diagnostics"]} '
            f'(longest gap {r["diagnostics_max_gap_s"]:.2f} s); parameter '
            f'gets {r["parameter_gets"]} answered (slowest '
            f'{r["parameter_max_s"] * 1e3:.0f} ms), '
            f'{r["parameter_unanswered"]} unanswered')
    elif case == 'reliable':
        r = result
        text = (f'reliable {r["kind"]} {r["rate"]} Hz {r["duration"]:g} s, '
                f'input depth {r["depth"]}: '
                f'{r["sent"]} sent, {r["outputs"]} outputs, missing '
                f'{r["missing"]}, duplicates {r["duplicates"]}, extra '
                f'{r["extra"]}; node CPU {r["node_cpu"]:.0%} of a core, '
                f'a thread of it runnable but not run up to '
                f'{_ms(r["node_waited_ms"])}; '
                f'producer late up to {r["late_max_ms"]:.1f} ms, outputs '
                f'silent up to {r["silence_ms"]:.1f} ms')
    elif case == 'kill_restart':
        r = result
        times = r['recovery_s']
        text = (
            f'kill/restart x{r["cycles"]} at {r["rate"]} Hz '
            f'({r["discovery"]} discovery): first output after start '
            + ', '.join(f'{t:.2f}' for t in times) + ' s (min '
            f'{min(times):.2f}, median {float(np.median(times)):.2f}, max '
            f'{max(times):.2f})\n'
            f'  producer while the node was down ({r["outage_s"]:.1f} s): '
            f'{r["outage_sent"]} published of {r["outage_expected"]} due, '
            f'longest call {_ms(r["outage_call_max_ms"])}'
            + (' (blocked)' if r['outage_call_blocked'] else '')
            + f', max lateness {_ms(r["outage_late_max_ms"])}; while up: '
            f'longest call {_ms(r["running_call_max_ms"])}')
    elif case == 'producer_restart':
        r = result
        text = (
            f'producer restarts x{r["restarts"]} ({r["kind"]}, '
            f'{r["discovery"]} discovery, later then earlier stamps): first '
            'output after the new producer\'s start '
            + ', '.join(f'{t:.2f}' for t in r['recovery_s'])
            + f' s; outputs per producer {r["outputs_per_producer"]}, lost '
            f'{r["lost"]}, internal errors {r["internal_errors"]}')
    else:
        text = 'stop mid-stream: ' + ', '.join(
            f'{name} exit {code} in {took:.2f} s'
            + (' (FATAL/Traceback)' if unclean else '')
            for name, code, took, unclean in result['stops'])
    return text
