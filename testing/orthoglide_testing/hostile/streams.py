"""
Hostile peers and stalls of the nodes' streams.

Stamps a builtin_interfaces/Time cannot hold (at the feedforward and at
the mechanism state publisher), the simulator asked for 10
kHz, the looping setpoint publisher's way back, a process of the closed
loop stopped for seconds, a flood of joint trajectories, finite but absurd
values on the inputs.
"""

from dataclasses import dataclass
import signal
import time

import numpy as np

from rclpy.duration import Duration

from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import (JointTrajectory, JointTrajectoryPoint,
                                 MultiDOFJointTrajectory)

from orthoglide_testing.load import REALTIME
from orthoglide_testing.hostile.peer import (
    diagnostic_counter, handshake, HarnessError, HOLD, home_setpoint, NODES,
    Nodes, Peer, START_TIMEOUT, wait_running)
from orthoglide_ros.cores.simulator import PARAMETERS as SIMULATOR
from orthoglide_ros.cores.tracking_controller import DRIVES
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot

# The tracking controller's effort limit, the same on each actuator (N).
MAX_EFFORT = DRIVES['slider_a']['max_effort']
# s: the simulator's default command timeout, past which it brakes.
COMMAND_TIMEOUT = SIMULATOR.defaults()['command_timeout']


@dataclass
class Stamps:
    """:func:`stamps`: outputs of the bad and of the good instants."""

    outputs: int            # for the bad ones: should be 0
    good: int               # for the same instants written right
    rejected_stamp: int
    alive: bool


@dataclass
class MechanismStamps:
    """:func:`mechanism_stamps`: what the bad and the good stamps gave."""

    bad_outputs: int        # published for the invalid stamps: should be 0
    stamps_out: list        # (sec, nanosec) of the outputs after them
    rejected_stamp: int
    level: int              # of the diagnostics after the bad stamps
    message: str
    alive: bool


@dataclass
class FastSimulator:
    """:func:`fast_simulator`: commands taken and the status said."""

    received: int
    sent: int               # the handshake's commands and ``commands``
    timeouts: int           # one is the brake after the last command
    stall_brakes: int       # timeouts after the simulator itself stood still
    sender_stalls: int      # gaps between two commands sent > the timeout
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
    max_effort: float       # N, the controller's clip
    stalls: dict            # process -> Stall
    alive: dict             # process -> every node alive after


# A flood of joint trajectories -----------------------------------------------
@dataclass
class Flood:
    """What :func:`trajectory_flood` saw (forces in N, speeds in m/s)."""

    sent: int                   # one-point trajectories published
    commands: int               # commands during the flood and after it
    pace: float                 # command rate in the flood / after it
    saturated: int              # of them, a force at the effort limit
    max_force: float
    max_speed: float            # largest |lambdadot| measured
    final_error: float          # |lambda| after the normal trajectory, m
    mode: str                   # the controller's mode at the end
    superseded: int             # replacements that waited for a tick
    alive: bool


# Finite but absurd values ----------------------------------------------------
@dataclass
class Absurd:
    """What :func:`absurd_values` saw: outputs and the refusals counted."""

    feedforward_outputs: int    # joint states and joint trajectories
    commands: int               # the controller's commands
    feedforward_rejected: dict  # diagnostics key -> count
    controller_rejected: dict
    alive: bool


# Stamps ----------------------------------------------------------------------
def stamps():
    """
    Send setpoints whose nanosec is >= 1e9 on every input; count outputs.

    The same instants written correctly are sent too. Returns ``outputs``
    (joint states received for the bad ones: should be 0), ``good``
    (for the good ones: 2), ``rejected_stamp`` from the diagnostics and
    ``received`` per input. Outputs are told apart by stamp: a handshake's
    may come late, and a pose's partners 100 ms and more after it on a
    busy host (a pairing_timeout of 5 s).
    """
    good_stamps = {(101, 500_000_000), (402, 4)}
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward', '-p', 'setpoint_timeout:=10.0',
                    '-p', 'pairing_timeout:=5.0')
        outputs = peer.record('feedforward/joint_states', JointState)
        pubs = {name: peer.publisher(kind, f'setpoint/{name}') for name, kind
                in (('pose', PoseStamped), ('twist', TwistStamped),
                    ('accel', AccelStamped),
                    ('trajectory', MultiDOFJointTrajectory))}
        wait_running(peer, ('feedforward',))

        def topics(sec, nanosec):
            for name, kind in (('pose', PoseStamped), ('twist', TwistStamped),
                               ('accel', AccelStamped)):
                msg = kind()
                if name == 'pose':
                    msg.pose.orientation.w = 1.0
                msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
                pubs[name].publish(msg)

        def point(header, offset):
            pubs['trajectory'].publish(home_setpoint('', header, offset))

        def stamps_out():
            return [(m.header.stamp.sec, m.header.stamp.nanosec)
                    for _, m in list(outputs)]

        # Both forms reach the node (stamps older than the test's; none
        # (1, 0), which (0, 1e9) would be if taken).
        trajectory_sent = handshake(peer, lambda k: point((1, k + 1), (0, 0)),
                                    lambda: outputs)
        topics_sent = handshake(peer, lambda k: topics(2, k),
                                lambda: any(s[0] == 2 for s in stamps_out()))
        shaken = {(1, k + 1) for k in range(trajectory_sent)} | {
            (2, k) for k in range(topics_sent)}
        topics(100, 1_500_000_000)          # = 101.5 s, written wrong
        point((200, 2_000_000_000), (0, 0))     # header wrong
        point((300, 0), (0, 1_000_000_000))     # offset wrong
        point((0, 1_000_000_000), (0, 0))   # "zero" sec, wrong nanosec
        peer.wait(lambda: diagnostic_counter(peer, 'feedforward', 'rejected stamp')
                  >= 6, START_TIMEOUT)
        topics(101, 500_000_000)            # the same instant, written right
        point((400, 5), (1, 999_999_999))
        # Each good one follows the bad ones of its input: once both are
        # out, so is any output of a bad one.
        peer.wait(lambda: good_stamps <= set(stamps_out()), START_TIMEOUT)
        tested = [s for s in stamps_out() if s not in shaken]
        good = len(good_stamps.intersection(tested))
        return Stamps(outputs=len(tested) - good, good=good,
                      rejected_stamp=diagnostic_counter(peer, 'feedforward',
                                                        'rejected stamp'),
                      alive=nodes.alive('feedforward'))


def mechanism_stamps(bad=((5, 2_000_000_000), (-1, 0), (-7, 999_999_999),
                          (0, 1_000_000_000))):
    """
    Send joint states stamped ``bad`` to the mechanism state publisher.

    Then one stamped zero (it passes: time 0 of a simulated clock) and a
    valid one. Returns how many outputs the bad ones gave (should be 0),
    the stamps of the outputs after them ((0, 0) and (9, 5)), the
    ``rejected stamp`` count and the diagnostics' level and message.
    The handshake's outputs, which may come late, are told apart by stamp.
    """
    def state(stamp):
        msg = JointState(name=['slider_a', 'slider_b', 'slider_c'],
                         position=[0.0, 0.0, 0.0])
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
        return msg

    with Nodes() as nodes, Peer() as peer:
        nodes.start('mechanism_state_publisher')
        states = peer.publisher(JointState, 'joint_states')
        outputs = peer.record('mechanism/joint_states', JointState)
        wait_running(peer, ('mechanism_state_publisher',))
        # Stamps (1, k + 1): none (1, 0), which (0, 1e9) would be if taken.
        sent = handshake(peer, lambda k: states.publish(state((1, k + 1))),
                         lambda: outputs)
        shaken = {(1, k + 1) for k in range(sent)}
        for stamp in bad:
            states.publish(state(stamp))
        # The first diagnostics to count them all: its period holds the
        # last of them.
        peer.wait(lambda: diagnostic_counter(peer, 'mechanism_state_publisher',
                                             'rejected stamp') >= len(bad),
                  START_TIMEOUT)
        with peer.lock:
            status = peer.diagnostics.get('mechanism_state_publisher',
                                          (-1, '', {}))
        for stamp in ((0, 0), (9, 5)):
            states.publish(state(stamp))

        def tested():
            return [s for s in ((m.header.stamp.sec, m.header.stamp.nanosec)
                                for _, m in list(outputs)) if s not in shaken]
        # One input, in order: once (9, 5) is out, so is all before it.
        peer.wait(lambda: (9, 5) in tested(), START_TIMEOUT)
        out = tested()
        bad_outputs = max(0, len(out) - 2)     # beyond the two good ones
        return MechanismStamps(
            bad_outputs=bad_outputs,
            stamps_out=out[bad_outputs:],
            rejected_stamp=diagnostic_counter(peer, 'mechanism_state_publisher',
                                              'rejected stamp'),
            level=status[0], message=status[1],
            alive=nodes.alive('mechanism_state_publisher'))


# The simulator at 10 kHz -----------------------------------------------------
def fast_simulator(rate_hz=10000.0, commands=1600, command_rate=500.0):
    """
    Run the simulator at ``rate_hz``; send ``commands`` at ``command_rate``.

    Returns, from its diagnostics once the commands are over, the commands
    ``received`` and the ``timeouts`` (one is the brake after the last
    command: more would be spurious, but for the ``stall_brakes`` of a
    simulator that itself stood still longer than its command timeout),
    and the ``sender_stalls``, gaps between two commands this process sent
    longer than the timeout (each a brake that is not the simulator's),
    and the level, message and step rate of a status made while it was
    commanded. The simulator and this process run at real-time priority
    where the OS grants it: a stall of the machine's other work is not a
    silence of the peer. The states (every step's) are recorded only
    until the first command is seen in them: 10 kHz of them would keep
    this process, and so its sender, busy.
    """
    with Nodes(REALTIME) as nodes, Peer(realtime=REALTIME) as peer:
        nodes.start('simulator', '-p', f'rate_hz:={rate_hz}')
        pub = peer.publisher(Float64MultiArray, 'commands')
        states = peer.record('joint_states', JointState)
        wait_running(peer, ('simulator',))
        msg = Float64MultiArray(data=list(HOLD))
        # The first command starts the plant: its efforts are the command's.
        shaken = handshake(peer, lambda k: pub.publish(msg), lambda: any(
            any(state.effort) for _, state in list(states)))
        peer.forget('joint_states')
        start = time.monotonic()
        during, sent_at, sender_stalls = None, None, 0
        for i in range(commands):
            deadline = start + i / command_rate
            wait = deadline - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            pub.publish(msg)
            now = time.monotonic()
            if sent_at is not None and now - sent_at > COMMAND_TIMEOUT:
                sender_stalls += 1
            sent_at = now
            if during is None and i > commands // 2:
                with peer.lock:     # the newest status, without waiting
                    found = peer.diagnostics.get('simulator')
                if found is not None and found[3] > start + 1.0:
                    during = found[:3]
        # The brake after the last command, once its diagnostics say so
        # (a brake after the process's own stall is not its peer's silence).
        peer.wait(lambda: diagnostic_counter(peer, 'simulator', 'timeouts')
                  > diagnostic_counter(peer, 'simulator', 'stall brakes'),
                  START_TIMEOUT)
        with peer.lock:
            values = peer.diagnostics.get('simulator', (None, None, {}))[2]
        level, message, seen = during if during else (None, '', {})
        return FastSimulator(
            received=int(values.get('commands received', -1)),
            sent=shaken + commands, timeouts=int(values.get('timeouts', -1)),
            stall_brakes=int(values.get('stall brakes', -1)),
            sender_stalls=sender_stalls,
            level=level, message=message,
            step_rate=float(seen.get('step rate (Hz)', 'nan')),
            alive=nodes.alive('simulator'))


# The setpoint publisher's loop -----------------------------------------------
def setpoint_loop(duration=0.6, return_duration=0.6, rate_hz=500.0,
                  seconds=3.5):
    """
    Record a looping setpoint publisher; measure the largest jumps.

    Returns the largest change of position and velocity between two
    consecutive setpoints, next to what the motion's own peak speed and
    acceleration allow over the same interval (``*_bound``), and how many
    passes were seen. Recorded until the stamps span ``seconds``; the
    publisher and this process at real-time priority where the OS grants
    it, so that a stall of the machine's other work is not a gap.
    """
    def stamp(entry):
        return entry[1].header.stamp.sec + entry[1].header.stamp.nanosec * 1e-9

    def spanned():
        return len(log) > 1 and stamp(log[-1]) - stamp(log[0]) >= seconds

    with Nodes(REALTIME) as nodes, Peer(realtime=REALTIME) as peer:
        log = peer.record('setpoint/trajectory', MultiDOFJointTrajectory)
        nodes.start('setpoint_publisher', '-p', 'loop:=true', '-p',
                    f'duration:={duration}', '-p',
                    f'return_duration:={return_duration}', '-p',
                    f'rate_hz:={rate_hz}', '-p', 'start_delay:=0.0')
        peer.wait(lambda: len(log) > 0, START_TIMEOUT)
        peer.wait(spanned, seconds + START_TIMEOUT)
        samples = [(stamp(entry), entry[1].points[0]) for entry in list(log)]
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


# A stall of one process of the closed loop -----------------------------------
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
    result = Stalls(peak_speed=peak, max_effort=MAX_EFFORT, stalls={},
                    alive={})
    with Peer(realtime=REALTIME) as peer:
        commands = peer.record('commands', Float64MultiArray)
        states = peer.record('joint_states', JointState)
        for name in stalled:
            with Nodes(REALTIME) as nodes:
                nodes.start('simulator', '-p', f'rate_hz:={plant_rate}')
                nodes.start('tracking_controller')
                nodes.start('feedforward')
                wait_running(peer, ('simulator', 'tracking_controller',
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


def stall_resume_one_host(**kwargs):
    """
    Run :func:`stall_resume` in a network namespace on the one-host profile.

    :func:`live_graph.stall_resume`: the loop's own behaviour through a
    stall, without the shared-memory transport's (robustness.md#stalls).
    Needs :func:`netns.unavailable` to be empty.
    """
    from orthoglide_testing import live_graph
    found = live_graph.in_namespace('stall_resume', **kwargs)
    return Stalls(**{**found, 'stalls': {
        name: Stall(**stall) for name, stall in found['stalls'].items()}})


def trajectory_flood(flood=1.5, period=0.001, after=1.5, home=1e-3,
                     settle=5.0):
    """
    Flood the tracking controller with one-point joint trajectories.

    The simulator as plant, the controller with the defaults; every
    ``period`` s a new trajectory with one point 50 ms ahead, its target
    alternating between 0 and 10 mm on every slider (efforts zero, header
    stamp zero: "now"), for ``flood`` s; then one normal trajectory, home
    in 1 s with the force that holds it there, followed for ``after`` s
    and up to ``settle`` s more until every slider is within ``home`` (m)
    of it (a loaded machine's loop is late, not wrong).
    """
    with Nodes() as nodes, Peer() as peer:
        commands = peer.record('commands', Float64MultiArray)
        states = peer.record('joint_states', JointState)
        nodes.start('simulator')
        nodes.start('tracking_controller')
        wait_running(peer, ('simulator', 'tracking_controller'))
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
        end = time.monotonic()
        pub.publish(one_point(0.0, HOLD, 1.0))
        time.sleep(after)
        deadline = time.monotonic() + settle
        while time.monotonic() < deadline and max(
                abs(x) for x in states[-1][1].position) >= home:
            time.sleep(0.05)
        stop = time.monotonic()
        forces = [max(abs(f) for f in m.data) for _, m in commands[first:]]
        during = sum(t < end for t, _ in commands[first:])
        rate_after = (len(forces) - during) / (stop - end)
        speeds = [max(abs(v) for v in m.velocity)
                  for t, m in list(states) if t >= start and len(m.velocity)]
        status = peer.status('tracking_controller', timeout=3.0)
        values = status[2] if status else {}
        return Flood(
            sent=sent, commands=len(forces),
            pace=during / (end - start) / rate_after if rate_after else 0.0,
            saturated=sum(f >= MAX_EFFORT for f in forces),
            max_force=max(forces, default=0.0),
            max_speed=max(speeds, default=0.0),
            final_error=max(abs(x) for x in states[-1][1].position),
            mode=values.get('mode'),
            superseded=int(values.get('trajectories superseded', -1)),
            alive=nodes.alive('simulator')
            and nodes.alive('tracking_controller'))


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
        wait_running(peer, ('feedforward', 'tracking_controller'))
        if not peer.wait(lambda: all(p.get_subscription_count() >= 1
                                     for p in pubs.values()), START_TIMEOUT):
            raise HarnessError('the nodes did not subscribe')
        names = ['slider_a', 'slider_b', 'slider_c']
        setpoint = home_setpoint('', (5, 0))
        setpoint.points[0].accelerations[0].linear.z = 1e200
        pubs['setpoint/trajectory'].publish(setpoint)
        whole = home_setpoint('', (0, 0))
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
