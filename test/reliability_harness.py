"""
Cross-process reliability runs of the feedforward node (issue 4).

Shared by the tests (``test_flood.py``, ``test_restarts.py``) and by
``scripts/reliability_report.py``, which runs the same functions longer:

- :func:`flood`: a producer publishes setpoints as fast as it can;
- :func:`reliable_stream`: a producer publishes at a steady rate over
  reliable QoS and every setpoint is matched to its output;
- :func:`kill_restart`: the node is SIGKILLed mid-stream and started again;
- :func:`producer_restart`: the producer is killed or stopped and another
  one starts with later or earlier stamps;
- :func:`big_messages`: a peer sends 3-16 MB messages on the same input
  while a reliable 500 Hz stream goes on (issue 13).

Each run is four processes, so that no two share a GIL: the node (its
console script, as a user starts it), a producer and a recorder (this file
run as a script: ``produce`` / ``record``) and this process, which
orchestrates them, watches ``/diagnostics``, asks the node for a parameter
and reads its memory and CPU time from ``/proc``. The producer publishes
with ``node_harness``'s :class:`Producer` (messages built once)
on the paper trajectory: the setpoint of stamp ``s`` ns is eq. (6) at
``t = (s mod 2 s)``, so an output can be checked from its stamp alone
(:func:`sample_at`). Stamps are grouped in epochs of 1000 s
(``stamp // EPOCH_NS``): each warm-up and each stream has its own, and the
recorder says on its standard output when a new epoch first shows up, when
outputs resume after a gap and when they stop.

Every function returns a dict of figures (see :func:`summary_lines`); the
callers assert on them or print them. Every child process is stopped in a
``finally`` (SIGINT, wait, SIGKILL) and every wait is bounded.
"""

import argparse
import array
from collections import Counter
import math
import os
import resource
import select
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

from node_harness import (client_prefix, cpu_seconds, INPUT_TOPICS,
                          interrupt, Producer, realtime_args,
                          realtime_client, REALTIME,
                          qos_profile, start_node_process, stop_process)
from orthoglide_ros.model import mechanics
from orthoglide_ros.formats.params_file import load_robot
from orthoglide_ros.model.trajectory import paper_sample

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PARAMS = os.path.join(ROOT, 'config', 'orthoglide.yaml')

EPOCH_NS = 10**12               # stamps of one stream: one epoch of 1000 s
PERIOD_NS = 2 * 10**9           # eq. (6) repeats every 2 s of stamp
FLOOD_STEP_NS = 100000          # stamp step of a flood (0.1 ms)
GAP_NS = 100 * 10**6            # outputs resuming after 100 ms: "gap"
IDLE_NS = 300 * 10**6           # no output for 300 ms: "idle"
RECORD_LIMIT_NS = 3600 * 10**9  # a recorder stops by itself after 1 h
WARM_PERIOD = 0.02              # s between two warm-up setpoints
START_TIMEOUT = 30.0            # s for a process to come up and answer
TOL = 1e-9                      # relative (above 1) or absolute tolerance
NODE_ARGS = ('--ros-args', '--params-file', PARAMS)
# The one-host Fast DDS profile (doc/deployment.md, "One host"): UDP on
# 127.0.0.1 only, announcements every 0.25 s; with the range SYSTEM_DEFAULT,
# so only inside a network namespace (netns.py).
ONE_HOST_PROFILE = os.path.join(ROOT, 'config', 'fastdds_one_host.xml')
PROFILE_VARIABLE = 'FASTRTPS_DEFAULT_PROFILES_FILE'
RANGE_VARIABLE = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
RECOVERY_LIMIT = 2.0            # s from a node's start to its first output
# Producer log: stamp, publish time, call duration, lateness (ns), voluntary
# context switches during the call.
LOG_COLUMNS = 5
# A flood ends with a few setpoints at a steady pace (:func:`_tail`).
TAIL_COUNT, TAIL_PERIOD = 10, 0.01
BEST_EFFORT_INPUT = '-p', (
    'qos_overrides./setpoint/{}.subscription.reliability:=best_effort')
# Where every output must reach the recorder: a deep output queue, so that
# a stall of the recorder (a test tool) cannot lose outputs the node made.
DEEP_OUTPUT = ('-p', 'qos_overrides./feedforward/joint_states.publisher.'
               'depth:=1000')
# History of the node's inputs for "nothing lost" under reliable QoS: 100
# setpoints cover a 100 ms stall at 1 kHz. The default keep-last 10 covers
# 10 ms, and a process on two busy cores is stalled that long now and then
# (measured: 2-79 of 2001 lost in most 2 s runs at 1 kHz; 0 with 100).
LOSSLESS_DEPTH = 100


class HarnessError(RuntimeError):
    """A process exited, or did not answer in time."""


def sample_at(stamp_ns):
    """Return the (position, velocity, acceleration) of a setpoint stamp."""
    return paper_sample((stamp_ns % PERIOD_NS) / 1e9)


def rss_mb(pid):
    """Return the resident set size of a process (MB), None if it is gone."""
    try:
        with open(f'/proc/{pid}/status') as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def process_environment(pid):
    """Return the environment a process started with, as a dict."""
    with open(f'/proc/{pid}/environ', 'rb') as f:
        items = f.read().split(b'\0')
    return dict(item.decode('utf-8', 'replace').split('=', 1)
                for item in items if b'=' in item)


# Child processes: producer and recorder -----------------------------------
def _stdin_lines(buffer):
    """Return the complete lines waiting on stdin (never blocks)."""
    lines = []
    while select.select([sys.stdin.fileno()], [], [], 0.0)[0]:
        chunk = os.read(sys.stdin.fileno(), 4096)
        if not chunk:
            lines.append('eof')
            break
        buffer.extend(chunk)
        while b'\n' in buffer:
            line, _, rest = bytes(buffer).partition(b'\n')
            buffer[:] = rest
            lines.append(line.decode().strip())
    return lines


def _say(*fields):
    sys.stdout.write(' '.join(str(f) for f in fields) + '\n')
    sys.stdout.flush()


def _stop_on_sigint():
    """Make SIGINT/SIGTERM set a flag; return the flag (a one-item list)."""
    stop = [False]

    def handler(signum, frame):
        stop[0] = True

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)
    return stop


def produce(args):
    """
    Child process: warm up until ``go``, then stream setpoints; log them.

    Says ``ready`` once its publishers match the node, publishes warm-up
    setpoints (epoch ``--warm-epoch``) every 20 ms until ``go`` arrives on
    stdin, then setpoints from ``--epoch`` on: at ``--rate`` Hz (deadline
    schedule, as bench_node), or as fast as it can with rate 0 (then a
    steady tail, :func:`_tail`). Stops on
    ``stop``, SIGINT or after ``--duration`` s; waits up to 2 s for reliable
    readers to acknowledge; writes LOG_COLUMNS numbers per setpoint to
    ``--log``; says ``done count last``.
    """
    import rclpy
    from rclpy.duration import Duration
    from rclpy.signals import SignalHandlerOptions

    stop = _stop_on_sigint()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'reliability_producer_{os.getpid()}')
    producer = Producer(node, args.kind, args.qos)
    log = array.array('q')
    buffer = bytearray()
    count = 0
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not producer.matched():
            if stop[0] or time.monotonic() > deadline:
                return 1
            time.sleep(0.01)
        _say('ready')
        warm = args.warm_epoch * EPOCH_NS
        go = False
        for k in range(round(START_TIMEOUT / WARM_PERIOD)):
            if stop[0]:
                break
            lines = _stdin_lines(buffer)
            if 'eof' in lines:      # the orchestrator is gone
                break
            if 'go' in lines:
                go = 'stop' not in lines    # both read at once: stop
                break
            stamp = warm + k * 1000
            producer.fill(stamp, sample_at(stamp))
            producer.publish()
            time.sleep(WARM_PERIOD)
        if go:
            count = _stream(producer, args, log, buffer, stop)
        for pub in producer.pubs:
            pub.wait_for_all_acked(Duration(seconds=2.0))
    finally:
        with open(args.log, 'wb') as f:
            log.tofile(f)
        node.destroy_node()
        rclpy.try_shutdown()
    last = log[-LOG_COLUMNS] if count else -1
    _say('done', count, last)
    return 0


def _stream(producer, args, log, buffer, stop):
    """Publish the stream of :func:`produce`; return the setpoints sent."""
    clock, sleep = time.monotonic_ns, time.sleep
    base = args.epoch * EPOCH_NS
    step = FLOOD_STEP_NS if args.rate == 0 else round(1e9 / args.rate)
    limit = round(args.duration * 1e9)
    # Voluntary context switches of this thread: a publish call that
    # waited (blocked) rather than lost the CPU makes some. Only at a rate:
    # a flood publishes as fast as it can.
    switches = ((lambda: resource.getrusage(
        resource.RUSAGE_THREAD).ru_nvcsw) if args.rate else (lambda: 0))
    start = clock()
    i = 0
    while not stop[0]:
        deadline = start + i * step
        if args.rate:
            wait = deadline - clock()
            if wait > 0:
                sleep(wait / 1e9)
        stamp = base + i * step
        producer.fill(stamp, sample_at(stamp))
        waited = switches()
        before = clock()
        producer.publish()
        after = clock()
        log.extend((stamp, before, after - before,
                    before - deadline if args.rate else 0,
                    switches() - waited))
        i += 1
        if i % 64 == 0 or args.rate:
            if after - start >= limit or {'stop', 'eof'} & set(
                    _stdin_lines(buffer)):
                break
    if not args.rate:
        i = _tail(producer, base + i * step, log)
    return i


def _tail(producer, stamp, log):
    """
    End a flood with TAIL_COUNT setpoints TAIL_PERIOD s apart; return them.

    Best effort drops what a full transport cannot take, the flood's last
    setpoint included now and then on a busy machine: the newest setpoint
    the node must end on is sent once the flood has drained.
    """
    for k in range(TAIL_COUNT):
        time.sleep(TAIL_PERIOD)
        producer.fill(stamp, sample_at(stamp))
        before = time.monotonic_ns()
        producer.publish()
        log.extend((stamp, before, time.monotonic_ns() - before, 0, 0))
        stamp += FLOOD_STEP_NS
    return len(log) // LOG_COLUMNS


def record(args):
    """
    Child process: record every ``feedforward/joint_states`` it receives.

    Raw subscription (reliable, keep-last 1000), EventsExecutor. Says
    ``matched``; ``first t stamp`` for the first output of a new stamp
    epoch, ``gap t stamp`` for an output after 100 ms without any and
    ``idle t stamp`` (stamp of the last output) after 300 ms without any; t
    is CLOCK_MONOTONIC in ns. On SIGINT writes an (N, 11) array to
    ``--out``: stamp (ns), receive time (ns), position, velocity and effort
    (NaN where an array does not hold three values).
    """
    import rclpy
    from rclpy.experimental import EventsExecutor
    from rclpy.serialization import deserialize_message
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState

    stop = _stop_on_sigint()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'reliability_recorder_{os.getpid()}')
    received = []
    state = {'last': None, 'stamp': None, 'idle': True, 'matched': False}
    epochs = set()
    clock = time.monotonic_ns

    def on_joints(data):
        now = clock()
        received.append((now, data))
        sec, nanosec = struct.unpack_from('<iI' if data[1] else '>iI',
                                          data, 4)
        stamp = sec * 10**9 + nanosec
        epoch = stamp // EPOCH_NS
        if epoch not in epochs:
            epochs.add(epoch)
            _say('first', now, stamp)
        elif state['last'] is not None and now - state['last'] >= GAP_NS:
            _say('gap', now, stamp)
        state.update(last=now, stamp=stamp, idle=False)

    sub = node.create_subscription(
        JointState, 'feedforward/joint_states', on_joints,
        qos_profile('reliable', 1000), raw=True)

    buffer = bytearray()
    started = clock()

    def watch():
        # Stop when the orchestrator is gone (stdin closed) or after an
        # hour, whatever happens.
        if 'eof' in _stdin_lines(buffer) or \
                clock() - started > RECORD_LIMIT_NS:
            stop[0] = True
        if not state['matched'] and sub.get_publisher_count() > 0:
            state['matched'] = True
            _say('matched')
        now = clock()
        if not state['idle'] and now - state['last'] >= IDLE_NS:
            state['idle'] = True
            _say('idle', now, state['stamp'])

    node.create_timer(0.05, watch)
    executor = EventsExecutor()
    executor.add_node(node)
    try:
        while not stop[0]:
            executor.spin_once(timeout_sec=0.05)
    finally:
        rows = np.full((len(received), 11), np.nan)
        for row, (now, data) in zip(rows, received):
            msg = deserialize_message(data, JointState)
            row[0] = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
            row[1] = now
            for k, values in enumerate((msg.position, msg.velocity,
                                        msg.effort)):
                if len(values) == 3:
                    row[2 + 3 * k:5 + 3 * k] = values
        np.save(args.out, rows)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


# Orchestration ---------------------------------------------------------------
def in_own_namespace():
    """
    Whether this process runs in a namespace of the tests' (netns.py).

    Its interfaces are the loopback and the ends of the tests' veth pairs
    (``og...v``) and nothing else: no packet can leave the machine.
    """
    try:
        names = os.listdir('/sys/class/net')
    except OSError:
        return False
    return all(n == 'lo' or (n.startswith('og') and n.endswith('v'))
               for n in names)


def profile_environment(profile=None, base=None):
    """
    Return an environment for processes with the Fast DDS ``profile``.

    ``profile`` (a file): the range SYSTEM_DEFAULT, which rmw_fastrtps
    needs to keep the profile's transports, and so only inside a network
    namespace (a HarnessError elsewhere: no DDS packet leaves this host);
    None: no profile, LOCALHOST. ``base``: the environment to start from
    (default this process's).
    """
    env = dict(os.environ if base is None else base)
    env.pop(PROFILE_VARIABLE, None)
    env[RANGE_VARIABLE] = 'LOCALHOST'
    if profile:
        if not in_own_namespace():
            raise HarnessError('a Fast DDS profile with the range '
                               'SYSTEM_DEFAULT runs only inside a network '
                               'namespace (test/netns.py)')
        env[PROFILE_VARIABLE] = profile
        env[RANGE_VARIABLE] = 'SYSTEM_DEFAULT'
    return env


class Child:
    """
    A producer or recorder process, talking in lines on stdout.

    ``wrap``: a command prefix (``ip netns exec NAME``: another namespace).
    """

    def __init__(self, role, args, workdir, env, wrap=()):
        self.role = role
        self.err = tempfile.TemporaryFile(dir=workdir)
        self.started = time.monotonic_ns()
        self.proc = subprocess.Popen(
            [*wrap, sys.executable, os.path.abspath(__file__), role] + args,
            cwd=ROOT, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=self.err)
        self.lines = []
        self._buffer = b''
        self.code = None
        self.stderr = ''

    def read(self, timeout):
        """Read what stdout holds, waiting up to ``timeout`` s for it."""
        fd = self.proc.stdout.fileno()
        if select.select([fd], [], [], timeout)[0]:
            chunk = os.read(fd, 65536)
            self._buffer += chunk
            *lines, self._buffer = self._buffer.split(b'\n')
            self.lines += [line.decode().split() for line in lines]
            return bool(chunk)
        return False

    def expect(self, word, timeout, alive=(), where=lambda fields: True):
        """
        Return the fields of the first line ``word ...`` meeting ``where``.

        Raises HarnessError after ``timeout`` s, or when this process or
        one of ``alive`` (Popen objects) exits first.
        """
        deadline = time.monotonic() + timeout
        while True:
            for fields in self.lines:
                if fields and fields[0] == word and where(fields):
                    return fields
            for proc in (self.proc,) + tuple(alive):
                if proc.poll() is not None and not self.read(0.0):
                    raise HarnessError(
                        f'{self.role} waiting for {word!r}: a process '
                        f'exited with code {proc.returncode}')
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise HarnessError(f'{self.role}: no {word!r} in '
                                   f'{timeout:g} s')
            self.read(min(remaining, 0.05))

    def send(self, text):
        """Write a command line to the process's stdin (if it still runs)."""
        try:
            self.proc.stdin.write(text.encode() + b'\n')
            self.proc.stdin.flush()
        except (BrokenPipeError, ValueError):
            pass

    def stop(self, timeout=10.0):
        """SIGINT, wait, else SIGKILL; return the exit code."""
        proc = self.proc
        try:
            interrupt(proc, timeout)
        finally:
            while self.read(0.0):
                pass
            for stream in (proc.stdin, proc.stdout):
                try:
                    stream.close()
                except OSError:
                    pass
            self.err.seek(0)
            self.stderr = self.err.read().decode('utf-8', 'replace')
            self.err.close()
        self.code = proc.returncode
        return self.code


class Run:
    """
    The processes of one run; :meth:`close` stops every one of them.

    ``discovery``: a Fast DDS profile file given to every process started,
    with the range SYSTEM_DEFAULT (None: Fast DDS defaults, LOCALHOST);
    refused outside a network namespace (:func:`profile_environment`).
    ``realtime`` (default: where the OS grants it): the node runs
    SCHED_FIFO NODE_PRIORITY, the recorders, a producer at a steady rate
    and the monitor (this process) CLIENT_PRIORITY; a flood's producer
    stays at normal scheduling, so that it cannot starve what checks it.
    Records every node exit: ``exits`` is a list
    of (how, exit code), how being ``sigint`` (a code other than 0 is a
    crash), ``sigkill`` (killed on purpose) or ``unexpected`` (exited by
    itself: a crash).
    """

    def __init__(self, discovery=None, realtime=REALTIME):
        self.env = profile_environment(discovery)
        self.realtime = realtime
        self.workdir = tempfile.mkdtemp(prefix='orthoglide-reliability-')
        self.node = None
        self.node_started = None
        self.children = []
        self.exits = []
        self.node_stderr = []
        self._files = 0
        self.monitor = None

    def path(self, suffix):
        """Return a new file name in the run's directory."""
        self._files += 1
        return os.path.join(self.workdir, f'{self._files}{suffix}')

    def start_node(self, extra=(), env=None):
        """Start the node's console script (``env``: else the run's)."""
        self.node_started = time.monotonic_ns()
        self.node = start_node_process(
            list(NODE_ARGS) + realtime_args(self.realtime) + list(extra),
            env=env or self.env, cwd=ROOT)
        return self.node

    def node_alive(self):
        """Raise HarnessError if the node exited by itself."""
        if self.node is not None and self.node.poll() is not None:
            code, stderr = stop_process(self.node)
            self.exits.append(('unexpected', code))
            self.node_stderr.append(stderr)
            self.node = None
            raise HarnessError(f'the node exited by itself (code {code})')

    def kill_node(self):
        """SIGKILL the node; return the monotonic time of the kill (ns)."""
        now = time.monotonic_ns()
        self.node.kill()
        code, stderr = stop_process(self.node)
        self.exits.append(('sigkill', code))
        self.node_stderr.append(stderr)
        self.node = None
        return now

    def restart_node(self, recorder, producer, outage=0.5, extra=()):
        """
        SIGKILL the node, start it again ``outage`` s later (``extra`` args).

        Returns ``(killed, first)``: the monotonic times (ns) of the kill and
        of the first output the recorder received from the new process, once
        it did (the producer keeps streaming throughout).
        """
        killed = self.kill_node()
        time.sleep(outage)
        self.start_node(extra)
        started = self.node_started
        fields = recorder.expect('gap', START_TIMEOUT,
                                 (self.node, producer.proc),
                                 lambda f: int(f[1]) > started)
        return killed, int(fields[1])

    def stop_node(self):
        """Stop the node with SIGINT (as Ctrl-C); record its exit code."""
        if self.node is not None:
            how = 'sigint' if self.node.poll() is None else 'unexpected'
            code, stderr = stop_process(self.node)
            self.exits.append((how, code))
            self.node_stderr.append(stderr)
            self.node = None

    def start_recorder(self, env=None, wrap=()):
        """
        Start a recorder; return it (its output file is ``out``).

        ``env`` (default the run's) and ``wrap`` as for :class:`Child`.
        """
        out = self.path('.npy')
        child = Child('record', ['--out', out], self.workdir,
                      env or self.env,
                      (*wrap, *client_prefix(self.realtime)))
        child.out = out
        self.children.append(child)
        return child

    def start_producer(self, kind='trajectory', qos='reliable', rate=0,
                       epoch=100, warm_epoch=1, duration=3600.0, env=None,
                       wrap=()):
        """Start a producer; ``go`` it with :meth:`warm_up`."""
        log = self.path('.bin')
        child = Child('produce', [
            '--kind', kind, '--qos', qos, '--rate', str(rate), '--epoch',
            str(epoch), '--warm-epoch', str(warm_epoch), '--duration',
            str(duration), '--log', log], self.workdir, env or self.env,
            (*wrap, *client_prefix(self.realtime and rate > 0)))
        child.log = log
        child.warm_epoch = warm_epoch
        self.children.append(child)
        return child

    def warm_up(self, producer, recorder, timeout=START_TIMEOUT,
                ready=lambda: None):
        """
        Wait until a warm-up setpoint came back as an output, then ``go``.

        ``ready()`` is called just before ``go``. Returns the time (s) from
        the producer's start to that output.
        """
        alive = (self.node,) if self.node is not None else ()
        producer.expect('ready', timeout, alive)
        epoch = producer.warm_epoch
        fields = recorder.expect(
            'first', timeout, alive + (producer.proc,),
            lambda f: int(f[2]) // EPOCH_NS == epoch)
        ready()
        producer.send('go')
        return (int(fields[1]) - producer.started) / 1e9

    def finish_producer(self, producer, timeout=30.0):
        """Wait for ``done`` (sending ``stop`` first); return its log."""
        producer.send('stop')
        producer.expect('done', timeout)
        producer.stop()
        return producer_log(producer.log)

    def close(self):
        """Stop every process (node last, so it sees no reader vanish)."""
        try:
            for child in self.children:
                if child.code is None:
                    child.stop()
        finally:
            try:
                self.stop_node()
                if self.monitor is not None:
                    self.monitor.close()
            finally:
                shutil.rmtree(self.workdir, ignore_errors=True)

    def crashes(self):
        """Count the node exits that were crashes."""
        return sum(1 for how, code in self.exits
                   if how == 'unexpected' or (how != 'sigkill' and code != 0))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def drained(recorder, done, node):
    """
    Wait until the outputs stopped after the producer said ``done``.

    That is an ``idle`` line carrying the last stamp sent, or any ``idle``
    line said after ``done`` was read (whatever came last has come).
    """
    seen = time.monotonic_ns()
    recorder.expect('idle', START_TIMEOUT, (node,),
                    lambda f: int(f[2]) == int(done[2]) or int(f[1]) > seen)


def producer_log(path):
    """Return a producer's log as an (N, LOG_COLUMNS) int64 array."""
    return np.fromfile(path, dtype=np.int64).reshape(-1, LOG_COLUMNS)


def load_outputs(recorder):
    """Stop a recorder; return its (N, 11) array of outputs."""
    recorder.stop()
    try:
        return np.load(recorder.out)
    except (OSError, ValueError) as error:
        raise HarnessError(f'recorder wrote no outputs ({error}); '
                           f'stderr:\n{recorder.stderr[-2000:]}')


class Monitor:
    """
    An in-process node: watches ``/diagnostics``, gets node parameters.

    ``diagnostics``: (monotonic s, {key: value}) of every status received.
    """

    def __init__(self, realtime=REALTIME):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter_client import AsyncParameterClient
        from diagnostic_msgs.msg import DiagnosticArray
        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(
            f'reliability_monitor_{os.getpid()}', context=self.context)
        self.diagnostics = []
        self.node.create_subscription(
            DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)
        self.parameters = AsyncParameterClient(self.node, '/feedforward')
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._pending = None
        self._asked = -1e9
        self.answers = []           # latency (s) of each answered get
        self.unanswered = 0
        # This process at CLIENT_PRIORITY while it watches (its DDS
        # threads exist now).
        self._realtime = realtime_client(realtime)
        self._realtime.__enter__()

    def _on_diagnostics(self, msg):
        for status in msg.status:
            if status.name.startswith('feedforward'):
                self.diagnostics.append((time.monotonic(), {
                    kv.key: kv.value for kv in status.values}))

    def spin(self, seconds):
        """Spin for ``seconds``."""
        deadline = time.monotonic() + seconds
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self.executor.spin_once(timeout_sec=min(remaining, 0.05))

    def ask(self, timeout, interval=0.25):
        """
        Judge the pending get of ``rate_hz``; start one every ``interval`` s.

        A get is answered when its future completes within ``timeout`` s,
        else it is counted unanswered and forgotten.
        """
        now = time.monotonic()
        if self._pending is not None:
            future, start = self._pending
            if future.done():
                if future.result() is not None and \
                        future.result().values:
                    self.answers.append(now - start)
                else:
                    self.unanswered += 1
                self._pending = None
            elif now - start > timeout:
                self.unanswered += 1
                self._pending = None
        if self._pending is None and now - self._asked >= interval:
            self._asked = now
            self._pending = (self.parameters.get_parameters(['rate_hz']),
                             now)

    def wait_for_service(self, timeout):
        """Wait until the node's parameter services are there."""
        deadline = time.monotonic() + timeout
        while not self.parameters.services_are_ready():
            if time.monotonic() > deadline:
                raise HarnessError('no parameter services')
            self.spin(0.05)

    def latest(self, after):
        """Return the values of the first status received after ``after``."""
        for t, values in self.diagnostics:
            if t > after:
                return values
        return None

    def close(self):
        """Destroy the node and shut the context down."""
        self._realtime.__exit__(None, None, None)
        self.executor.shutdown()
        self.node.destroy_node()
        self._rclpy.try_shutdown(context=self.context)


# Checks --------------------------------------------------------------------
def check_outputs(outputs, robot=None):
    """
    Check outputs against mechanics.solve of their setpoints.

    Returns (non-finite outputs, wrong outputs, first wrong stamp or None);
    an output is wrong when a value differs from mechanics.solve of
    :func:`sample_at` its stamp by more than 1e-9 (relative above 1).
    """
    robot = robot or load_robot(PARAMS)
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


def _slope(samples):
    """Least-squares slope of (t, value) samples; 0.0 for fewer than 3."""
    if len(samples) < 3:
        return 0.0
    t, v = np.array(samples, dtype=float).T
    return float(np.polyfit(t, v, 1)[0])


def _pct(values, q):
    return float(np.percentile(values, q)) if len(values) else math.nan


# Runs ----------------------------------------------------------------------
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
            latency_p50_ms=_pct(latency, 50), latency_max_ms=float(
                latency.max()) if len(latency) else math.nan,
            nonfinite=nonfinite, wrong=wrong, first_wrong=first_wrong,
            rss_warm_mb=rss_warm, rss_end_mb=rss_end,
            rss_max_mb=max(r for _, r in rss if r is not None),
            growth_mb=rss_end - rss_warm,
            rss_slope_mb_s=_slope([r for r in rss if r[0] >= warm
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
                    say=None):
    """
    Stream at ``rate`` Hz, reliable; match every setpoint to its output.

    ``depth``: the history of the node's input subscriptions (doc/measurements.md's
    ``qos_overrides./setpoint/<input>.subscription.depth``); the producer
    keeps its own keep-last 10.
    """
    say = say or (lambda text: None)
    result = dict(case='reliable', kind=kind, rate=rate, duration=duration,
                  depth=depth)
    with Run() as run:
        node = run.start_node(lossless_args(kind, depth))
        recorder = run.start_recorder()
        producer = run.start_producer(kind, 'reliable', rate=rate, epoch=100,
                                      duration=duration)
        run.warm_up(producer, recorder)
        cpu_start = cpu_seconds(node.pid)
        done = producer.expect('done', duration + START_TIMEOUT, (node,))
        cpu_end = cpu_seconds(node.pid)
        drained(recorder, done, node)
        log = run.finish_producer(producer)
        outputs = load_outputs(recorder)
        run.stop_node()
        stream = in_epoch(outputs, 100)
        missing, duplicates, extra = match_stamps(log[:, 0], stream)
        nonfinite, wrong, first_wrong = check_outputs(outputs)
        result.update(
            sent=len(log), outputs=len(stream), missing=missing,
            duplicates=duplicates, extra=extra, nonfinite=nonfinite,
            wrong=wrong, first_wrong=first_wrong,
            late_p99_ms=_pct(log[:, 3], 99) / 1e6,
            node_cpu=(cpu_end - cpu_start) / duration)
    result.update(crashes=run.crashes(), exits=run.exits)
    say(f'reliable {rate} Hz: {result["sent"]} sent, {result["missing"]} '
        f'missing, {result["duplicates"]} duplicates')
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


def attack(args):
    """
    Child process: publish the attack messages raw, round robin.

    Says ``ready`` once matched; on ``go`` publishes one message every
    1/--rate s until ``stop`` or --duration; says ``done count``.
    """
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    stop = _stop_on_sigint()
    payloads = attack_payloads()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'hostile_attacker_{os.getpid()}')
    pub = node.create_publisher(MultiDOFJointTrajectory,
                                'setpoint/trajectory',
                                qos_profile('reliable', 1))
    buffer = bytearray()
    count = 0
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while pub.get_subscription_count() == 0:
            if stop[0] or time.monotonic() > deadline:
                return 1
            time.sleep(0.01)
        _say('ready')
        while not stop[0]:
            lines = _stdin_lines(buffer)
            if 'go' in lines or 'eof' in lines:
                break
            time.sleep(0.01)
        start = time.monotonic()
        while not stop[0] and time.monotonic() - start < args.duration:
            if {'stop', 'eof'} & set(_stdin_lines(buffer)):
                break
            pub.publish(payloads[count % len(payloads)][1])
            count += 1
            time.sleep(1.0 / args.rate)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    _say('done', count)
    return 0


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


# Expectations ---------------------------------------------------------------
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
                f'{r["extra"]}; node CPU {r["node_cpu"]:.0%} of a core')
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


def _status_after(monitor, moment, timeout=5.0):
    """Return the first diagnostics values received after ``moment``."""
    deadline = time.monotonic() + timeout
    while monitor.latest(moment) is None and time.monotonic() < deadline:
        monitor.spin(0.1)
    return monitor.latest(moment) or {}


def bystand(args):
    """
    Child process: ``--participants`` participants that read one topic.

    Each (an rclpy context of its own, as a process of several nodes has
    with several contexts) subscribes to ``--topic`` (reliable, keep-last
    10; by default the node's ``feedforward/joint_states``: the node sends
    it every output) ``--subscribe-after`` s after it saw the node
    ``feedforward`` in the graph (said: ``joined``), as ``ros2 topic echo``
    or a display added in RViz does. Says ``matched`` once every
    subscription matched a publisher, spins until ``stop``, stdin closes
    or SIGINT, and says ``done count``.
    """
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState

    stop = _stop_on_sigint()
    nodes, executors = [], []
    for k in range(args.participants):
        context = Context()
        rclpy.init(context=context,
                   signal_handler_options=SignalHandlerOptions.NO)
        nodes.append(rclpy.create_node(f'bystander_{os.getpid()}_{k}',
                                       context=context))
        executors.append(SingleThreadedExecutor(context=context))
        executors[-1].add_node(nodes[-1])
    count = [0]

    def on_joints(data):
        count[0] += 1
    buffer = bytearray()
    subs, joined, matched = [], None, False
    try:
        while not stop[0] and not {'stop', 'eof'} & set(
                _stdin_lines(buffer)):
            for executor in executors:
                executor.spin_once(timeout_sec=0.005)
            if joined is None and 'feedforward' in nodes[0].get_node_names():
                joined = time.monotonic()
                _say('joined')
            if not subs and joined is not None and \
                    time.monotonic() - joined >= args.subscribe_after:
                subs = [node.create_subscription(
                    JointState, args.topic, on_joints,
                    qos_profile('reliable', 10), raw=True) for node in nodes]
            if subs and not matched and all(
                    sub.get_publisher_count() for sub in subs):
                matched = True
                _say('matched')
    finally:
        for executor, node in zip(executors, nodes):
            context = node.context
            executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown(context=context)
    _say('done', count[0])
    return 0


def main(argv=None):
    """Entry point of the child processes: produce, record, attack..."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('role', choices=('produce', 'record', 'attack',
                                         'bystand'))
    parser.add_argument('--kind', default='trajectory',
                        choices=tuple(INPUT_TOPICS))
    parser.add_argument('--qos', default='reliable')
    parser.add_argument('--rate', type=float, default=0.0)
    parser.add_argument('--epoch', type=int, default=100)
    parser.add_argument('--warm-epoch', type=int, default=1)
    parser.add_argument('--duration', type=float, default=3600.0)
    parser.add_argument('--log')
    parser.add_argument('--out')
    parser.add_argument('--topic', default='feedforward/joint_states')
    parser.add_argument('--subscribe-after', type=float, default=0.0)
    parser.add_argument('--participants', type=int, default=1)
    args = parser.parse_args(argv)
    return {'produce': produce, 'record': record, 'attack': attack,
            'bystand': bystand}[args.role](args)


if __name__ == '__main__':
    sys.exit(main())
