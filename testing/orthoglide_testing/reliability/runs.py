"""
The processes of a reliability run: the node, producers, recorders, a monitor.

:class:`Run` starts the node (its console script) and the children
(:class:`Child`: :mod:`.roles` run as a process, talking in lines on
stdout) and stops every one of them; :class:`Monitor` watches the node's
``/diagnostics`` and asks it for a parameter from this process.
"""

import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from orthoglide_testing.checkout import checkout, config_file, params_file
from orthoglide_testing.load import (client_prefix, REALTIME,
                                     realtime_args, realtime_client)
from orthoglide_testing.processes import (interrupt, start_node_process,
                                          stop_process)
from orthoglide_ros.model.trajectory import paper_sample

# The module the children run.
ROLES = 'orthoglide_testing.reliability.roles'
EPOCH_NS = 10**12               # stamps of one stream: one epoch of 1000 s
PERIOD_NS = 2 * 10**9           # eq. (6) repeats every 2 s of stamp
FLOOD_STEP_NS = 100000          # stamp step of a flood (0.1 ms)
GAP_NS = 100 * 10**6            # outputs resuming after 100 ms: "gap"
IDLE_NS = 300 * 10**6           # no output for 300 ms: "idle"
RECORD_LIMIT_NS = 3600 * 10**9  # a recorder stops by itself after 1 h
WARM_PERIOD = 0.02              # s between two warm-up setpoints
START_TIMEOUT = 30.0            # s for a process to come up and answer
TOL = 1e-9                      # relative (above 1) or absolute tolerance
# The one-host Fast DDS profile (doc/deployment.md, "One host"), by its
# name in the checkout's config/: UDP on 127.0.0.1 only, announcements
# every 0.25 s; with the range SYSTEM_DEFAULT, so only inside a network
# namespace (netns.py).
ONE_HOST_PROFILE = 'fastdds_one_host.xml'
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
# History of the node's inputs for "nothing lost" under reliable QoS
# (doc/feedforward.md's recipe): 1000 setpoints cover a 1 s stall at 1 kHz,
# past the default keep-last 10 (10 ms, which a busy machine exceeds) and
# the shared-memory transport's join stall of 0.33-0.67 s
# (doc/robustness.md#stalls; figures in doc/measurements.md#reliability).
LOSSLESS_DEPTH = 1000


class HarnessError(RuntimeError):
    """A process exited, or did not answer in time."""


def sample_at(stamp_ns):
    """Return the (position, velocity, acceleration) of a setpoint stamp."""
    return paper_sample((stamp_ns % PERIOD_NS) / 1e9)


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

    ``profile`` (a file, by its name in the checkout's ``config/`` or a
    path): the range SYSTEM_DEFAULT, which rmw_fastrtps
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
                               'namespace (orthoglide_testing.netns)')
        env[PROFILE_VARIABLE] = str(config_file(profile))
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
            [*wrap, sys.executable, '-m', ROLES, role] + args,
            cwd=checkout(), env=env, stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=self.err)
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
            ['--ros-args', '--params-file', str(params_file()),
             *realtime_args(self.realtime), *extra],
            env=env or self.env, cwd=checkout())
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
