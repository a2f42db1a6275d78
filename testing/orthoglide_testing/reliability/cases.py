"""
The reliability cases: floods, a reliable stream, big messages, restarts.

Each starts a :class:`runs.Run`, plays its case and returns a dict of
figures (:func:`checks.summary_lines` writes them).
"""

import math
import signal
import time

import numpy as np

from orthoglide_testing.messages import INPUT_TOPICS
from orthoglide_testing.processes import (cpu_seconds, rss_mb, stop_process,
                                          waited_ms)
from orthoglide_testing.reliability.checks import (
    check_outputs, in_epoch, match_stamps, percentile, slope, stalled_by)
from orthoglide_testing.reliability.runs import (
    BEST_EFFORT_INPUT, Child, DEEP_OUTPUT, drained, HarnessError,
    load_outputs, LOSSLESS_DEPTH, Monitor, ONE_HOST_PROFILE, producer_log,
    Run, START_TIMEOUT)
from orthoglide_testing.verdicts import ATTEMPTS, first_unspoiled


def flood(duration, kind='trajectory', qos='best_effort', say=None):
    """
    Flood the node for ``duration`` s; watch it; check its outputs.

    The node's inputs are overridden to ``qos`` (keep-last 10 as is). The
    node's RSS is sampled every 0.5 s: ``rss_warm_mb`` after 20 % of the
    flood (at most 2 s), ``rss_end_mb`` at its end. A parameter get is
    asked once it answered or after 2 s.
    """
    say = say or (lambda text: None)
    result = dict(case='flood', kind=kind, qos=qos, duration=duration)
    with Run() as run:
        extra = []
        if qos == 'best_effort':
            for topic in INPUT_TOPICS[kind]:
                extra += [BEST_EFFORT_INPUT[0],
                          BEST_EFFORT_INPUT[1].format(topic)]
        node = run.start_node(extra)
        recorder = run.start_recorder()
        producer = run.start_producer(kind, qos, rate=0, epoch=100,
                                      duration=duration)
        run.monitor = monitor = Monitor(run.realtime)
        run.warm_up(producer, recorder, ready=lambda: (
            monitor.wait_for_service(START_TIMEOUT), monitor.spin(0.5)))
        start = time.monotonic()
        cpu_start = cpu_seconds(node.pid)
        rss, warm = [], min(0.2 * duration, 2.0)
        rss_warm = None
        next_sample = start
        while producer.proc.poll() is None:
            now = time.monotonic()
            if now > start + duration + START_TIMEOUT:
                raise HarnessError('the producer did not stop')
            if now >= next_sample:
                rss.append((now - start, rss_mb(node.pid)))
                if rss_warm is None and now - start >= warm:
                    rss_warm = rss[-1][1]
                next_sample += 0.5
            monitor.ask(2.0)
            monitor.spin(0.05)
            run.node_alive()
            if producer.read(0.0) and any(
                    f[0] == 'done' for f in producer.lines):
                break
        end = time.monotonic()
        cpu_end = cpu_seconds(node.pid)
        rss_end = rss_mb(node.pid)
        if rss_warm is None:
            rss_warm = rss[0][1]
        done = producer.expect('done', START_TIMEOUT, (node,))
        drained(recorder, done, node)
        after = _status_after(monitor, end)
        log = run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
        diag = [t for t, _ in monitor.diagnostics if start <= t <= end]
        gaps = np.diff([start] + diag + [end])
        stream = in_epoch(outputs, 100)
        stamps = stream[:, 0]
        latency = (stream[:, 1] - log[np.searchsorted(
            log[:, 0], stamps).clip(0, len(log) - 1), 1]) / 1e6
        nonfinite, wrong, first_wrong = check_outputs(outputs)
        result.update(
            sent=len(log), rate=len(log) / max(end - start, 1e-9),
            outputs=len(stream), last_sent=int(log[-1, 0]) if len(log)
            else None,
            last_output=int(stamps[-1]) if len(stamps) else None,
            increasing=bool(np.all(np.diff(stamps) > 0)),
            latency_p50_ms=percentile(latency, 50), latency_max_ms=float(
                latency.max()) if len(latency) else math.nan,
            nonfinite=nonfinite, wrong=wrong, first_wrong=first_wrong,
            rss_warm_mb=rss_warm, rss_end_mb=rss_end,
            rss_max_mb=max(r for _, r in rss if r is not None),
            growth_mb=rss_end - rss_warm,
            rss_slope_mb_s=slope([r for r in rss if r[0] >= warm
                                  and r[1] is not None]),
            diagnostics=len(diag), diagnostics_max_gap_s=float(gaps.max()),
            parameter_gets=len(monitor.answers),
            parameter_max_s=max(monitor.answers, default=math.nan),
            parameter_unanswered=monitor.unanswered,
            node_cpu=(cpu_end - cpu_start) / (end - start),
            internal_errors=int(after.get('internal errors', -1)))
    result.update(crashes=run.crashes(), exits=run.exits)
    say(f'flood {kind} {qos}: {result["sent"]} sent, '
        f'{result["outputs"]} outputs')
    return result


def lossless_args(kind='trajectory', depth=LOSSLESS_DEPTH):
    """
    Return the node's arguments for "nothing lost" under reliable QoS.

    ``depth`` setpoints of history on each input of ``kind`` (doc/measurements.md's
    ``qos_overrides./setpoint/<input>.subscription.depth``) and DEEP_OUTPUT.
    """
    return DEEP_OUTPUT + tuple(
        arg for topic in INPUT_TOPICS[kind] for arg in (
            '-p', f'qos_overrides./setpoint/{topic}.subscription.depth:='
            f'{depth}'))


def reliable_stream(rate, duration, kind='trajectory', depth=LOSSLESS_DEPTH,
                    say=None, attempts=ATTEMPTS):
    """
    Stream at ``rate`` Hz, reliable; match every setpoint to its output.

    ``depth``: the history of the node's input subscriptions (doc/measurements.md's
    ``qos_overrides./setpoint/<input>.subscription.depth``); the producer
    keeps its own keep-last 10. A run in which the producer, the run's
    highest priority, was itself late by more than that history covers
    measured a stalled machine, not the node (:func:`checks.stalled_by`):
    it is run again, ``attempts`` runs at most, the last returned.
    """
    say = say or (lambda text: None)

    def once():
        result = _reliable_once(rate, duration, kind, depth)
        say(f'reliable {rate} Hz: {result["sent"]} sent, '
            f'{result["missing"]} missing, {result["duplicates"]} duplicates')
        return result
    return first_unspoiled(once, stalled_by, lambda result, stalled, attempt: say(
        f'reliable {rate} Hz: {stalled}, run {attempt} of {attempts}'),
        attempts)


def _reliable_once(rate, duration, kind, depth):
    """One run of :func:`reliable_stream`: its result."""
    result = dict(case='reliable', kind=kind, rate=rate, duration=duration,
                  depth=depth)
    with Run() as run:
        node = run.start_node(lossless_args(kind, depth))
        recorder = run.start_recorder()
        producer = run.start_producer(kind, 'reliable', rate=rate, epoch=100,
                                      duration=duration)
        run.warm_up(producer, recorder)
        cpu_start, waits_start = cpu_seconds(node.pid), waited_ms(node.pid)
        done = producer.expect('done', duration + START_TIMEOUT, (node,))
        cpu_end, waits_end = cpu_seconds(node.pid), waited_ms(node.pid)
        drained(recorder, done, node)
        log = run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
        stream = in_epoch(outputs, 100)
        missing, duplicates, extra = match_stamps(log[:, 0], stream)
        nonfinite, wrong, first_wrong = check_outputs(outputs)
        received = np.sort(stream[:, 1]) if len(stream) else np.zeros(1)
        result.update(
            sent=len(log), outputs=len(stream), missing=missing,
            duplicates=duplicates, extra=extra, nonfinite=nonfinite,
            wrong=wrong, first_wrong=first_wrong,
            late_p99_ms=percentile(log[:, 3], 99) / 1e6,
            late_max_ms=float(log[:, 3].max(initial=0)) / 1e6,
            silence_ms=float(np.diff(received).max(initial=0)) / 1e6,
            node_cpu=(cpu_end - cpu_start) / duration,
            node_waited_ms=max((waits_end[tid] - waits_start[tid]
                                for tid in waits_end.keys() & waits_start),
                               default=None))
    result.update(crashes=run.crashes(), exits=run.exits)
    return result


# Messages a hostile peer sends on setpoint/trajectory: (label, bytes).
ATTACKS = ('names 8 MB', 'XCDR2 16 MB', 'names 3.8 MB', 'XCDR2 3.4 MB')


def attack_payloads():
    """
    Return the serialized attack messages (label, bytes) of ATTACKS.

    Legal MultiDOFJointTrajectory messages made long by their joint names
    (the node reads them one by one); the XCDR2 ones carry the CDR2_LE
    encapsulation, which the fast reader does not know (the node would
    hand them to rclpy's deserializer). Two exceed the input's 4 MiB
    limit, two stay just under it.
    """
    from rclpy.serialization import serialize_message
    from trajectory_msgs.msg import MultiDOFJointTrajectory
    payloads = []
    for label, count, width in zip(ATTACKS, (1_000_000, 1_000_000, 480_000,
                                             210_000), (1, 9, 1, 9)):
        data = bytearray(serialize_message(MultiDOFJointTrajectory(
            joint_names=['j' * width] * count)))
        if label.startswith('XCDR2'):
            data[1] = 0x07      # CDR2_LE
        payloads.append((label, bytes(data)))
    return payloads


def big_messages(rate=500, duration=6.0, attack_rate=4.0, say=None):
    """
    Stream reliably at ``rate`` Hz; send 3-16 MB messages on the same input.

    The producer streams for ``duration`` s; the attacker sends
    :data:`ATTACKS` round robin at
    ``attack_rate`` Hz during the middle third. Every setpoint is matched
    to its output: latency = reception by the recorder - publication.
    Returns the setpoints lost, the latency (p99, max) of the setpoints
    published outside and during the attack, the attack messages sent and
    the node's ``rejected`` counters.
    """
    say = say or (lambda text: None)
    result = dict(case='big messages', rate=rate, duration=duration,
                  attack_rate=attack_rate)
    # A second of the stream in the input's history: a stall of the machine
    # (half a second seen with one core busy) delays setpoints but loses
    # none, so that a loss or a delay is the attack's alone.
    deep_input = ('-p', 'qos_overrides./setpoint/trajectory.subscription.'
                  f'depth:={rate}')
    with Run() as run:
        run.monitor = Monitor(run.realtime)
        node = run.start_node(DEEP_OUTPUT + deep_input)
        recorder = run.start_recorder()
        producer = run.start_producer('trajectory', 'reliable', rate=rate,
                                      epoch=100, duration=duration)
        attacker = Child('attack', ['--rate', str(attack_rate),
                                    '--duration', str(duration / 3)],
                         run.workdir, run.env)
        run.children.append(attacker)
        attacker.expect('ready', START_TIMEOUT, (node,))
        run.warm_up(producer, recorder)
        began = time.monotonic_ns()
        time.sleep(duration / 3)
        attacker.send('go')
        attack_start = time.monotonic_ns()
        done_attack = attacker.expect('done', duration + START_TIMEOUT,
                                      (node,))
        attack_end = time.monotonic_ns()
        done = producer.expect('done', duration + START_TIMEOUT, (node,))
        drained(recorder, done, node)
        log = run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.monitor.spin(0.3)       # what waited in its queue: old
        status = _status_after(run.monitor, time.monotonic())
        run.node_alive()
        run.stop_node()
        stream = in_epoch(outputs, 100)
        missing, duplicates, extra = match_stamps(log[:, 0], stream)
        received = dict(zip(stream[:, 0].astype(np.int64), stream[:, 1]))
        latency = np.array([received.get(stamp, np.nan) - published
                            for stamp, published in log[:, :2]]) / 1e9
        during = (log[:, 1] >= attack_start) & (log[:, 1] <= attack_end)
        outside = ~during & (log[:, 1] >= began)
        result.update(
            sent=len(log), missing=missing, duplicates=duplicates,
            attacks=int(done_attack[1]),
            latency_outside_p99=float(np.nanpercentile(latency[outside], 99)),
            latency_outside_max=float(np.nanmax(latency[outside])),
            latency_during_p99=float(np.nanpercentile(latency[during], 99)),
            latency_during_max=float(np.nanmax(latency[during])),
            rejected={k: v for k, v in status.items()
                      if k.startswith('rejected') and v != '0'},
            internal_errors=int(status.get('internal errors', -1)))
    result.update(crashes=run.crashes(), exits=run.exits)
    say(f'big messages: {result["sent"]} sent, {result["missing"]} missing, '
        f'{result["attacks"]} attack messages')
    return result


def kill_restart(cycles, rate=500, running=1.0, outage=0.5,
                 discovery=ONE_HOST_PROFILE, say=None):
    """
    SIGKILL the node ``cycles`` times mid-stream; restart it after ``outage``.

    A reliable producer (keep-last 10, as the node's input) streams at
    ``rate`` Hz throughout; every process uses the Fast DDS profile
    ``discovery`` (None: Fast DDS defaults). ``recovery_s``: per restart,
    the time from the new process's Popen (imports included) to the first
    output the recorder received from it. ``outage_*``: the producer while
    the node was dead or starting (kill to first output): setpoints sent
    against ``rate`` times the outage, longest publish call and largest
    lateness, next to ``running_*`` while the node ran.
    """
    say = say or (lambda text: None)
    result = dict(case='kill_restart', cycles=cycles, rate=rate,
                  discovery='profile' if discovery else 'default')
    recoveries, windows = [], []
    with Run(discovery) as run:
        run.start_node()
        recorder = run.start_recorder()
        producer = run.start_producer('trajectory', 'reliable', rate=rate,
                                      epoch=100)
        run.warm_up(producer, recorder)
        for cycle in range(cycles):
            time.sleep(running)
            run.node_alive()
            killed, first = run.restart_node(recorder, producer, outage)
            recoveries.append((first - run.node_started) / 1e9)
            windows.append((killed, first))
            say(f'kill/restart {cycle + 1}/{cycles} ({result["discovery"]} '
                f'discovery): first output {recoveries[-1]:.2f} s after '
                'start')
        time.sleep(running)
        log = run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
    down = np.zeros(len(log), dtype=bool)
    for begin, end in windows:
        down |= (log[:, 1] >= begin) & (log[:, 1] <= end)
    nonfinite, wrong, first_wrong = check_outputs(outputs)
    calls, late = log[:, 2] / 1e6, log[:, 3] / 1e6
    outage_s = sum(end - begin for begin, end in windows) / 1e9
    result.update(
        recovery_s=recoveries, sent=len(log), outputs=len(outputs),
        nonfinite=nonfinite, wrong=wrong, first_wrong=first_wrong,
        outage_s=outage_s, outage_sent=int(down.sum()),
        outage_expected=round(outage_s * rate),
        outage_call_max_ms=float(calls[down].max()) if down.any()
        else math.nan,
        outage_call_blocked=bool(down.any() and log[down][
            np.argmax(calls[down]), 4] > 0),
        outage_late_max_ms=float(late[down].max()) if down.any()
        else math.nan,
        running_call_max_ms=float(calls[~down].max()),
        running_late_max_ms=float(late[~down].max()),
        crashes=run.crashes(), exits=run.exits)
    return result


def stop_mid_stream(signals=('SIGINT', 'SIGTERM'), rate=1000, running=0.5,
                    say=None):
    """
    Stop the node with each of ``signals`` while setpoints stream in.

    The node is started again after each stop (and stopped at the end). Per
    signal: (name, exit code, seconds to exit, whether its standard error
    holds ``FATAL`` or ``Traceback``); a clean stop is (name, 0, < 5,
    False).
    """
    say = say or (lambda text: None)
    stops = []
    with Run() as run:
        run.start_node()
        recorder = run.start_recorder()
        producer = run.start_producer('trajectory', 'reliable', rate=rate)
        run.warm_up(producer, recorder)
        for name in signals:
            time.sleep(running)
            run.node_alive()
            began = time.monotonic()
            run.node.send_signal(getattr(signal, name))
            code, stderr = stop_process(run.node)
            took = time.monotonic() - began
            run.exits.append((name.lower(), code))
            run.node_stderr.append(stderr)
            run.node = None
            stops.append((name, code, took, 'FATAL' in stderr
                          or 'Traceback' in stderr))
            say(f'{name} mid-stream: exit code {code} after {took:.2f} s')
            run.start_node()
            recorder.expect('gap', START_TIMEOUT, (run.node,),
                            lambda f: int(f[1]) > run.node_started)
        run.finish_producer(producer)
        run.stop_node()
    return dict(case='stop_mid_stream', stops=stops, crashes=run.crashes(),
                unclean=sum(1 for stop in stops if stop[3]),
                stderr=[line for e in run.node_stderr
                        for line in e.splitlines()
                        if line.strip() and not line.startswith('[INFO]')])


# (stream epoch, how the previous producer is stopped) per restart; the
# first producer streams epoch 100.
RESTARTS = ((200, 'sigkill', 'later'), (50, 'sigint', 'earlier'))


def producer_restart(kind='trajectory', rate=500, running=1.0,
                     restarts=RESTARTS, discovery=None, say=None):
    """
    Replace the producer mid-stream, without restarting the node.

    Per restart: the previous producer is SIGKILLed or stopped with SIGINT,
    a new one (a new participant) streams stamps later or earlier than the
    previous one's. ``recovery_s``: from the new producer's start to the
    first output of its warm-up (``discovery`` as for :func:`kill_restart`,
    default: Fast DDS defaults). Every output must equal mechanics.solve of
    its setpoint; ``lost``: per producer that said how many it sent, the
    setpoints without an output; ``internal_errors`` is the node's count
    afterwards.
    """
    say = say or (lambda text: None)
    result = dict(case='producer_restart', kind=kind, rate=rate,
                  discovery='profile' if discovery else 'default')
    recoveries, lost = [], []
    with Run(discovery) as run:
        node = run.start_node(DEEP_OUTPUT)
        recorder = run.start_recorder()
        run.monitor = monitor = Monitor(run.realtime)
        epochs = [100] + [epoch for epoch, _, _ in restarts]
        how = [None] + [stop for _, stop, _ in restarts]
        logs = []
        for k, epoch in enumerate(epochs):
            producer = run.start_producer(kind, 'reliable', rate=rate,
                                          epoch=epoch, warm_epoch=1 + k)
            recovery = run.warm_up(producer, recorder)
            if k:
                recoveries.append(recovery)
                say(f'producer restart {k} ({restarts[k - 1][2]} stamps): '
                    f'first output {recovery:.2f} s after start')
            monitor.spin(running)
            run.node_alive()
            stop = how[k + 1] if k + 1 < len(how) else 'finish'
            if stop == 'sigkill':
                producer.proc.kill()
                producer.stop()
                logs.append(None)
            elif stop == 'sigint':
                producer.stop()
                logs.append(producer_log(producer.log))
            else:
                logs.append(run.finish_producer(producer))
        recorder.expect('idle', START_TIMEOUT, (node,))
        final = _status_after(monitor, time.monotonic())
        outputs = load_outputs(recorder)
        run.stop_node()
    for epoch, log in zip(epochs, logs):
        stream = in_epoch(outputs, epoch)
        if log is not None:
            lost.append(match_stamps(log[:, 0], stream)[0])
        if not len(stream):
            lost.append(-1)     # no output at all for that producer
    nonfinite, wrong, first_wrong = check_outputs(outputs)
    result.update(
        recovery_s=recoveries, restarts=len(restarts),
        outputs_per_producer=[len(in_epoch(outputs, e)) for e in epochs],
        lost=lost, nonfinite=nonfinite, wrong=wrong, first_wrong=first_wrong,
        internal_errors=int(final.get('internal errors', -1)),
        crashes=run.crashes(), exits=run.exits)
    return result


def _status_after(monitor, moment, timeout=5.0):
    """Return the first diagnostics values received after ``moment``."""
    deadline = time.monotonic() + timeout
    while monitor.latest(moment) is None and time.monotonic() < deadline:
        monitor.spin(0.1)
    return monitor.latest(moment) or {}
