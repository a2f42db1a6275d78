"""
Hostile peers and stalls against the installed nodes (issue 13).

Shared by ``test_hostile_peers.py`` and ``scripts/reliability_report.py``.
Every case starts the nodes from their console scripts (as ``ros2 run``
does), plays the peer from this process or from a child process of its own
(this file run as a script: ``burst``), and returns a dict of figures that
the tests assert on and the report prints:

- :func:`malformed_parameters`: set-parameters requests whose value type
  is not a ParameterType, to every node;
- :func:`absurd_parameters`: ``robot.l3 = 1e200`` and friends, at run time
  and at start-up;
- :func:`stamps`: a nanosecond field >= 1e9 on every input of the
  feedforward;
- :func:`startup_signals`: SIGINT and SIGTERM while a node starts;
- :func:`log_amplification`: long text inside messages, and a flood of
  malformed ones;
- :func:`departed_clients`: 100 requests from a client that then leaves;
- :func:`fast_simulator`: the simulator at 10 kHz with commands at 500 Hz;
- :func:`stall_resume`: the closed loop, one process stopped for 2 s;
- :func:`setpoint_loop`: the looping setpoint publisher's way back;
- :func:`trajectory_flood`: a new joint trajectory every millisecond to
  the tracking controller (issue 16);
- :func:`absurd_values`: finite but absurd values (1e200, 1e300, 5 m) on
  the inputs of the feedforward and the controller (issue 16).

(Big messages on an input are ``reliability_harness.big_messages``: they
need its producer and recorder.) Every child process is stopped in a
``finally``; every wait is bounded.
"""

import argparse
from dataclasses import dataclass
import math
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import rclpy
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter_client import AsyncParameterClient
from rclpy.serialization import serialize_message

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterValue
from rcl_interfaces.srv import (GetParameters, SetParameters,
                                SetParametersAtomically)
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import (JointTrajectory, JointTrajectoryPoint,
                                 MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from node_harness import (node_executable, qos_profile, realtime_args,
                          realtime_client, REALTIME, start_node_process,
                          stop_process)
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PARAMS = os.path.join(ROOT, 'config', 'orthoglide.yaml')
NODES = ('feedforward', 'simulator', 'tracking_controller',
         'setpoint_publisher')
START_TIMEOUT = 20.0    # s for nodes to appear and answer
LOG_LINE_LIMIT = 10000  # characters: the longest log line accepted
HOLD = mechanics.solve(Robot(), (0.0, 0.0, 0.0)).force   # N, at home


class HarnessError(RuntimeError):
    """A case could not run (a node did not start, a peer failed)."""


# What each case saw: named results, one dataclass per case ------------------
@dataclass
class Refusal:
    """One node under :func:`malformed_parameters`."""

    answered: bool          # both requests got a response
    refused: bool           # every result unsuccessful, naming the request
    reasons: list
    answers_after: bool = False     # get_parameters answered afterwards
    alive: bool = False
    code: int = None        # exit code of the stop
    stderr: str = ''


@dataclass
class AbsurdParameters:
    """:func:`absurd_parameters`: per node, per parameter, what happened."""

    runtime: dict           # node -> {parameter: (successful, reason)}
    alive: dict             # node -> alive after the requests
    startup: dict           # node -> (exit code, stderr) of -p l3:=1e200


@dataclass
class Stamps:
    """:func:`stamps`: outputs of the bad and of the good instants."""

    outputs: int            # for the bad ones: should be 0
    good: int               # for the same instants written right
    rejected_stamp: int
    alive: bool


@dataclass
class Signalled:
    """One try of :func:`startup_signals`."""

    name: str
    signal: str
    delay: float            # s after the first line (or the summary)
    code: int
    stderr: str


@dataclass
class Logged:
    """One node under :func:`log_amplification`."""

    alive: bool
    code: int
    lines: int              # stderr lines
    longest: int            # characters of the longest
    counters: dict          # the non-zero 'rejected ...' diagnostics


@dataclass
class Departed:
    """:func:`departed_clients`: the longest gap of each output stream."""

    requests: int
    bursts: tuple
    gaps: dict              # stream -> s, while requests were handled
    joining: dict           # stream -> s, while a client joined (apart)
    seconds: float
    client_exits: list
    dropped: dict           # node -> replies dropped (client gone)
    alive: dict


@dataclass
class FastSimulator:
    """:func:`fast_simulator`: commands taken and the status said."""

    received: int
    sent: int
    timeouts: int           # one is the brake after the last command
    level: int
    message: str
    step_rate: float
    alive: bool


@dataclass
class SetpointLoop:
    """:func:`setpoint_loop`: the largest jumps and what the motion allows."""

    samples: int
    span: float
    passes: int
    jump_p: float
    jump_p_bound: float
    jump_v: float
    jump_v_bound: float
    peak_speed: float


@dataclass
class Stall:
    """One stalled process of :func:`stall_resume`."""

    max_force: float        # N, from the stall's start to its end + after
    max_speed: float        # m/s
    commands: int
    trips: int
    stall_holds: int
    mode: str


@dataclass
class Stalls:
    """:func:`stall_resume`: each stalled process and the bounds."""

    peak_speed: float       # the trajectory's own, m/s
    force_limit: float
    stalls: dict            # process -> Stall
    alive: dict             # process -> every node alive after


# A peer in this process ------------------------------------------------------
class Peer:
    """
    An rclpy node in this process, spun by a thread of its own.

    ``record(topic, kind)`` keeps ``(monotonic s, message)`` of a topic;
    ``diagnostics[name]`` the newest ``{key: value}`` and level per node.
    ``realtime``: this process at CLIENT_PRIORITY while it records (the
    timing cases). Use it as a context manager.
    """

    def __init__(self, name='hostile_peer', realtime=False):
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.records = {}
        self.diagnostics = {}
        self.lock = threading.Lock()
        self.node.create_subscription(DiagnosticArray, '/diagnostics',
                                      self._on_diagnostics,
                                      qos_profile('reliable', 100))
        self._stop = False
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()
        self._realtime = realtime_client(realtime)
        self._realtime.__enter__()

    def _spin(self):
        while not self._stop and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:   # shutting down
                if self._stop:
                    return
                raise

    def _on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                node = status.name.split(':')[0]
                self.diagnostics[node] = (
                    status.level[0] if isinstance(status.level, bytes)
                    else status.level, status.message,
                    {kv.key: kv.value for kv in status.values},
                    time.monotonic())

    def record(self, topic, kind, depth=1000):
        """Record every message of ``topic``: a list of (time, message)."""
        log = self.records.setdefault(topic, [])

        def on_message(msg):
            log.append((time.monotonic(), msg))
        self.node.create_subscription(kind, topic, on_message,
                                      qos_profile('reliable', depth))
        return log

    def publisher(self, kind, topic, depth=10):
        """Return a reliable publisher of ``kind`` on ``topic``."""
        return self.node.create_publisher(kind, topic,
                                          qos_profile('reliable', depth))

    def status(self, node, after=None, timeout=5.0):
        """
        Return ``(level, message, values)`` of ``node``'s diagnostics.

        The first received after the monotonic time ``after`` (default:
        now), waiting up to ``timeout`` s; None if none came.
        """
        after = time.monotonic() if after is None else after
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                found = self.diagnostics.get(node)
            if found is not None and found[3] > after:
                return found[:3]
            time.sleep(0.05)
        return None

    def call(self, srv_type, name, request, timeout=10.0):
        """Call a service; return its response (None: no answer)."""
        client = self.node.create_client(srv_type, name)
        try:
            if not client.wait_for_service(timeout_sec=timeout):
                return None
            future = client.call_async(request)
            deadline = time.monotonic() + timeout
            while not future.done() and time.monotonic() < deadline:
                time.sleep(0.01)
            return future.result() if future.done() else None
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node, parameters, timeout=10.0):
        """Set ``{name: value}`` on ``node``; return the results."""
        client = AsyncParameterClient(self.node, node)
        if not client.wait_for_services(timeout_sec=timeout):
            return None
        from rclpy.parameter import Parameter
        future = client.set_parameters(
            [Parameter(k, value=v) for k, v in parameters.items()])
        deadline = time.monotonic() + timeout
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        return future.result().results if future.done() else None

    def wait(self, predicate, timeout):
        """Wait until ``predicate()`` holds; return whether it did."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                return predicate()
            time.sleep(0.02)
        return True

    def close(self):
        """Stop spinning, destroy the node, shut the context down."""
        self._realtime.__exit__(None, None, None)
        self._stop = True
        self._thread.join(5.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Nodes:
    """
    Node processes started from their console scripts; all stopped.

    ``realtime``: every node at NODE_PRIORITY (the timing cases).
    """

    def __init__(self, realtime=False):
        self.processes = {}
        self.results = {}
        self.realtime = realtime

    def start(self, name, *args, params=True):
        """Start ``name`` with ``args`` (after ``--ros-args``)."""
        extra = ['--params-file', PARAMS] if params else []
        self.processes[name] = start_node_process(
            ['--ros-args', *extra, *realtime_args(self.realtime), *args],
            command=[node_executable(name)])
        return self.processes[name]

    def alive(self, name):
        """Whether the process still runs."""
        return self.processes[name].poll() is None

    def stop(self, name):
        """Stop one (SIGINT); keep and return (exit code, stderr)."""
        self.results[name] = stop_process(self.processes.pop(name))
        return self.results[name]

    def close(self):
        """Stop every process still running."""
        for name in list(self.processes):
            self.stop(name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _running(peer, names, timeout=START_TIMEOUT):
    """Wait until every node answers get_parameters; raise if not."""
    for name in names:
        answer = peer.call(GetParameters, f'/{name}/get_parameters',
                           GetParameters.Request(names=['use_sim_time']),
                           timeout)
        if answer is None:
            raise HarnessError(f'{name} did not answer')


def _handshake(peer, publish, arrived, timeout=START_TIMEOUT, every=0.05):
    """
    ``publish(k)`` every ``every`` s until ``arrived()``; return how many.

    A reliable writer matches its reader before the reader matches the
    writer, and a volatile reader drops what came before: the first
    message whose effect is seen proves the path. A HarnessError after
    ``timeout`` s.
    """
    deadline = time.monotonic() + timeout
    sent = 0
    while True:
        publish(sent)
        sent += 1
        if peer.wait(arrived, every):
            return sent
        if time.monotonic() > deadline:
            raise HarnessError('no message went through')


def _counter(peer, node, key):
    """Return a counter of ``node``'s newest diagnostics (-1: none yet)."""
    with peer.lock:
        found = peer.diagnostics.get(node)
    return int(found[2].get(key, -1)) if found else -1


def _lines(text):
    """Return the log lines of a stderr text (stdout part included)."""
    return [line for line in text.splitlines() if line.strip()]


# 1. Malformed parameter requests ----------------------------------------------
def malformed_parameters(type_code=200):
    """
    Send SetParameters and SetParametersAtomically with a bad value type.

    To each node (the setpoint publisher looping, so that it stays up).
    Returns per node: ``refused`` (every result unsuccessful, the reason
    naming the malformed request), ``answers_after`` (get_parameters still
    answered), ``alive`` after 1 s, ``code`` and ``stderr`` of the stop.
    """
    bad = ParameterMsg(name='rate_hz',
                       value=ParameterValue(type=type_code,
                                            double_value=1.0))
    result = {}
    with Nodes() as nodes, Peer() as peer:
        for name in NODES:
            nodes.start(name, *(('-p', 'loop:=true') if name ==
                                'setpoint_publisher' else ()))
        _running(peer, NODES)
        for name in NODES:
            single = peer.call(SetParameters, f'/{name}/set_parameters',
                               SetParameters.Request(parameters=[bad]))
            atomic = peer.call(
                SetParametersAtomically,
                f'/{name}/set_parameters_atomically',
                SetParametersAtomically.Request(parameters=[bad]))
            results = ([] if single is None else list(single.results)) + (
                [] if atomic is None else [atomic.result])
            result[name] = Refusal(
                answered=single is not None and atomic is not None,
                refused=len(results) == 2 and all(
                    not r.successful and 'malformed' in r.reason
                    for r in results),
                reasons=[r.reason for r in results])
        time.sleep(1.0)
        for name in NODES:
            result[name].answers_after = peer.call(
                GetParameters, f'/{name}/get_parameters',
                GetParameters.Request(names=['use_sim_time']),
                5.0) is not None
            result[name].alive = nodes.alive(name)
        for name in NODES:
            result[name].code, result[name].stderr = nodes.stop(name)
    return result


# 2. Absurd parameter values ---------------------------------------------------
ABSURD = {
    'feedforward': {'robot.l3': 1e200, 'robot.m5': 1e300,
                    'robot.gravity': [1e200, 0.0, 0.0]},
    'simulator': {'robot.l3': 1e200, 'initial_position': [1e200, 0.0, 0.0],
                  'robot.gravity': [0.0, 0.0, -1e200]},
}


def absurd_parameters():
    """
    Huge but finite values: refused at run time, exit 2 at start-up.

    Returns ``runtime[node][parameter] = (successful, reason)``,
    ``alive[node]`` after the requests, ``startup[node] = (code, stderr)``
    for ``-p robot.l3:=1e200``.
    """
    runtime, alive, startup = {}, {}, {}
    with Nodes() as nodes, Peer() as peer:
        for name in ABSURD:
            nodes.start(name)
        _running(peer, ABSURD)
        for name, changes in ABSURD.items():
            runtime[name] = {}
            for key, value in changes.items():
                results = peer.set_parameters(name, {key: value})
                runtime[name][key] = (None, 'no answer') if results is None \
                    else (results[0].successful, results[0].reason)
        time.sleep(0.5)
        for name in ABSURD:
            alive[name] = nodes.alive(name)
    for name in ABSURD:
        with Nodes() as nodes:
            proc = nodes.start(name, '-p', 'robot.l3:=1e200')
            try:
                proc.wait(START_TIMEOUT)
            except Exception:
                pass
            startup[name] = nodes.stop(name)
    return AbsurdParameters(runtime, alive, startup)


# 5. Stamps -------------------------------------------------------------------
def stamps():
    """
    Send setpoints whose nanosec is >= 1e9 on every input; count outputs.

    The same instants written correctly are sent too. Returns ``outputs``
    (joint states received for the bad ones: should be 0), ``good``
    (for the good ones: 2), ``rejected_stamp`` from the diagnostics and
    ``received`` per input.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward', '-p', 'setpoint_timeout:=10.0')
        outputs = peer.record('feedforward/joint_states', JointState)
        pubs = {name: peer.publisher(kind, f'setpoint/{name}') for name, kind
                in (('pose', PoseStamped), ('twist', TwistStamped),
                    ('accel', AccelStamped),
                    ('trajectory', MultiDOFJointTrajectory))}
        _running(peer, ('feedforward',))

        def topics(sec, nanosec):
            for name, kind in (('pose', PoseStamped), ('twist', TwistStamped),
                               ('accel', AccelStamped)):
                msg = kind()
                if name == 'pose':
                    msg.pose.orientation.w = 1.0
                msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
                pubs[name].publish(msg)

        def point(header, offset):
            pubs['trajectory'].publish(_setpoint('', header, offset))

        # Both forms reach the node (stamps older than the test's).
        _handshake(peer, lambda k: point((1, k), (0, 0)), lambda: outputs)
        shaken = len(outputs)
        _handshake(peer, lambda k: topics(2, k),
                   lambda: len(outputs) > shaken)
        shaken = len(outputs)
        topics(100, 1_500_000_000)          # = 101.5 s, written wrong
        point((200, 2_000_000_000), (0, 0))     # header wrong
        point((300, 0), (0, 1_000_000_000))     # offset wrong
        point((0, 1_000_000_000), (0, 0))   # "zero" sec, wrong nanosec
        peer.wait(lambda: _counter(peer, 'feedforward', 'rejected stamp')
                  >= 6, START_TIMEOUT)
        bad = len(outputs) - shaken
        topics(101, 500_000_000)            # the same instant, written right
        point((400, 5), (1, 999_999_999))
        peer.wait(lambda: len(outputs) >= shaken + bad + 2, 5.0)
        return Stamps(outputs=bad, good=len(outputs) - shaken - bad,
                      rejected_stamp=_counter(peer, 'feedforward',
                                              'rejected stamp'),
                      alive=nodes.alive('feedforward'))


def _setpoint(frame, stamp=(5, 0), offset=(0, 0)):
    """Return a one-point MultiDOFJointTrajectory at home, at rest."""
    msg = MultiDOFJointTrajectory(points=[MultiDOFJointTrajectoryPoint(
        transforms=[Transform()], velocities=[Twist()],
        accelerations=[Twist()])])
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    point = msg.points[0]
    point.transforms[0].rotation.w = 1.0
    point.time_from_start.sec, point.time_from_start.nanosec = offset
    return msg


# 6. Signals while starting ----------------------------------------------------
def catches_sigterm(pid):
    """Whether process ``pid`` has a handler for SIGTERM (its SigCgt)."""
    try:
        with open(f'/proc/{pid}/status') as status:
            for line in status:
                if line.startswith('SigCgt:'):
                    return bool(int(line.split()[1], 16)
                                & (1 << (signal.SIGTERM - 1)))
    except OSError:
        pass
    return False


def startup_signals(delays=(0.0, 0.05, 0.15, 0.3), names=NODES,
                    signals=('SIGINT', 'SIGTERM'),
                    exit_delays=(0.0, 0.005, 0.02, 0.05)):
    """
    Signal a node ``delay`` s after the package's first line ran.

    That moment is when the console script installs its SIGTERM handler
    (seen in ``/proc/<pid>/status``): from there on, through the imports
    (about 0.3 s), rclpy's start and the node's construction, a signal must
    give exit code 0 and nothing on stderr. (Python's own start-up, before
    the package's code, is not the package's to guard.) Returns a list of
    ``(name, signal, delay, code, stderr)``; the last entries are the
    setpoint publisher (``duration`` 0.3 s) signalled ``exit_delays`` s
    after its end-of-pass summary, while it exits by itself.
    """
    outcomes = []
    for name in names:
        for signame in signals:
            for delay in delays:
                proc = start_node_process(['--ros-args'],
                                          command=[node_executable(name)])
                outcomes.append(Signalled(name, signame, delay, *_signalled(
                    proc, signame, delay, lambda p: catches_sigterm(p.pid))))
    for signame in signals:
        for delay in exit_delays:
            proc = start_node_process(
                ['--ros-args', '-p', 'duration:=0.3', '-p',
                 'start_delay:=0.0'],
                command=[node_executable('setpoint_publisher')])
            outcomes.append(Signalled(
                'setpoint_publisher end of pass', signame, delay,
                *_signalled(proc, signame, delay, _summary_written)))
    return outcomes


def _summary_written(proc):
    """Whether the setpoint publisher logged its end-of-pass summary."""
    err = proc.output_files[1]
    err.seek(0)
    return b']: published ' in err.read()


def _signalled(proc, signame, delay, ready):
    """
    Send ``signame`` ``delay`` s after ``ready(proc)``; ``(code, stderr)``.

    ``ready`` is polled every 0.5 ms, for START_TIMEOUT s at most.
    """
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not ready(proc) and time.monotonic() < deadline:
            time.sleep(0.0005)
        time.sleep(delay)
        proc.send_signal(getattr(signal, signame))
        try:
            proc.wait(10.0)
        except subprocess.TimeoutExpired:
            pass                    # stop_process ends it
    finally:
        code, stderr = stop_process(proc)
    return code, stderr


def quiet(stderr):
    """Whether a stopped node's stderr holds nothing but INFO lines."""
    return all(line.startswith('[INFO]') or line == '[stdout]'
               for line in _lines(stderr))


# 7. Log amplification ---------------------------------------------------------
def log_amplification():
    """
    Long text in messages; malformed floods: log lines stay short and few.

    The feedforward gets a trajectory point whose frame_id is 60,000
    characters (under its input's byte limit: rejected ``frame``) and one
    of 5 MB (``oversize``); the tracking controller a joint state of 4,000
    names without its joints (``missing_joint``), one of 100,000 names
    (``oversize``) and 500 malformed byte strings in 1 s. Returns the
    longest stderr line of each node, its line count and the counters.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward')
        nodes.start('tracking_controller')
        setpoints = peer.publisher(MultiDOFJointTrajectory,
                                   'setpoint/trajectory')
        measured = peer.publisher(JointState, 'joint_states')
        outputs = peer.record('feedforward/joint_states', JointState)
        _running(peer, ('feedforward', 'tracking_controller'))
        _handshake(peer, lambda k: setpoints.publish(_setpoint('', (1, k))),
                   lambda: outputs)
        _handshake(peer, lambda k: measured.publish(JointState(
            name=['unknown'], position=[0.0])), lambda: _counter(
            peer, 'tracking_controller', 'rejected measured missing_joint')
            > 0)
        for frame in ('f' * 60000, 'g' * 5_000_000):
            setpoints.publish(_setpoint(frame))
        for count in (4000, 100000):
            state = JointState(name=[f'joint_{i}' for i in range(count)])
            measured.publish(state)
        # Both queues keep 10 messages: the big one must have reached the
        # node and been taken before the flood, or the flood pushes it out
        # (a loaded machine took longer than 10 flood messages to send it).
        measured.wait_for_all_acked(Duration(seconds=START_TIMEOUT))
        peer.wait(lambda: peer.diagnostics.get('tracking_controller', (
            None, None, {}))[2].get('rejected measured oversize', '0') != '0',
            START_TIMEOUT)
        good = serialize_message(JointState(name=['a'], position=[1.0]))
        for i in range(500):
            measured.publish(good[:8 + i % 16] + b'\xff' * (i % 7))
            time.sleep(0.002)
        # Taken and counted (at least the 400 the test asks for).
        peer.wait(lambda: int(peer.diagnostics.get('tracking_controller', (
            None, None, {}))[2].get('rejected measured malformed', '0'))
            >= 400, START_TIMEOUT)
        status = {name: peer.status(name, timeout=3.0) for name in
                  ('feedforward', 'tracking_controller')}
        result = {}
        for name in ('feedforward', 'tracking_controller'):
            alive = nodes.alive(name)
            code, stderr = nodes.stop(name)
            lines = _lines(stderr)
            values = status[name][2] if status[name] else {}
            result[name] = Logged(
                alive=alive, code=code, lines=len(lines),
                longest=max((len(line) for line in lines), default=0),
                counters={k: v for k, v in values.items()
                          if k.startswith('rejected') and v != '0'})
        return result


# 8. Departed clients ----------------------------------------------------------
def departed_clients(requests=100):
    """
    Let clients send ``requests`` requests each, then leave at once.

    The simulator publishes its held state every step (1 kHz) and the
    feedforward its newest result at ``rate_hz`` 500 (a looping setpoint
    publisher keeps it fresh); three bursts from child processes, one after
    the other: parameter sets to the simulator, ``~/reset`` to the
    simulator, parameter sets to the feedforward. Each child says when its
    requests begin (it has found the service: its participant has joined).

    Returns, for each stream, the longest gap (s) between the stamps of
    two consecutive outputs that began while requests were being sent,
    answered or dropped (``gaps``: from a child's first request to the next
    child's start, and after the last child until its requests' replies
    are over), and apart from it the longest gap that began while a child
    was joining the graph (``joining``: its start-up and discovery, before
    any request; a participant joining can stall a node by itself,
    doc/robustness.md). The stamps say when a node published, whatever
    delays this recording process: the simulator stamps each state with
    its step's time, the feedforward each output with its setpoint's.
    Also how long it took, the children's exit codes, the replies each
    node dropped and whether the nodes are alive.
    """
    gaps_of, joining_of = {}, {}
    with Nodes(REALTIME) as nodes, Peer(realtime=REALTIME) as peer:
        nodes.start('simulator')
        nodes.start('feedforward', '-p', 'rate_hz:=500.0')
        nodes.start('setpoint_publisher', '-p', 'loop:=true')
        states = peer.record('joint_states', JointState)
        outputs = peer.record('feedforward/joint_states', JointState)
        _running(peer, ('simulator', 'feedforward'))
        if not peer.wait(lambda: len(states) > 100 and len(outputs) > 100,
                         START_TIMEOUT):
            raise HarnessError('the streams did not start')
        time.sleep(0.5)
        start = time.monotonic()
        children, joins = [], []
        try:
            for what, target in BURSTS:
                # One after the other: three Python start-ups at once would
                # take both cores for a second, whatever the nodes do.
                joins.append([time.monotonic(), math.inf])
                children.append(start_node_process(
                    [what, target, str(requests)], command=[
                        sys.executable, os.path.abspath(__file__),
                        'burst']))
                children[-1].wait(START_TIMEOUT)
        finally:
            stopped = [stop_process(child) for child in children]
        for join, (_, text) in zip(joins, stopped):
            for line in text.splitlines():
                if line.startswith(REQUESTS_BEGIN):
                    join[1] = float(line.split()[-1])
        # The replies: each dropped after REPLY_WAIT (0.1 s) at most.
        time.sleep(0.12 * requests)
        end = time.monotonic()
        # Stamps are wall time: on this host, monotonic = wall - offset.
        offset = time.time() - time.monotonic()
        for stream, log in (('simulator joint_states', states),
                            ('feedforward joint_states', outputs)):
            stamps = np.array([
                m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 - offset
                for t, m in list(log) if start - 0.5 <= t <= end])
            began, gaps = stamps[:-1], np.diff(stamps)
            joining = np.zeros(len(gaps), bool)
            for first, requesting in joins:
                joining |= (began >= first) & (began < requesting)
            gaps_of[stream] = max(gaps[~joining], default=math.inf)
            joining_of[stream] = max(gaps[joining], default=0.0)
        dropped = {}
        for name in ('simulator', 'feedforward'):
            status = peer.status(name, timeout=3.0)
            dropped[name] = int(status[2].get(
                'replies dropped (client gone)', -1)) if status else -1
        return Departed(
            requests=requests, bursts=BURSTS, gaps=gaps_of,
            joining=joining_of, seconds=end - start,
            client_exits=[code for code, _ in stopped], dropped=dropped,
            alive={n: nodes.alive(n) for n in ('simulator', 'feedforward')})


# What a departing client prints (with its monotonic time) as its requests
# begin.
REQUESTS_BEGIN = 'requests begin at'


BURSTS = (('set', 'simulator'), ('reset', 'simulator'),
          ('set', 'feedforward'))


def burst(args):
    """Child process: ``requests`` requests to ``target``, then leave."""
    rclpy.init()
    node = Node(f'departing_client_{os.getpid()}')
    if args.what == 'reset':
        client = node.create_client(Trigger, f'/{args.target}/reset')
        make = Trigger.Request
    else:
        client = node.create_client(SetParameters,
                                    f'/{args.target}/set_parameters')
        name, value = {'simulator': ('force_limit', 1000.0),
                       'feedforward': ('singularity_margin', 0.2)}[
                           args.target]

        def make():
            return SetParameters.Request(parameters=[ParameterMsg(
                name=name, value=ParameterValue(type=3, double_value=value))])
    if not client.wait_for_service(timeout_sec=START_TIMEOUT):
        return 1
    print(REQUESTS_BEGIN, time.monotonic(), flush=True)
    for _ in range(args.requests):
        client.call_async(make())
    node.destroy_node()
    rclpy.shutdown()
    return 0


# 9. The simulator at 10 kHz ---------------------------------------------------
def fast_simulator(rate_hz=10000.0, commands=1600, command_rate=500.0):
    """
    Run the simulator at ``rate_hz``; send ``commands`` at ``command_rate``.

    Returns, from its diagnostics once the commands are over, the commands
    ``received`` and the ``timeouts`` (one is the brake after the last
    command: more would be spurious), and the level, message and step rate
    of a status made while it was commanded.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('simulator', '-p', f'rate_hz:={rate_hz}')
        pub = peer.publisher(Float64MultiArray, 'commands')
        states = peer.record('joint_states', JointState)
        _running(peer, ('simulator',))
        msg = Float64MultiArray(data=list(HOLD))
        # The first command starts the plant: its efforts are the command's.
        _handshake(peer, lambda k: pub.publish(msg), lambda: any(
            any(state.effort) for _, state in list(states)))
        start = time.monotonic()
        during = None
        for i in range(commands):
            deadline = start + i / command_rate
            wait = deadline - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            pub.publish(msg)
            if during is None and i > commands // 2:
                with peer.lock:     # the newest status, without waiting
                    found = peer.diagnostics.get('simulator')
                if found is not None and found[3] > start + 1.0:
                    during = found[:3]
        # The brake after the last command, once its diagnostics say so.
        peer.wait(lambda: _counter(peer, 'simulator', 'timeouts') > 0,
                  START_TIMEOUT)
        with peer.lock:
            values = peer.diagnostics.get('simulator', (None, None, {}))[2]
        level, message, seen = during if during else (None, '', {})
        return FastSimulator(
            received=int(values.get('commands received', -1)),
            sent=commands, timeouts=int(values.get('timeouts', -1)),
            level=level, message=message,
            step_rate=float(seen.get('step rate (Hz)', 'nan')),
            alive=nodes.alive('simulator'))


# 10. The setpoint publisher's loop --------------------------------------------
def setpoint_loop(duration=0.6, return_duration=0.6, rate_hz=500.0,
                  seconds=3.5):
    """
    Record a looping setpoint publisher; measure the largest jumps.

    Returns the largest change of position and velocity between two
    consecutive setpoints, next to what the motion's own peak speed and
    acceleration allow over the same interval (``*_bound``), and how many
    passes were seen.
    """
    with Nodes() as nodes, Peer() as peer:
        log = peer.record('setpoint/trajectory', MultiDOFJointTrajectory)
        nodes.start('setpoint_publisher', '-p', 'loop:=true', '-p',
                    f'duration:={duration}', '-p',
                    f'return_duration:={return_duration}', '-p',
                    f'rate_hz:={rate_hz}', '-p', 'start_delay:=0.0')
        peer.wait(lambda: len(log) > 0, START_TIMEOUT)
        time.sleep(seconds)
        samples = [(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                    m.points[0]) for _, m in list(log)]
    t = np.array([s for s, _ in samples])
    p = np.array([[pt.transforms[0].translation.x,
                   pt.transforms[0].translation.y,
                   pt.transforms[0].translation.z] for _, pt in samples])
    v = np.array([[pt.velocities[0].linear.x, pt.velocities[0].linear.y,
                   pt.velocities[0].linear.z] for _, pt in samples])
    dt = np.diff(t)
    dense = np.linspace(0.0, duration + return_duration, 2001)
    from orthoglide_ros.cores.setpoint_publisher import PARAMETERS, Stream
    stream = Stream(PARAMETERS.parse({
        'loop': True, 'duration': float(duration),
        'return_duration': float(return_duration)}))
    motion = [stream.sample(s) for s in dense]
    speed = max(np.linalg.norm(m[1]) for m in motion)
    accel = max(np.linalg.norm(m[2]) for m in motion)
    jumps_p = np.linalg.norm(np.diff(p, axis=0), axis=1)
    jumps_v = np.linalg.norm(np.diff(v, axis=0), axis=1)
    return SetpointLoop(
        samples=len(t), span=float(t[-1] - t[0]) if len(t) else 0.0,
        passes=int((t[-1] - t[0]) // (duration + return_duration)) + 1
        if len(t) else 0,
        jump_p=float(jumps_p.max()),
        jump_p_bound=float((speed * dt).max() * 1.01 + 1e-12),
        jump_v=float(jumps_v.max()),
        jump_v_bound=float((accel * dt).max() * 1.01 + 1e-12),
        peak_speed=speed)


# 4. A stall of one process of the closed loop ---------------------------------
def trajectory_peak_speed(duration=trajectory.PAPER_DURATION,
                          return_duration=trajectory.RETURN_DURATION):
    """Largest |lambdadot| (m/s) of the looped paper motion, any slider."""
    from orthoglide_ros.cores.setpoint_publisher import PARAMETERS, Stream
    stream = Stream(PARAMETERS.parse({'loop': True}))
    times = np.linspace(0.0, duration + return_duration, 3001)
    samples = [stream.sample(t) for t in times]
    solution = mechanics.solve_batch(
        Robot(), np.array([s[0] for s in samples]),
        np.array([s[1] for s in samples]), np.array([s[2] for s in samples]))
    return float(np.abs(solution.lambdadot).max())


def stall_resume(stalled=NODES, before=2.0, stall=2.0, after=3.0,
                 loop_rate=250.0, plant_rate=500.0):
    """
    Run the closed loop; SIGSTOP one of its processes for ``stall`` s.

    The loop as the closed-loop demo runs it (setpoints and feedforward at
    ``loop_rate``, the plant at ``plant_rate``, default controller: path
    tolerance on), started afresh for each process of ``stalled``:
    ``before`` s following the looping paper trajectory, then SIGSTOP,
    ``stall`` s, SIGCONT, ``after`` s. Returns per stalled process the
    largest |command| (N) and |lambdadot| (m/s) from the stall's start to
    ``after`` s past its end, the controller's mode, trips and stall
    holds, and the trajectory's own peak |lambdadot|.
    """
    peak = trajectory_peak_speed()
    result = Stalls(peak_speed=peak, force_limit=1000.0, stalls={}, alive={})
    with Peer(realtime=REALTIME) as peer:
        commands = peer.record('commands', Float64MultiArray)
        states = peer.record('joint_states', JointState)
        for name in stalled:
            with Nodes(REALTIME) as nodes:
                nodes.start('simulator', '-p', f'rate_hz:={plant_rate}')
                nodes.start('tracking_controller')
                nodes.start('feedforward')
                _running(peer, ('simulator', 'tracking_controller',
                                'feedforward'))
                first = len(commands)
                nodes.start('setpoint_publisher', '-p', 'loop:=true', '-p',
                            f'rate_hz:={loop_rate}', '-p',
                            'min_subscribers:=1')
                if not peer.wait(lambda: len(commands) > first + 50,
                                 START_TIMEOUT):
                    raise HarnessError('the loop did not close')
                time.sleep(before)
                proc = nodes.processes[name]
                start = time.monotonic()
                proc.send_signal(signal.SIGSTOP)
                time.sleep(stall)
                proc.send_signal(signal.SIGCONT)
                time.sleep(after)
                end = time.monotonic()
                forces = [max(abs(f) for f in m.data)
                          for t, m in list(commands) if start <= t <= end]
                speeds = [max(abs(v) for v in m.velocity)
                          for t, m in list(states)
                          if start <= t <= end and len(m.velocity)]
                status = peer.status('tracking_controller', timeout=3.0)
                values = status[2] if status else {}
                result.stalls[name] = Stall(
                    max_force=max(forces, default=0.0),
                    max_speed=max(speeds, default=0.0),
                    commands=len(forces),
                    trips=int(values.get('path tolerance trips', -1)),
                    stall_holds=int(values.get('stall holds', -1)),
                    mode=values.get('mode'))
                result.alive[name] = all(nodes.alive(n) for n in NODES)
    return result


# 11. A flood of joint trajectories (issue 16) ---------------------------------
@dataclass
class Flood:
    """What :func:`trajectory_flood` saw (forces in N, speeds in m/s)."""

    sent: int                   # one-point trajectories published
    commands: int               # commands during the flood and after it
    saturated: int              # of them, a force at force_limit
    max_force: float
    max_speed: float            # largest |lambdadot| measured
    final_error: float          # |lambda| after the normal trajectory, m
    mode: str                   # the controller's mode at the end
    superseded: int             # replacements that waited for a tick
    alive: bool


def trajectory_flood(flood=1.5, period=0.001, after=1.5):
    """
    Flood the tracking controller with one-point joint trajectories.

    The simulator as plant, the controller with the defaults; every
    ``period`` s a new trajectory with one point 50 ms ahead, its target
    alternating between 0 and 10 mm on every slider (efforts zero, header
    stamp zero: "now"), for ``flood`` s; then one normal trajectory, home
    in 1 s with the force that holds it there, followed for ``after`` s.
    """
    force_limit = 1000.0
    with Nodes() as nodes, Peer() as peer:
        commands = peer.record('commands', Float64MultiArray)
        states = peer.record('joint_states', JointState)
        nodes.start('simulator')
        nodes.start('tracking_controller')
        _running(peer, ('simulator', 'tracking_controller'))
        pub = peer.publisher(JointTrajectory, 'joint_trajectory', 100)
        if not peer.wait(lambda: pub.get_subscription_count()
                         and len(states) > 10, START_TIMEOUT):
            raise HarnessError('the controller did not subscribe')
        names = ['slider_a', 'slider_b', 'slider_c']

        def one_point(position, effort, seconds):
            return JointTrajectory(joint_names=names, points=[
                JointTrajectoryPoint(
                    positions=[position] * 3, velocities=[0.0] * 3,
                    effort=list(effort), time_from_start=Duration(
                        seconds=seconds).to_msg())])
        messages = [one_point(0.01 * (i % 2), (0.0,) * 3, 0.05)
                    for i in range(2)]
        first = len(commands)
        start = time.monotonic()
        sent = 0
        while time.monotonic() < start + flood:
            pub.publish(messages[sent % 2])
            sent += 1
            wait = start + sent * period - time.monotonic()
            if wait > 0:
                time.sleep(wait)
        pub.publish(one_point(0.0, HOLD, 1.0))
        time.sleep(after)
        forces = [max(abs(f) for f in m.data) for _, m in commands[first:]]
        speeds = [max(abs(v) for v in m.velocity)
                  for t, m in list(states) if t >= start and len(m.velocity)]
        status = peer.status('tracking_controller', timeout=3.0)
        values = status[2] if status else {}
        return Flood(
            sent=sent, commands=len(forces),
            saturated=sum(f >= force_limit for f in forces),
            max_force=max(forces, default=0.0),
            max_speed=max(speeds, default=0.0),
            final_error=max(abs(x) for x in states[-1][1].position),
            mode=values.get('mode'),
            superseded=int(values.get('trajectories superseded', -1)),
            alive=nodes.alive('simulator')
            and nodes.alive('tracking_controller'))


# 12. Finite but absurd values (issue 16) -------------------------------------
@dataclass
class Absurd:
    """What :func:`absurd_values` saw: outputs and the refusals counted."""

    feedforward_outputs: int    # joint states and joint trajectories
    commands: int               # the controller's commands
    feedforward_rejected: dict  # diagnostics key -> count
    controller_rejected: dict
    alive: bool


def absurd_values():
    """
    Send finite but absurd values to the feedforward and the controller.

    The feedforward gets a setpoint and a cartesian_trajectory point
    accelerating at 1e200 m/s^2 (once a 2.45e201 N effort); the tracking
    controller a measurement at 5 m and one at 1e300 m/s, a desired
    effort and a joint trajectory effort of 1e300 N. Returns what each
    published and the ``rejected ...`` counters of their diagnostics.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward')
        nodes.start('tracking_controller')
        outputs = peer.record('feedforward/joint_states', JointState)
        trajectories = peer.record('feedforward/joint_trajectory',
                                   JointTrajectory)
        commands = peer.record('commands', Float64MultiArray)
        pubs = {topic: peer.publisher(kind, topic) for topic, kind in (
            ('setpoint/trajectory', MultiDOFJointTrajectory),
            ('cartesian_trajectory', MultiDOFJointTrajectory),
            ('joint_states', JointState),
            ('feedforward/joint_states', JointState),
            ('joint_trajectory', JointTrajectory))}
        _running(peer, ('feedforward', 'tracking_controller'))
        if not peer.wait(lambda: all(p.get_subscription_count() >= 1
                                     for p in pubs.values()), START_TIMEOUT):
            raise HarnessError('the nodes did not subscribe')
        names = ['slider_a', 'slider_b', 'slider_c']
        setpoint = _setpoint('', (5, 0))
        setpoint.points[0].accelerations[0].linear.z = 1e200
        pubs['setpoint/trajectory'].publish(setpoint)
        whole = _setpoint('', (0, 0))
        whole.points[0].accelerations[0].linear.z = 1e200
        pubs['cartesian_trajectory'].publish(whole)
        for position, velocity in (([0.0, 5.0, 0.0], [0.0] * 3),
                                   ([0.0] * 3, [0.0, 0.0, 1e300])):
            pubs['joint_states'].publish(JointState(
                name=names, position=position, velocity=velocity))
        pubs['joint_states'].publish(JointState(
            name=names, position=[0.0] * 3, velocity=[0.0] * 3))
        pubs['feedforward/joint_states'].publish(JointState(
            name=names, position=[0.0] * 3, velocity=[0.0] * 3,
            effort=[0.0, 1e300, 0.0]))
        pubs['joint_trajectory'].publish(JointTrajectory(
            joint_names=names, points=[JointTrajectoryPoint(
                positions=[0.0] * 3, velocities=[0.0] * 3,
                effort=[0.0, 0.0, 1e300],
                time_from_start=Duration(seconds=0.5).to_msg())]))
        start = time.monotonic()
        statuses = {}
        for name in ('feedforward', 'tracking_controller'):
            status = peer.status(name, after=start + 0.3, timeout=5.0)
            statuses[name] = {k: int(v) for k, v in (
                status[2] if status else {}).items()
                if k.startswith('rejected') and v.isdigit() and int(v)}
        # The peer's own desired state arrives here too: not an output.
        mine = sum(len(m.effort) == 3 and m.effort[1] == 1e300
                   for _, m in outputs)
        return Absurd(
            feedforward_outputs=len(outputs) - mine + len(trajectories),
            commands=len(commands),
            feedforward_rejected=statuses['feedforward'],
            controller_rejected=statuses['tracking_controller'],
            alive=nodes.alive('feedforward')
            and nodes.alive('tracking_controller'))


def main(argv=None):
    """Entry point of the child process: ``burst WHAT TARGET REQUESTS``."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('role', choices=('burst',))
    parser.add_argument('what', choices=('set', 'reset'))
    parser.add_argument('target')
    parser.add_argument('requests', type=int)
    return burst(parser.parse_args(argv))


if __name__ == '__main__':
    sys.exit(main())
