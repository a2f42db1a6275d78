"""
Hostile peers of the nodes' services and processes.

Malformed and absurd parameter requests, clients that leave with requests
in flight (``burst``: this module run as a child process, ``python -m
orthoglide_testing.hostile.services burst ...``), a client whose reply
reader can never match and stays (``linger``), stalls of a node while it
answers, signals while a node starts, text in messages that would make
long or many log lines.
"""

import argparse
from dataclasses import dataclass
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import serialize_message

from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterValue
from rcl_interfaces.srv import (GetParameters, SetParameters,
                                SetParametersAtomically)
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_testing.load import REALTIME
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)

from orthoglide_testing.hostile.peer import (
    diagnostic_counter, handshake, HarnessError, home_setpoint, log_lines,
    NODES, Nodes, Peer, START_TIMEOUT, wait_running)


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


# Malformed parameter requests ------------------------------------------------
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
        wait_running(peer, NODES)
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


# A simulator parameter the cases set, harmless: A's effort limit (N).
EFFORT = 'joint_limits.slider_a.max_effort'


# Absurd parameter values -----------------------------------------------------
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
        wait_running(peer, ABSURD)
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


# Signals while starting ------------------------------------------------------
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
               for line in log_lines(stderr))


# Log amplification -----------------------------------------------------------
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
        # The flood's queues (the controller's input, this writer) hold it
        # whole: every malformed message is counted, however late the node
        # or this process runs on a busy host.
        nodes.start('tracking_controller', '-p',
                    'qos_overrides./joint_states.subscription.depth:=1000')
        setpoints = peer.publisher(MultiDOFJointTrajectory,
                                   'setpoint/trajectory')
        measured = peer.publisher(JointState, 'joint_states', depth=1000)
        outputs = peer.record('feedforward/joint_states', JointState)
        wait_running(peer, ('feedforward', 'tracking_controller'))
        handshake(peer, lambda k: setpoints.publish(home_setpoint('', (1, k))),
                  lambda: outputs)
        handshake(peer, lambda k: measured.publish(JointState(
            name=['unknown'], position=[0.0])), lambda: diagnostic_counter(
            peer, 'tracking_controller', 'rejected measured missing_joint')
            > 0)
        for frame in ('f' * 60000, 'g' * 5_000_000):
            setpoints.publish(home_setpoint(frame))
        for count in (4000, 100000):
            state = JointState(name=[f'joint_{i}' for i in range(count)])
            measured.publish(state)
        # The big one must have reached the node and been taken before the
        # flood, or the flood may push it out.
        measured.wait_for_all_acked(Duration(seconds=START_TIMEOUT))
        peer.wait(lambda: peer.diagnostics.get('tracking_controller', (
            None, None, {}))[2].get('rejected measured oversize', '0') != '0',
            START_TIMEOUT)
        good = serialize_message(JointState(name=['a'], position=[1.0]))
        for i in range(500):
            measured.publish(good[:8 + i % 16] + b'\xff' * (i % 7))
            time.sleep(0.002)
        # Taken and counted (at least the 400 the test asks for; all 500
        # unless one is lost).
        peer.wait(lambda: int(peer.diagnostics.get('tracking_controller', (
            None, None, {}))[2].get('rejected measured malformed', '0'))
            >= 400, START_TIMEOUT)
        status = {name: peer.status(name, timeout=3.0) for name in
                  ('feedforward', 'tracking_controller')}
        result = {}
        for name in ('feedforward', 'tracking_controller'):
            alive = nodes.alive(name)
            code, stderr = nodes.stop(name)
            lines = log_lines(stderr)
            values = status[name][2] if status[name] else {}
            result[name] = Logged(
                alive=alive, code=code, lines=len(lines),
                longest=max((len(line) for line in lines), default=0),
                counters={k: v for k, v in values.items()
                          if k.startswith('rejected') and v != '0'})
        return result


# Departed clients ------------------------------------------------------------
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
        wait_running(peer, ('simulator', 'feedforward'))
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
                        sys.executable, '-m', __spec__.name,
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
        return Departed(
            requests=requests, bursts=BURSTS, gaps=gaps_of,
            joining=joining_of, seconds=end - start,
            client_exits=[code for code, _ in stopped],
            dropped=_replies_dropped(peer),
            alive={n: nodes.alive(n) for n in ('simulator', 'feedforward')})


@dataclass
class Isolated:
    """:func:`isolated_clients`: fresh clients beside a hostile one."""

    fresh: int              # fresh clients per service
    answered: dict          # service -> fresh clients answered (successful)
    carried_out: dict       # service -> the hostile request took effect
    lingering_sends: int    # requests the hostile client sent (2 at best)
    stalls: int             # 150 ms stops of the feedforward, one a reply
    after_stalls: dict      # 'same client', 'fresh process' -> answered
    dropped: dict           # node -> replies dropped
    alive: dict


def isolated_clients(fresh=3, stalls=5):
    """
    Call beside a client that can never take a reply and stays.

    A child process (``linger``) makes its clients of the feedforward's
    ``~/change_state`` and the simulator's ``~/set_parameters`` with a
    TRANSIENT_LOCAL reply reader (the VOLATILE reply writer never matches
    it: a user's QoS mistake is enough), sends one request to each
    (deactivate; A's ``max_effort`` 999 N, EFFORT; again while an ordinary
    client does not see it done: a request can be lost before discovery
    ends), and stays. Then ``fresh`` new clients of this process call each service in
    turn (5 s each). Then the feedforward is stopped (SIGSTOP) for 150 ms as
    each of ``stalls`` get_state requests of one client is being answered,
    and that client and a fresh process ask ``stalls`` more times.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('simulator')
        node = nodes.start('feedforward')
        wait_running(peer, ('simulator', 'feedforward'))
        hostile = start_node_process([], command=[
            sys.executable, '-m', __spec__.name, 'linger'])
        try:
            return _beside(peer, nodes, node, hostile, fresh, stalls)
        finally:
            stop_process(hostile)


def _beside(peer, nodes, node, hostile, fresh, stalls):
    """:func:`isolated_clients` once the nodes run and ``hostile`` started."""
    sends = _await_line(hostile, LINGERING, START_TIMEOUT)
    if not sends:
        raise HarnessError('the lingering client saw no effect of its '
                           'requests')
    state = '/feedforward/get_state'
    carried_out = {
        'feedforward change_state': peer.wait(lambda: _state(
            peer, state) == 'inactive', 5.0),
        'simulator set_parameters': peer.wait(lambda: _parameter(
            peer, 'simulator', EFFORT) == 999.0, 5.0)}
    answered = {'feedforward change_state': 0, 'simulator set_parameters': 0}
    for k in range(fresh):
        transition = (Transition.TRANSITION_ACTIVATE if k % 2 == 0
                      else Transition.TRANSITION_DEACTIVATE)
        reply = peer.call(ChangeState, '/feedforward/change_state',
                          ChangeState.Request(transition=Transition(
                              id=transition)), timeout=5.0)
        answered['feedforward change_state'] += bool(
            reply is not None and reply.success)
        results = peer.set_parameters(
            'simulator', {EFFORT: 1000.0 + k}, timeout=5.0)
        answered['simulator set_parameters'] += bool(
            results and results[0].successful)
    client = peer.node.create_client(GetState, state)
    answers = 0
    for _ in range(stalls):
        future = client.call_async(GetState.Request())
        time.sleep(0.002)
        os.kill(node.pid, signal.SIGSTOP)
        time.sleep(0.15)
        os.kill(node.pid, signal.SIGCONT)
        answers += peer.wait(future.done, 5.0)
    after = {'same client': 0}
    for _ in range(stalls):
        future = client.call_async(GetState.Request())
        after['same client'] += peer.wait(future.done, 5.0)
    asker = start_node_process([state, str(stalls)], command=[
        sys.executable, '-m', __spec__.name, 'ask'])
    after['fresh process'] = int(_await_line(
        asker, ANSWERED, 5.0 * stalls + START_TIMEOUT) or -1)
    stop_process(asker)
    return Isolated(
        fresh=fresh, answered=answered, carried_out=carried_out,
        lingering_sends=int(sends),
        stalls=stalls, after_stalls=after, dropped=_replies_dropped(peer),
        alive={n: nodes.alive(n) for n in ('simulator', 'feedforward')})


def _replies_dropped(peer):
    """Return each node's ``replies dropped (client gone)``; -1: no status."""
    dropped = {}
    for name in ('simulator', 'feedforward'):
        status = peer.status(name, timeout=3.0)
        dropped[name] = int(status[2].get(
            'replies dropped (client gone)', -1)) if status else -1
    return dropped


def _state(peer, service):
    """Return the label of a node's lifecycle state (None: no answer)."""
    reply = peer.call(GetState, service, GetState.Request(), timeout=2.0)
    return None if reply is None else reply.current_state.label


def _parameter(peer, node, name):
    """Return a double parameter of ``node`` (None: no answer)."""
    reply = peer.call(GetParameters, f'/{node}/get_parameters',
                      GetParameters.Request(names=[name]), timeout=2.0)
    return None if reply is None else reply.values[0].double_value


def _await_line(proc, prefix, timeout):
    """
    Wait for a child's stdout line beginning ``prefix``; return its rest.

    None when the child ended or ``timeout`` s passed first.
    """
    out = proc.output_files[0]
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        out.seek(0)
        for line in out.read().decode(errors='replace').splitlines():
            if line.startswith(prefix):
                return line[len(prefix):].strip() or prefix
        if proc.poll() is not None:
            return None
        time.sleep(0.05)
    return None


# What the lingering client prints once its requests are sent, and what
# the asking one prints at its end.
LINGERING, ANSWERED = 'lingering', 'answered'
# How long the lingering client waits for its request's effect before it
# sends the request again (s).
RESEND = 2.0


def _seen(node, client, request, done):
    """Ask ``client``; whether its reply satisfies ``done``."""
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=2.0)
    return future.done() and future.result() is not None \
        and done(future.result())


def linger(args):
    """
    Child: one request each from TRANSIENT_LOCAL clients, then stay.

    A request sent before the service's request reader has matched this
    writer is lost (DDS, on a loaded machine), and the reply that would
    say so never comes: ordinary clients of the same node read the effect
    (feedforward inactive, A's ``max_effort`` 999 N), and a request whose
    effect does not show within RESEND s is sent again.
    """
    rclpy.init()
    node = Node(f'lingering_client_{os.getpid()}')
    qos = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    change = node.create_client(ChangeState, '/feedforward/change_state',
                                qos_profile=qos)
    parameters = node.create_client(SetParameters,
                                    '/simulator/set_parameters',
                                    qos_profile=qos)
    state = node.create_client(GetState, '/feedforward/get_state')
    force = node.create_client(GetParameters, '/simulator/get_parameters')
    requests = (
        (change, ChangeState.Request(transition=Transition(
            id=Transition.TRANSITION_DEACTIVATE)),
         state, GetState.Request(),
         lambda reply: reply.current_state.label == 'inactive'),
        (parameters, SetParameters.Request(parameters=[ParameterMsg(
            name=EFFORT, value=ParameterValue(
                type=3, double_value=999.0))]),
         force, GetParameters.Request(names=[EFFORT]),
         lambda reply: reply.values[0].double_value == 999.0))
    try:
        # Not wait_for_service on the hostile clients: it waits for the
        # reply reader to match too, which this one never does.
        deadline = time.monotonic() + START_TIMEOUT
        if not all(check.wait_for_service(timeout_sec=START_TIMEOUT)
                   for _, _, check, _, _ in requests):
            return 1
        sends = 0
        for client, request, check, question, done in requests:
            seen = False
            while not seen:
                if time.monotonic() > deadline:
                    return 1
                client.call_async(request)
                sends += 1
                end = time.monotonic() + RESEND
                while not seen and time.monotonic() < end:
                    seen = _seen(node, check, question, done)
        if sends > len(requests):   # a late copy lands before the callers
            time.sleep(RESEND)
        print(LINGERING, sends, flush=True)
        while True:
            time.sleep(0.1)
    except KeyboardInterrupt:
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def ask(args):
    """Child: ``requests`` get_state calls to ``target``; print answered."""
    rclpy.init()
    node = Node(f'asking_client_{os.getpid()}')
    client = node.create_client(GetState, args.target)
    answered = 0
    try:
        if client.wait_for_service(timeout_sec=START_TIMEOUT):
            for _ in range(args.requests):
                future = client.call_async(GetState.Request())
                rclpy.spin_until_future_complete(node, future,
                                                 timeout_sec=5.0)
                answered += future.done()
        print(ANSWERED, answered, flush=True)
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


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
        name, value = {'simulator': (EFFORT, 1000.0),
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


def main(argv=None):
    """
    Entry point of the child processes.

    ``burst WHAT TARGET REQUESTS``, ``linger``, ``ask TARGET REQUESTS``.
    """
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    roles = parser.add_subparsers(dest='role', required=True)
    role = roles.add_parser('burst')
    role.add_argument('what', choices=('set', 'reset'))
    role.add_argument('target')
    role.add_argument('requests', type=int)
    roles.add_parser('linger')
    role = roles.add_parser('ask')
    role.add_argument('target')
    role.add_argument('requests', type=int)
    args = parser.parse_args(argv)
    return {'burst': burst, 'linger': linger, 'ask': ask}[args.role](args)


if __name__ == '__main__':
    sys.exit(main())
