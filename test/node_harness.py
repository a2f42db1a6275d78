"""
Helpers for the feedforward node's DDS tests: a probe node, spinning, processes.

- :class:`Probe`: a test node that publishes setpoints (pose/twist/accel or
  one trajectory point) and records every message on the node's outputs and
  on ``/diagnostics``;
- :func:`spin_until`: spin an executor until a predicate holds or time runs
  out; :func:`wait_diagnostics`: until a diagnostics message matches;
- :func:`node_graphs`: a node under test and its probe on one executor,
  matched, destroyed afterwards (the in-process tests' fixture);
- :func:`start_node_process` / :func:`stop_process`: run the node as a
  separate process and stop it the way a user does (Ctrl-C = SIGINT), then
  kill it if it does not stop; :func:`timed_stop` and
  :func:`assert_clean_exit`: it must stop promptly with code 0;
  :func:`run_to_exit`: a process expected to end by itself;
- :func:`call` and :func:`parameter_client`: services from a probe;
- :class:`Producer`, :func:`qos_profile`, :func:`cpu_seconds`: a setpoint
  producer with messages built once, for floods and benchmarks;
  :func:`busy_loops`: a loaded machine, for demos and benchmarks.

pytest puts the test directory on ``sys.path`` (the tests import it by
name); the scripts and benchmarks that reuse it insert that directory.
"""

from contextlib import contextmanager
import gc
import os
import signal
import subprocess
import sys
import tempfile
import time
from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros.cores import realtime

IDENTITY = (0.0, 0.0, 0.0, 1.0)
ZERO = (0.0, 0.0, 0.0)
# Reliable like the node; deep, so that no output is lost while a test
# spins at its own pace.
PROBE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                       reliability=ReliabilityPolicy.RELIABLE)
OUTPUTS = ('joint_states', 'forces', 'power')
STOP_TIMEOUT = 10.0     # s between SIGINT and SIGKILL
INPUT_TOPICS = {'trajectory': ('trajectory',),
                'topics': ('pose', 'twist', 'accel')}
CLK_TCK = os.sysconf('SC_CLK_TCK')
# The real-time set of the demos and the timing tests: the nodes at
# ros2_control's default priority, the process that feeds and records
# them above it (doc/deployment.md#real-time).
NODE_PRIORITY = 50
CLIENT_PRIORITY = 60
# Whether the OS grants it here: the timing tests then run their nodes
# and their recording processes at it, so that their verdicts do not
# depend on what else the machine runs.
REALTIME = realtime.granted(CLIENT_PRIORITY)


def realtime_args(on=REALTIME):
    """Return a node's arguments for NODE_PRIORITY (none if not ``on``)."""
    return ['-p', f'thread_priority:={NODE_PRIORITY}'] if on else []


def client_prefix(on=REALTIME):
    """Return the command prefix of a client process at CLIENT_PRIORITY."""
    return ['chrt', '-f', str(CLIENT_PRIORITY)] if on else []


def elevate(proc, on=REALTIME):
    """
    Put a started client process at CLIENT_PRIORITY (every thread).

    For a process whose start-up (imports, discovery: a second of CPU)
    must not preempt a real-time loop already running, as
    :func:`client_prefix` would make it.
    """
    if on:
        realtime.client(CLIENT_PRIORITY, proc.pid)


@contextmanager
def realtime_client(on=REALTIME):
    """
    Run every thread of this process at CLIENT_PRIORITY meanwhile.

    For a test or demo that records a real-time node in its own process;
    its children start at normal scheduling (:func:`realtime.client`).
    Call it once the process's DDS participant exists.
    """
    if on:
        realtime.client(CLIENT_PRIORITY)
    try:
        yield
    finally:
        if on:
            realtime.normal()


def stamp_of(seconds, base=(1000, 0)):
    """Return ``base`` + ``seconds`` as a (sec, nanosec) stamp."""
    total = base[0] * 10**9 + base[1] + round(seconds * 1e9)
    return divmod(total, 10**9)


def header_stamp(msg):
    """Return a message's header stamp as (sec, nanosec)."""
    return (msg.header.stamp.sec, msg.header.stamp.nanosec)


def diagnostic_values(msg):
    """Return ``{key: value}`` of the first status of a DiagnosticArray."""
    return {kv.key: kv.value for kv in msg.status[0].values}


class Probe(Node):
    """
    Publishes setpoints to the feedforward node and records its outputs.

    ``joint_states``, ``forces``, ``power``, ``diagnostics``: every message
    received, in order; ``arrivals``: the monotonic time (s) each joint
    state arrived. ``forces_topic`` lets a test follow a remapped topic.
    """

    def __init__(self, context, name='feedforward_probe', namespace='',
                 forces_topic='feedforward/forces'):
        super().__init__(name, namespace=namespace, context=context)
        qos = PROBE_QOS
        self.publishers_by_input = {
            'pose': self.create_publisher(PoseStamped, 'setpoint/pose', qos),
            'twist': self.create_publisher(TwistStamped, 'setpoint/twist',
                                           qos),
            'accel': self.create_publisher(AccelStamped, 'setpoint/accel',
                                           qos),
            'trajectory': self.create_publisher(
                MultiDOFJointTrajectory, 'setpoint/trajectory', qos),
        }
        self.joint_states = []
        self.arrivals = []
        self.forces = []
        self.power = []
        self.diagnostics = []
        self.subscriptions_by_output = {
            'joint_states': self.create_subscription(
                JointState, 'feedforward/joint_states', self._on_joints, qos),
            'forces': self.create_subscription(
                Float64MultiArray, forces_topic, self.forces.append, qos),
            'power': self.create_subscription(
                Float64MultiArray, 'feedforward/power', self.power.append,
                qos),
            'diagnostics': self.create_subscription(
                DiagnosticArray, '/diagnostics', self.diagnostics.append,
                qos),
        }

    def _on_joints(self, msg):
        self.joint_states.append(msg)
        self.arrivals.append(time.monotonic())

    # Sending --------------------------------------------------------------
    def send(self, stamp, position, velocity=ZERO, acceleration=ZERO,
             frame='', orientation=IDENTITY, order=('pose', 'twist', 'accel')):
        """
        Publish one setpoint as pose, twist and accel (in ``order``).

        ``stamp`` is (sec, nanosec); ``order`` may leave parts out. The
        messages are built first and published back to back with the
        garbage collector off: a full collection of this test process
        (tens of ms) between two parts would make them arrive farther
        apart than ``pairing_timeout``, which the node rightly refuses.
        """
        messages = []
        for part in order:
            if part == 'pose':
                msg = PoseStamped()
                p, q = msg.pose.position, msg.pose.orientation
                p.x, p.y, p.z = (float(v) for v in position)
                q.x, q.y, q.z, q.w = (float(v) for v in orientation)
            elif part == 'twist':
                msg = TwistStamped()
                v = msg.twist.linear
                v.x, v.y, v.z = (float(c) for c in velocity)
            else:
                msg = AccelStamped()
                a = msg.accel.linear
                a.x, a.y, a.z = (float(c) for c in acceleration)
            msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
            msg.header.frame_id = frame
            messages.append((self.publishers_by_input[part], msg))
        gc.disable()
        try:
            for publisher, msg in messages:
                publisher.publish(msg)
        finally:
            gc.enable()

    def send_trajectory(self, stamp, position, velocity=ZERO,
                        acceleration=ZERO, frame='', orientation=IDENTITY,
                        time_from_start=(0, 0), extra_points=(),
                        with_point=True, with_transform=True):
        """
        Publish one MultiDOFJointTrajectory; its first point is the setpoint.

        ``stamp`` is the header stamp (sec, nanosec); the node adds
        ``time_from_start``. A None ``velocity`` or ``acceleration`` leaves
        that list empty. ``extra_points``: (position, velocity,
        acceleration) of further points, which the node must ignore.
        """
        msg = MultiDOFJointTrajectory()
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
        msg.header.frame_id = frame
        msg.joint_names = ['platform']
        if with_point:
            first = _point(position, velocity, acceleration, orientation,
                           time_from_start, with_transform)
            msg.points = [first] + [
                _point(p, v, a, IDENTITY, time_from_start, True)
                for p, v, a in extra_points]
        self.publishers_by_input['trajectory'].publish(msg)

    # Reading --------------------------------------------------------------
    def clear(self):
        """Forget every message recorded so far."""
        for name in OUTPUTS + ('diagnostics', 'arrivals'):
            getattr(self, name).clear()

    def output_stamps(self):
        """Return the header stamps of the joint states received."""
        return [header_stamp(m) for m in self.joint_states]

    def matched(self, node=None):
        """
        Whether every input and output is matched with the node.

        ``node``, when the node runs in this process, also lets the node's
        own publishers on this probe's topics confirm that they match its
        subscriptions (``feedforward/joint_trajectory`` is not one).
        """
        if any(p.get_subscription_count() == 0
               for p in self.publishers_by_input.values()):
            return False
        if any(s.get_publisher_count() == 0
               for s in self.subscriptions_by_output.values()):
            return False
        if node is not None:
            topics = {s.topic_name
                      for s in self.subscriptions_by_output.values()}
            return all(p.get_subscription_count() > 0
                       for p in node.publishers if p.topic_name in topics)
        return True

    def handshake(self, executor, timeout=30.0, outputs=OUTPUTS):
        """
        Wait until the node answers; then forget the answers.

        For a node in another process, whose publishers cannot be asked:
        sends home setpoints on the trajectory input (stamps (1, k)) until
        every output in ``outputs`` has delivered a message. Returns the
        number of setpoints sent.
        """
        deadline = time.monotonic() + timeout
        assert spin_until(executor, self.matched, timeout), (
            'the node did not appear on the graph')
        sent = 0
        while not all(getattr(self, name) for name in outputs):
            assert time.monotonic() < deadline, (
                'the node did not answer: '
                + ', '.join(f'{n}: {len(getattr(self, n))}' for n in outputs))
            sent += 1
            self.send_trajectory((1, sent), ZERO)
            spin_until(executor, lambda: all(
                getattr(self, name) for name in outputs), 0.5)
        spin_until(executor, lambda: False, 0.1)    # drain stragglers
        self.clear()
        return sent


def _point(position, velocity, acceleration, orientation, time_from_start,
           with_transform):
    point = MultiDOFJointTrajectoryPoint()
    if with_transform:
        transform = Transform()
        t, q = transform.translation, transform.rotation
        t.x, t.y, t.z = (float(v) for v in position)
        q.x, q.y, q.z, q.w = (float(v) for v in orientation)
        point.transforms = [transform]
    for name, vector, field in (('velocities', velocity, 'linear'),
                                ('accelerations', acceleration, 'linear')):
        if vector is not None:
            twist = Twist()
            v = getattr(twist, field)
            v.x, v.y, v.z = (float(c) for c in vector)
            setattr(point, name, [twist])
    point.time_from_start.sec, point.time_from_start.nanosec = time_from_start
    return point


# Outputs are checked against mechanics.solve to this (relative above 1,
# absolute below): the node publishes the core's doubles unchanged.
TOL = 1e-9


def close(actual, expected):
    """Say whether two floats agree to TOL (relative above 1, else absolute)."""
    return abs(actual - expected) <= TOL * max(1.0, abs(expected))


def assert_vector(actual, expected, what):
    """Check three received floats against the expected 3-tuple."""
    actual = list(actual)
    assert len(actual) == 3 and all(
        close(a, e) for a, e in zip(actual, expected)), (
        f'{what}: got {actual}, expected {list(expected)}')


def spin_until(executor, predicate, timeout):
    """Spin ``executor`` until ``predicate()`` holds; return whether it did."""
    deadline = time.monotonic() + timeout
    while not predicate():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            return predicate()
        executor.spin_once(timeout_sec=min(0.05, remaining))
    return True


def wait_diagnostics(executor, messages, predicate, timeout):
    """
    Spin until a DiagnosticArray in ``messages`` satisfies ``predicate``.

    ``messages``: the list a probe appends to; ``predicate`` takes the
    first status's ``{key: value}``. Returns the first such message;
    fails the test (with the last values seen) when ``timeout`` s pass.
    """
    def found():
        return any(predicate(diagnostic_values(m)) for m in messages)
    ok = spin_until(executor, found, timeout)
    last = diagnostic_values(messages[-1]) if messages else None
    assert ok, f'no matching diagnostics; last: {last}'
    return next(m for m in messages if predicate(diagnostic_values(m)))


@contextmanager
def node_graphs(context, node_class, probe_class, ready, timeout):
    """
    Yield ``make(params=None, executor='events')`` for in-process tests.

    ``make`` builds ``node_class`` with ``params`` as parameter overrides
    and ``probe_class(context)``, adds both to an EventsExecutor (or a
    SingleThreadedExecutor for ``executor='single'``), spins until
    ``ready(probe, node)`` and returns ``SimpleNamespace(node, probe,
    executor)``. Everything made is shut down and destroyed on exit.
    """
    from rclpy.experimental import EventsExecutor
    made = []

    def make(params=None, executor='events'):
        overrides = [Parameter(k, value=v) for k, v in (params or {}).items()]
        node = node_class(context=context, parameter_overrides=overrides)
        probe = probe_class(context)
        spinner = (EventsExecutor if executor == 'events'
                   else SingleThreadedExecutor)(context=context)
        made.append((spinner, node, probe))
        spinner.add_node(node)
        spinner.add_node(probe)
        assert spin_until(spinner, lambda: ready(probe, node), timeout), (
            'probe and node did not match')
        return SimpleNamespace(node=node, probe=probe, executor=spinner)

    try:
        yield make
    finally:
        for spinner, node, probe in made:
            spinner.shutdown()
            probe.destroy_node()
            node.destroy_node()


def call(g, future, timeout=10.0):
    """Spin ``g.executor`` until a service future is done; return its result."""
    assert spin_until(g.executor, future.done, timeout), 'no service response'
    return future.result()


def parameter_client(g, node_name, timeout=10.0):
    """Return an AsyncParameterClient of ``node_name``, services ready."""
    client = AsyncParameterClient(g.probe, node_name)
    assert spin_until(g.executor, client.services_are_ready, timeout)
    return client


def spin_for(executor, seconds):
    """Spin ``executor`` for ``seconds``, whatever happens."""
    spin_until(executor, lambda: False, seconds)


def node_executable(name='feedforward'):
    """Return the console script ``name`` next to the running Python."""
    return os.path.join(os.path.dirname(sys.executable), name)


def needs_scripts(*names):
    """
    Return a pytest mark: skip unless the console scripts are installed.

    ``names`` default to the feedforward; the scripts are looked for next to
    the running Python (:func:`node_executable`).
    """
    import pytest               # the demos use this module without pytest
    missing = [name for name in names or ('feedforward',)
               if not os.path.exists(node_executable(name))]
    return pytest.mark.skipif(
        bool(missing), reason='not installed next to python: '
        + ', '.join(missing))


def start_node_process(args, env=None, command=None, cwd=None):
    """
    Start ``command`` (default: the feedforward console script) + ``args``.

    ``env`` defaults to ``os.environ`` (which conftest keeps on localhost
    and in the session's domain). Standard output and error go to temporary
    files, read back by :func:`stop_process`.
    """
    command = [node_executable()] if command is None else list(command)
    out = tempfile.TemporaryFile()
    err = tempfile.TemporaryFile()
    proc = subprocess.Popen(command + list(args),
                            env=os.environ if env is None else env,
                            cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
                            stderr=err)
    proc.output_files = (out, err)
    return proc


def interrupt(proc, timeout=STOP_TIMEOUT):
    """
    Stop ``proc`` as Ctrl-C does: SIGINT, wait ``timeout`` s, then SIGKILL.

    The one process-stopping helper of the tests, scripts and benchmarks.
    Returns True when it had exited or SIGINT stopped it, False when it
    had to be killed. Safe on a process that has already exited.
    """
    if proc.poll() is not None:
        return True
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout)
        return True
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout)
        return False


def stop_process(proc, timeout=STOP_TIMEOUT):
    """
    Stop ``proc``: SIGINT, wait ``timeout`` s, then SIGKILL (:func:`interrupt`).

    Returns (exit code, standard error text); the exit code is negative for
    a signal (-9 if it had to be killed). Safe on a process that has
    already exited, and a second call returns the first one's answer.
    """
    if getattr(proc, 'stopped', None) is not None:
        return proc.stopped
    try:
        interrupt(proc, timeout)
    finally:
        out, err = proc.output_files
        err.seek(0)
        text = err.read().decode('utf-8', 'replace')
        out.seek(0)
        text_out = out.read().decode('utf-8', 'replace')
        out.close()
        err.close()
    if text_out:
        text += '\n[stdout]\n' + text_out
    proc.stopped = (proc.returncode, text)
    return proc.stopped


def timed_stop(proc):
    """Stop ``proc`` (:func:`stop_process`); return (code, stderr, seconds)."""
    start = time.monotonic()
    code, stderr = stop_process(proc)
    return code, stderr, time.monotonic() - start


def assert_clean_exit(code, stderr, seconds, prompt):
    """Assert an exit code 0 within ``prompt`` s and no traceback."""
    assert code == 0, f'exit code {code} after SIGINT; stderr:\n{stderr}'
    assert seconds < prompt, f'took {seconds:.1f} s to exit after SIGINT'
    assert 'Traceback' not in stderr, stderr


# A busy loop that puts itself at normal scheduling first: a real-time
# parent's children inherit its policy unless it resets them.
BUSY_LOOP = ('import os; os.sched_setscheduler(0, os.SCHED_OTHER, '
             'os.sched_param(0))\nwhile True: pass')


@contextmanager
def busy_loops(count):
    """Run ``count`` busy loops (processes, normal scheduling) meanwhile."""
    procs = [subprocess.Popen([sys.executable, '-c', BUSY_LOOP],
                              stdin=subprocess.DEVNULL)
             for _ in range(count)]
    try:
        yield procs
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def add_load_options(parser):
    """Add a demo's ``--realtime`` and ``--load N`` to its ``parser``."""
    parser.add_argument('--realtime', action='store_true', help=(
        'run every thread of the loop\'s nodes SCHED_FIFO '
        f'{NODE_PRIORITY} (their thread_priority) and this '
        f'recorder SCHED_FIFO {CLIENT_PRIORITY}: '
        'doc/deployment.md#real-time'))
    parser.add_argument('--load', type=int, default=0, metavar='N',
                        help='run N busy loops meanwhile, a loaded machine '
                        '(default 0)')


def check_load_options(parser, args):
    """Refuse a negative load, or --realtime where it is not granted."""
    if args.load < 0:
        parser.error('--load must be >= 0')
    if args.realtime and not realtime.granted(CLIENT_PRIORITY):
        parser.error('--realtime: SCHED_FIFO is not granted here '
                     '(CAP_SYS_NICE or an RLIMIT_RTPRIO, '
                     'doc/deployment.md#real-time)')


def run_to_exit(args, command, timeout):
    """Start ``command`` + ``args``, wait for its exit: (code, stderr)."""
    proc = start_node_process(args, command=command)
    try:
        wait_exit(proc, timeout)
    finally:
        code, stderr = stop_process(proc)
    return code, stderr


def wait_exit(proc, timeout):
    """Wait up to ``timeout`` s for ``proc`` to exit; return its code or None."""
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        return None


# Traffic: setpoints built once, published fast ------------------------------
def qos_profile(name, depth=10):
    """Keep-last ``depth`` QoS, ``'reliable'`` or best effort."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE
                      if name == 'reliable'
                      else ReliabilityPolicy.BEST_EFFORT)


def cpu_seconds(pid):
    """Return utime + stime (s) of a process; None if it is gone."""
    try:
        with open(f'/proc/{pid}/stat') as f:
            fields = f.read().rsplit(')', 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


class Producer:
    """Publishers of one input form, with messages built once and reused."""

    def __init__(self, node, kind, qos):
        self.kind = kind
        profile = qos_profile(qos)
        if kind == 'trajectory':
            self.msg = MultiDOFJointTrajectory(
                joint_names=['G'], points=[MultiDOFJointTrajectoryPoint(
                    transforms=[Transform()], velocities=[Twist()],
                    accelerations=[Twist()])])
            self.pubs = [node.create_publisher(
                MultiDOFJointTrajectory, 'setpoint/trajectory', profile)]
            point = self.msg.points[0]
            self.vectors = (point.transforms[0].translation,
                            point.velocities[0].linear,
                            point.accelerations[0].linear)
            self.stamps = (self.msg.header.stamp,)
        else:
            self.msgs = (PoseStamped(), TwistStamped(), AccelStamped())
            self.pubs = [node.create_publisher(type(m), f'setpoint/{t}',
                                               profile)
                         for m, t in zip(self.msgs, INPUT_TOPICS[kind])]
            self.vectors = (self.msgs[0].pose.position,
                            self.msgs[1].twist.linear,
                            self.msgs[2].accel.linear)
            self.stamps = tuple(m.header.stamp for m in self.msgs)

    def matched(self):
        """Whether every input publisher has matched a subscription."""
        return all(p.get_subscription_count() > 0 for p in self.pubs)

    def fill(self, stamp_ns, sample):
        """Set the stamp and the (position, velocity, acceleration)."""
        sec, nanosec = divmod(stamp_ns, 1000000000)
        for stamp in self.stamps:
            stamp.sec, stamp.nanosec = sec, nanosec
        for vector, values in zip(self.vectors, sample):
            vector.x, vector.y, vector.z = values

    def publish(self):
        """Publish the setpoint (pose, twist, accel in that order)."""
        if self.kind == 'trajectory':
            self.pubs[0].publish(self.msg)
        else:
            for pub, msg in zip(self.pubs, self.msgs):
                pub.publish(msg)


def cartesian_message(times, positions, velocities, accelerations, stamp,
                      frame='base_link', rotations=None):
    """
    Build a MultiDOFJointTrajectory of whole Cartesian trajectory points.

    ``times`` (N,) s from the start; ``positions``, ``velocities``,
    ``accelerations``: (N, 3) arrays (m, m/s, m/s^2), a None leaving that
    list empty in every point; ``stamp`` (sec, nanosec); ``rotations``:
    None (the identity) or (N, 4) quaternions (x, y, z, w).
    """
    msg = MultiDOFJointTrajectory(joint_names=['platform'])
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    for k, t in enumerate(times):
        transform = Transform()
        p = transform.translation
        p.x, p.y, p.z = (float(c) for c in positions[k])
        q = transform.rotation
        q.x, q.y, q.z, q.w = (0.0, 0.0, 0.0, 1.0) if rotations is None \
            else (float(c) for c in rotations[k])
        point = MultiDOFJointTrajectoryPoint(transforms=[transform])
        for name, vectors in (('velocities', velocities),
                              ('accelerations', accelerations)):
            if vectors is not None:
                twist = Twist()
                v = twist.linear
                v.x, v.y, v.z = (float(c) for c in vectors[k])
                setattr(point, name, [twist])
        point.time_from_start.sec, point.time_from_start.nanosec = \
            divmod(round(float(t) * 1e9), 10**9)
        msg.points.append(point)
    return msg
