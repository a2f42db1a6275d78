"""
The feedforward in a live graph: joins, discovery, two hosts.

Every case here gives a process DDS settings other than LOCALHOST, so it
runs inside network namespaces (:mod:`.netns`): :func:`in_namespace` starts
this module as a script inside a new namespace, where it runs one case and
prints its result as one JSON line; the processes it starts inherit the
namespace (or are put in the other one of a pair with ``ip netns exec``).
The processes are :mod:`.reliability`'s: the node (its console
script), a producer and a recorder, and plain readers (``bystand``).

- :func:`joins`: the feedforward streams at 500 Hz to a recorder while
  plain participants (LOCALHOST settings) join and leave; the longest gap
  between two outputs the recorder received, per join.
- :func:`discovery`: a warm-up setpoint goes producer -> node -> recorder
  with the node and its peers on different settings (profile or plain).
- :func:`two_hosts`: the node in one namespace, the producer and the
  recorder in another, over a veth pair, with the several-host settings of
  doc/deployment.md; latency and restart time.
- ``kill_restart``: :func:`reliability.kill_restart` (the one-host
  profile is the default there).
- :func:`stall_resume`: :func:`hostile.stall_resume` on the one-host
  profile.
"""

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import time

import numpy as np

from orthoglide_testing import netns
from orthoglide_testing.checkout import checkout, use_checkout
from orthoglide_testing import reliability as rh
from orthoglide_testing.reliability.runs import (
    Child, load_outputs, ONE_HOST_PROFILE, profile_environment, Run,
    START_TIMEOUT)

# An output gap this long is the shared-memory health check's stall (ms):
# it sleeps healthy_check_timeout_ms / 3 = 333 ms; scheduling on a busy
# machine makes gaps of tens of ms, never this.
STALL_MS = 250.0
# The domain of the processes in a namespace: not the session's, whose
# processes on the host share /dev/shm (shared-memory ports are named by
# domain and participant, not by network namespace).
DOMAIN_SHIFT = 116
DISCOVERY_SERVER_PORT = 11811
CASE_TIMEOUT = 300.0    # s for one case in a namespace


def namespace_domain(domain=None):
    """Return the domain for processes in a namespace (see DOMAIN_SHIFT)."""
    domain = int(os.environ.get('ROS_DOMAIN_ID', '0') if domain is None
                 else domain)
    return (domain + DOMAIN_SHIFT) % 232 + 1


def _gaps(received, windows):
    """Return the longest gap (ms) that began in each window (ns pairs)."""
    received = np.sort(received)
    gaps = np.diff(received)
    return [float(gaps[(received[:-1] >= begin) & (received[:-1] <= end)]
                  .max(initial=0.0)) / 1e6 for begin, end in windows]


def joins(profile=ONE_HOST_PROFILE, count=8, rate=500, bystanders=3,
          participants=8, hold=0.2, late=1.2, quiet=2.0, say=None):
    """
    Stream at ``rate`` Hz while ``count`` plain participants join, one by one.

    The node (``rate_hz`` = ``rate``), a reliable producer at ``rate`` Hz
    and the recorder use ``profile`` (None: plain LOCALHOST settings, like
    everyone else); ``bystanders`` plain readers of the node's output stay
    throughout. Each joining process holds ``participants`` plain
    participants that subscribe to the node's output ``late`` s after they
    joined (as ``ros2 topic echo`` does, or a display added in RViz: their
    ports have been idle, and the node opens each when it first sends to
    it), is kept ``hold`` s after they matched, and stops.
    Returns ``join_gaps_ms`` (the longest gap between two outputs the
    recorder received that began between a joiner's start and its stop),
    ``quiet_gap_ms`` (the same over ``quiet`` s before the first join: the
    machine's own jitter), ``stalls`` (joins with a gap above STALL_MS, the
    health check's) and the outputs.
    """
    say = say or (lambda text: None)
    plain = profile_environment(None)
    result = dict(case='joins', profile=os.path.basename(profile or '')
                  or 'none', count=count, rate=rate, bystanders=bystanders)
    windows = []
    with Run(profile) as run:
        run.start_node(['-p', f'rate_hz:={float(rate)}'])
        recorder = run.start_recorder()
        producer = run.start_producer('trajectory', 'reliable', rate=rate)
        standing = [Child('bystand', [], run.workdir, plain)
                    for _ in range(bystanders)]
        run.children += standing
        run.warm_up(producer, recorder)
        for child in standing:
            child.expect('matched', START_TIMEOUT, (run.node,))
        begin = time.monotonic_ns()
        time.sleep(quiet)
        windows.append((begin, time.monotonic_ns()))
        for k in range(count):
            begin = time.monotonic_ns()
            joiner = Child('bystand', [
                '--subscribe-after', str(late), '--participants',
                str(participants)], run.workdir, plain)
            run.children.append(joiner)
            joiner.expect('matched', START_TIMEOUT, (run.node,))
            time.sleep(hold)
            joiner.stop()
            windows.append((begin, time.monotonic_ns()))
            run.node_alive()
        run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
    gaps = _gaps(outputs[:, 1], windows)
    result.update(quiet_gap_ms=gaps[0], join_gaps_ms=gaps[1:],
                  stalls=sum(g > STALL_MS for g in gaps[1:]),
                  outputs=len(outputs), crashes=run.crashes())
    say(f'joins ({result["profile"]}): longest gaps '
        + ', '.join(f'{g:.0f}' for g in gaps[1:]) + ' ms')
    return result


def discovery(node_profile, peers_profile):
    """
    Return how long a first setpoint took producer -> node -> recorder.

    The node uses ``node_profile``, the producer and the recorder
    ``peers_profile`` (either None: plain LOCALHOST). ``first_output_s``:
    from the producer's start to the first output the recorder received.
    """
    result = dict(case='discovery',
                  node='profile' if node_profile else 'plain',
                  peers='profile' if peers_profile else 'plain')
    with Run(None) as run:
        run.start_node(env=profile_environment(node_profile))
        peers = profile_environment(peers_profile)
        recorder = run.start_recorder(env=peers)
        producer = run.start_producer('trajectory', 'reliable', rate=100,
                                      env=peers)
        result['first_output_s'] = run.warm_up(producer, recorder)
        run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
    result.update(outputs=len(outputs), crashes=run.crashes())
    return result


def two_hosts(settings, other, address, rate=500, duration=3.0,
              restarts=2):
    """
    Run the node here, a producer and a recorder in namespace ``other``.

    ``settings``: the environment variables of the several-host recipe
    (doc/deployment.md) for every process; ``address``: this namespace's
    address on the link (a discovery server, when the settings name one,
    runs here). Streams ``duration`` s at ``rate`` Hz, reliable, and
    SIGKILLs and restarts the node ``restarts`` times. Returns, for the
    setpoints published before the first kill (the last 0.5 s excepted:
    in flight when it died on a busy machine), how many were ``sent`` and
    ``received`` as an
    output and their latency (publication to reception, p50 and max: both
    clocks are this machine's CLOCK_MONOTONIC); the restart times (SIGKILL
    to the first output of the new process: ``restart_s``, from its start)
    and the bytes that crossed the link.
    """
    env = dict(profile_environment(None), **settings)
    result = dict(case='two_hosts', settings=settings, rate=rate)
    server = None
    if 'ROS_DISCOVERY_SERVER' in settings:
        server = subprocess.Popen(
            [os.path.join(os.path.dirname(sys.executable),
                          'fast-discovery-server'),
             '-i', '0', '-l', address, '-p', str(DISCOVERY_SERVER_PORT)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wrap = netns.exec_prefix(other)
    link_before = netns.link_bytes()
    recoveries = []
    try:
        with Run(None) as run:
            run.env = env
            # Histories that a stalled process on a busy machine cannot
            # overrun: what is lost, the link lost.
            run.start_node(rh.lossless_args())
            recorder = run.start_recorder(wrap=wrap)
            producer = run.start_producer('trajectory', 'reliable',
                                          rate=rate, wrap=wrap)
            result['first_output_s'] = run.warm_up(producer, recorder)
            time.sleep(duration)
            first_kill = None
            for _ in range(restarts):
                killed, first = run.restart_node(recorder, producer,
                                                 extra=rh.lossless_args())
                first_kill = first_kill or killed
                recoveries.append((first - run.node_started) / 1e9)
            time.sleep(1.0)
            log = run.finish_producer(producer)
            outputs = load_outputs(recorder)
            run.stop_node()
    finally:
        if server is not None:
            server.terminate()
            server.wait(10)
    stream = rh.in_epoch(outputs, 100)
    received = dict(zip(stream[:, 0].astype(np.int64), stream[:, 1]))
    before = log[log[:, 1] < first_kill - 500 * 10**6]
    latency = np.array([received[s] - p for s, p in before[:, :2]
                        if s in received]) / 1e6
    result.update(
        sent=len(before), received=len(latency),
        latency_p50_ms=float(np.percentile(latency, 50)),
        latency_max_ms=float(latency.max()), restart_s=recoveries,
        link_bytes=netns.link_bytes() - link_before, crashes=run.crashes())
    return result


def stall_resume(**kwargs):
    """
    Run :func:`hostile.stall_resume` on the one-host profile: a dict.

    Its processes are stopped for 2 s (SIGSTOP): on shared memory a port
    whose listener stood still that long meets Fast DDS's health check
    when it is next used (robustness.md#stalls), a stall of the transport
    that is not the loop's; the one-host profile has no shared memory.
    """
    from orthoglide_testing import hostile
    os.environ.update(profile_environment(ONE_HOST_PROFILE))
    return dataclasses.asdict(hostile.stall_resume(**kwargs))


CASES = {'joins': joins, 'discovery': discovery, 'two_hosts': two_hosts,
         'kill_restart': rh.kill_restart, 'stall_resume': stall_resume}


def in_namespace(case, namespace=None, **kwargs):
    """
    Run ``case`` (a key of CASES) with ``kwargs`` in a network namespace.

    A new namespace with only its loopback unless ``namespace`` (a
    :class:`netns.Namespace`) is given. Returns the case's result (a dict);
    a HarnessError with the case's output when it failed.
    """
    env = dict(os.environ, ROS_DOMAIN_ID=str(namespace_domain()))
    command = [sys.executable, '-m', __spec__.name, str(checkout()), case,
               json.dumps(kwargs)]
    if namespace is None:
        with netns.Namespace() as ns:
            return _run(ns.command(command), env)
    return _run(namespace.command(command), env)


def _run(command, env):
    try:
        proc = subprocess.run(command, env=env, capture_output=True,
                              text=True, timeout=CASE_TIMEOUT,
                              cwd=checkout())
    except subprocess.TimeoutExpired as late:
        raise rh.HarnessError(
            f'{command[-2]} ran past {CASE_TIMEOUT:g} s:\n'
            f'{_text(late.stdout)[-2000:]}\n{_text(late.stderr)[-4000:]}'
        ) from None
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith('result '):
            return json.loads(line[len('result '):])
    raise rh.HarnessError(f'{command[-2]} failed (exit {proc.returncode}):'
                          f'\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}')


def _text(output):
    """Return a subprocess's output as text (bytes after a timeout, None)."""
    if isinstance(output, bytes):
        return output.decode(errors='replace')
    return output or ''


def _plain(value):
    """JSON for numpy scalars and tuples."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(type(value))


def main(argv=None):
    """Run one case (inside a namespace); print ``result <json>``."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('checkout', help='the repository root')
    parser.add_argument('case', choices=sorted(CASES))
    parser.add_argument('kwargs', help='keyword arguments, as JSON')
    args = parser.parse_args(argv)
    if not rh.in_own_namespace():
        parser.error('runs only inside a network namespace '
                     '(orthoglide_testing.netns)')
    use_checkout(args.checkout)
    result = CASES[args.case](**json.loads(args.kwargs))
    print('result ' + json.dumps(result, default=_plain), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
