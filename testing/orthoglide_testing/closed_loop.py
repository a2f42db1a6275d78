"""
The closed loop over DDS, for the closed-loop demo and its tests.

``setpoint_publisher`` (eq. 6) -> ``feedforward`` -> ``tracking_controller``
-> ``simulator`` -> back to the controller, five processes on real Fast
DDS, and a recorder node here that keeps the simulator's ``joint_states``
and the setpoints' stamps. :class:`ClosedLoop` starts the three long-lived
nodes once; each :meth:`ClosedLoop.run` sets the controller's gains and
feedforward switch, the plant's robot (the simulator's ``robot.*``) and
the model (the feedforward's ``robot.*``) through the standard parameter
services, resets the simulator (platform at home, at rest, held until the
first command) and streams one pass (or several, looped) of a motion from
a new ``setpoint_publisher`` process: the paper's trajectory, a faster
one, or an excitation (:func:`excitation_motion`, for identification).
With ``mode='trajectory'`` it sends the whole pass once as a Cartesian
trajectory instead, which the feedforward converts into a JointTrajectory
that the tracking controller follows as joint_trajectory_controller would
(its ``joint_trajectory`` input is remapped onto
``feedforward/joint_trajectory``). A trajectory is sent once and published
once, reliable but volatile, like a real planner's: the harness confirms
through the controller's ``/diagnostics`` (``trajectories received``)
that it arrived before its start, and sends it once more otherwise (the
same stamp: the same plan), since a pass whose trajectory was lost would
measure the plant at rest.

Tracking error. A measured sample of stamp ``s`` (the simulator's clock at
the end of a step) is compared with the trajectory at the same time,
``r*(s - start)``, where ``start`` is the stamp of the pass's first
setpoint: the error includes everything a real loop suffers (the
controller's sampling, the transport latency, the plant's zero-order hold),
not only the model. The platform position comes from the measured
``lambda`` through :func:`mechanics.forward_kinematics`.

Rates. The control loop (setpoints, feedforward, commands) runs at
``loop_rate`` and the plant at ``plant_rate`` (default 250 Hz and 500 Hz):
four Python nodes and the recorder at 1 kHz would need more than this
machine's two cores (see doc/measurements.md).

"""

from collections import namedtuple
from contextlib import contextmanager
import math
import time

import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_testing.load import (busy_loops, REALTIME,
                                     realtime_args, realtime_client)
from orthoglide_testing.messages import cartesian_message
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)
from orthoglide_testing.verdicts import (ATTEMPTS, first_unspoiled,
                                         pass_spoiled_by)

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import JOINT_NAMES, Robot
from orthoglide_ros.cores.tracking_controller import PARAMETERS

LOOP_RATE = 250.0       # Hz: setpoints, feedforward and commands
PLANT_RATE = 500.0      # Hz: the simulator's steps

Motion = namedtuple('Motion', ('args', 'duration', 'sample'))
Motion.__doc__ = """A motion the setpoint publisher streams.

``args``: its ``setpoint_publisher`` parameters (``-p name:=value`` ...);
``duration``: one pass (s); ``sample(t)``: position, velocity and
acceleration at ``t`` s after the first setpoint (passes repeat).
"""


def paper_motion(target, omega, duration):
    """Return eq. (6) with ``target`` (m), ``omega`` (rad/s) as a Motion."""
    return Motion(
        ['-p', f'omega:={float(omega)}', '-p', f'duration:={duration}',
         '-p', f'target:={[float(c) for c in target]}'], duration,
        lambda t: trajectory.paper_sample(t, target, omega))


def excitation_motion(seed, period):
    """Return the excitation of ``seed`` and ``period`` (s) as a Motion."""
    motion = trajectory.excitation(seed, period)
    return Motion(
        ['-p', 'motion:=excitation', '-p', f'seed:={seed}',
         '-p', f'duration:={float(period)}'], period,
        lambda t: trajectory.excitation_sample(motion, t % period))


# The paper's trajectory, eq. (6), and a faster one (1 Hz, 8x the
# accelerations at the same path length; the target is scaled so that the
# platform stays in the tested cube, |x|, |y|, |z| <= 0.3 m).
TRAJECTORIES = {
    'paper': paper_motion(trajectory.PAPER_TARGET, trajectory.PAPER_OMEGA,
                          trajectory.PAPER_DURATION),
    'fast': paper_motion((0.04, 0.08, -0.16), 2.0 * math.pi, 2.0),
}
DEFAULT_GAINS = {s.name: s.default for s in PARAMETERS.specs
                 if s.name in ('kp', 'kd')}
MISMATCH = 1.2          # the mismatched plant's platform: 20 % heavier
# A plant the paper's model does not know, for identification: a 25 %
# heavier platform, bars 15 % heavier, friction on every slider.
UNKNOWN_PLANT = Robot(m5=18.75, m3=2.875,
                      friction_viscous=(30.0, 40.0, 50.0),
                      friction_coulomb=(5.0, 3.0, 4.0))
# The simulator holds the platform at rest, effort zero, until the first
# command: a log to identify from starts this long after the first
# setpoint (s).
SETTLE = 0.5
START_TIMEOUT = 20.0    # s for the nodes to start and match
PASS_MARGIN = 15.0      # s beyond a pass's duration before giving up
CALL_TIMEOUT = 5.0      # s for one service call
# A step between two recorded states longer than this many plant periods is
# a skip (log_of); logs are joined JOIN_GAP s apart (joined).
SKIP_FACTOR = 1.5
JOIN_GAP = 1.0
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                 reliability=ReliabilityPolicy.RELIABLE)

Run = namedtuple('Run', (
    'label', 'times', 'position_error', 'joint_error', 'rms_mm', 'max_mm',
    'samples', 'start_ns', 'lambdas', 'efforts', 'braked', 'skipped_s',
    'told_s', 'same_command_s'))
Run.__doc__ = """One pass of the closed loop.

``times`` (s since the pass's first setpoint), ``position_error`` (N, 3)
of the platform centre and ``joint_error`` (N, 3) of ``lambda`` (m,
measured minus desired); ``rms_mm`` and ``max_mm`` of the position error's
norm (mm); ``samples``: N; ``start_ns``: the first setpoint's stamp (ns,
node clock); ``lambdas`` and ``efforts``: (N, 3) the measured joint
positions (m) and the forces the plant applied (N): a log to identify
from (:func:`log_of`); ``braked``: states published while the plant was
held after it had started (zero effort: no command for the simulator's
``command_timeout``, a process stalled), which spoil a pass; ``skipped_s``:
the simulated time the plant skipped in the pass (s: a stalled simulator
drops what it cannot catch up with, ``cores/simulator.py``); ``told_s``:
with a pick-up, when the plant and (if told) the model had both
acknowledged the payload (s since the first setpoint; None without);
``same_command_s``: the longest the plant applied one unchanged nonzero
force (s: the controller, at the loop rate, changes it every period
unless a process of the loop stalled).
"""


class LoopError(Exception):
    """The loop could not be started or a pass did not complete."""


class Recorder(Node):
    """Keep the plant's joint states and the stamp of the first setpoint."""

    def __init__(self, context):
        super().__init__('closed_loop_recorder', context=context)
        self.joints = []        # (stamp ns, lambda (3,), effort (3,))
        self.first_setpoint = None
        self.last_setpoint = None
        self.create_subscription(JointState, 'joint_states', self._on_joints,
                                 QOS)
        self.create_subscription(MultiDOFJointTrajectory,
                                 'setpoint/trajectory', self._on_setpoint,
                                 QOS)
        self.reset = self.create_client(Trigger, '/simulator/reset')
        self.plant = AsyncParameterClient(self, 'simulator')
        self.controller = AsyncParameterClient(self, 'tracking_controller')
        self.model = AsyncParameterClient(self, 'feedforward')
        self.cartesian = self.create_publisher(
            MultiDOFJointTrajectory, 'cartesian_trajectory', QOS)
        # The controller's count of joint trajectories received.
        self.controller_trajectories = None
        self.create_subscription(DiagnosticArray, '/diagnostics',
                                 self._on_diagnostics, 10)

    def clear(self):
        """Forget everything recorded."""
        self.joints = []
        self.first_setpoint = None
        self.last_setpoint = None

    def _on_joints(self, msg):
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        self.joints.append((stamp, tuple(msg.position), tuple(msg.effort)))

    def _on_diagnostics(self, msg):
        for status in msg.status:
            if status.name.startswith('tracking_controller'):
                values = {v.key: v.value for v in status.values}
                self.controller_trajectories = int(values.get(
                    'trajectories received', 0))

    def _on_setpoint(self, msg):
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        if self.first_setpoint is None or stamp < self.first_setpoint:
            self.first_setpoint = stamp
        if self.last_setpoint is None or stamp > self.last_setpoint:
            self.last_setpoint = stamp


class ClosedLoop:
    """
    The simulator, feedforward and tracking controller, started once.

    Use it as a context manager: on exit every process gets SIGINT (SIGKILL
    after a timeout) and :attr:`exit_codes` and :attr:`stderr` keep what
    they returned. ``loop_rate`` and ``plant_rate`` in Hz; ``engine``: the
    simulator's (``builtin`` or ``mujoco``), ``mjcf_file`` its model file
    (mujoco; '' builds it from the plant's robot); ``max_effort``: the
    simulator's drives' limit (N, each actuator's
    ``joint_limits.<joint>.max_effort``; None: its default). ``realtime`` (default:
    where the OS grants it): the loop's nodes (the setpoint publisher's
    included) run every thread SCHED_FIFO NODE_PRIORITY (their
    ``thread_priority``) and this process, the recorder, SCHED_FIFO
    CLIENT_PRIORITY, its children reset (:func:`load.realtime_client`).
    """

    def __init__(self, context, loop_rate=LOOP_RATE, plant_rate=PLANT_RATE,
                 engine='builtin', mjcf_file='', realtime=REALTIME,
                 max_effort=None):
        self.context = context
        self.realtime = realtime
        self.node_args = realtime_args(realtime)
        self.loop_rate = loop_rate
        self.plant_rate = plant_rate
        self.engine = engine
        self.mjcf_file = mjcf_file
        self.max_effort = max_effort
        self.processes = {}
        self.exit_codes = {}
        self.stderr = {}
        self.recorder = None
        self.executor = None
        self._realtime = None
        self._told_ns = None

    def __enter__(self):
        """Start the nodes and wait until the recorder reaches them."""
        from rclpy.experimental import EventsExecutor
        commands = {
            'simulator': ['-p', f'rate_hz:={self.plant_rate}',
                          '-p', f'engine:={self.engine}'] + (
                              ['-p', f'mjcf_file:={self.mjcf_file}']
                              if self.mjcf_file else []) + (
                              [arg for joint in JOINT_NAMES for arg in (
                                  '-p', f'joint_limits.{joint}.max_effort:='
                                  f'{float(self.max_effort)}')]
                              if self.max_effort else []),
            'feedforward': [],
            'tracking_controller': [
                '-r', 'joint_trajectory:=feedforward/joint_trajectory'],
        }
        try:
            for name, params in commands.items():
                self.processes[name] = start_node_process(
                    ['--ros-args', *params, *self.node_args],
                    command=[node_executable(name)])
            self.recorder = Recorder(self.context)
            self.executor = EventsExecutor(context=self.context)
            self.executor.add_node(self.recorder)
            # The recorder's DDS threads exist now.
            self._realtime = realtime_client(self.realtime)
            self._realtime.__enter__()
            self._wait(lambda: (
                self.recorder.reset.service_is_ready()
                and self.recorder.plant.services_are_ready()
                and self.recorder.controller.services_are_ready()
                and self.recorder.model.services_are_ready()
                and self.recorder.count_publishers('joint_states') >= 1
                and self.recorder.controller_trajectories is not None),
                START_TIMEOUT, 'the simulator and the controller')
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc):
        """Stop every process (SIGINT) and the recorder."""
        if self._realtime is not None:
            self._realtime.__exit__(None, None, None)
            self._realtime = None
        for name, proc in self.processes.items():
            self.exit_codes[name], self.stderr[name] = stop_process(proc)
        self.processes = {}
        if self.executor is not None:
            self.executor.shutdown()
            self.executor = None
        if self.recorder is not None:
            self.recorder.destroy_node()
            self.recorder = None
        return False

    def check_exits(self):
        """After the ``with`` block: a LoopError unless every node exited 0."""
        failed = {k: v for k, v in self.exit_codes.items() if v != 0}
        if failed:
            raise LoopError(f'nodes exited with {failed}:\n'
                            + '\n'.join(self.stderr.values()))

    def run(self, name='paper', feedforward=True, kp=None, kd=None,
            mass_factor=1.0, plant=None, model=None, passes=1,
            mode='stream', pickup=None):
        """
        Run a motion and return its :class:`Run`.

        ``name``: a key of TRAJECTORIES or a :class:`Motion`;
        ``feedforward``: the controller adds the feedforward force or not;
        ``kp``, ``kd``: the controller's gains (3 values; None: its
        defaults); ``plant``: the simulator's robot (a :class:`Robot`;
        None: the model's with its platform mass times ``mass_factor``);
        ``model``: the feedforward's robot (None: the paper's);
        ``passes``: how many passes, looped (the publisher is stopped
        after the last); ``mode``: ``'stream'`` (setpoints from a
        setpoint_publisher) or ``'trajectory'`` (the whole motion as one
        Cartesian trajectory, see the module docstring); ``pickup``:
        ``(seconds, kg, told)``, a payload the plant picks up that many
        seconds into the stream (the simulator's ``robot.payload``, set at
        run time), the feedforward told at once (its ``robot.payload``) or
        not.
        """
        motion = TRAJECTORIES[name] if isinstance(name, str) else name
        model = model or Robot()
        plant = plant or model.replace(m5=model.m5 * mass_factor)
        gains = [Parameter('feedforward', value=feedforward)]
        for key, values in (('kp', kp), ('kd', kd)):
            if values is None:
                values = DEFAULT_GAINS[key]
            gains.append(Parameter(key, value=[float(v) for v in values]))
        self._set(self.recorder.controller, gains)
        self._set(self.recorder.plant, robot_parameters(plant))
        self._set(self.recorder.model, robot_parameters(model))
        answer = self._call(self.recorder.reset.call_async(Trigger.Request()))
        if not answer.success:
            raise LoopError(f'simulator reset refused: {answer.message}')
        self.recorder.clear()
        self._told_ns = None
        duration = motion.duration * passes
        if mode == 'trajectory':
            self._send_trajectory(motion, duration)
        else:
            self._stream(motion, duration, passes, pickup)
        label = (f'{name if isinstance(name, str) else "motion"}, '
                 f'{"PD + feedforward" if feedforward else "PD"}, '
                 f'plant m5 x{plant.m5 / model.m5:g}'
                 + (', joint trajectory' if mode == 'trajectory' else '')
                 + (f', {pickup[1]:g} kg picked up at {pickup[0]:g} s, '
                    f'feedforward {"told" if pickup[2] else "not told"}'
                    if pickup else ''))
        return _tracking(label, self.recorder, motion, duration,
                         1.0 / self.plant_rate, self._told_ns)

    def run_unspoiled(self, *args, report=None, case=None, **kwargs):
        """
        :meth:`run` until a pass is not spoiled by a stall, ATTEMPTS at most.

        Spoiled (:func:`verdicts.pass_spoiled_by`): a process of the loop
        stalled, which busy cores do now and then, and the pass measured the
        stall, not the loop (:func:`verdicts.first_unspoiled`). Returns the first
        unspoiled pass, else the last. ``report(text)`` (optional) hears about
        every spoiled pass, named ``case`` (default the run's label).
        """
        def heard(run, spoiled, attempt):
            report(f'{case or run.label}: {spoiled} (a process stalled), '
                   f'pass {attempt} of {ATTEMPTS}')
        return first_unspoiled(lambda: self.run(*args, **kwargs),
                               pass_spoiled_by, heard if report else None)

    def _stream(self, motion, duration, passes, pickup=None):
        """Stream the motion from a setpoint_publisher process."""
        publisher = start_node_process([
            '--ros-args', '-p', f'rate_hz:={self.loop_rate}', *motion.args,
            '-p', 'start_delay:=10.0',
            # The feedforward and the recorder.
            '-p', 'min_subscribers:=2',
            '-p', f'loop:={"true" if passes > 1 else "false"}',
            *self.node_args],
            command=[node_executable('setpoint_publisher')])
        try:
            end_ns = None
            deadline = time.monotonic() + duration + PASS_MARGIN
            while publisher.poll() is None:
                recorder = self.recorder
                if end_ns is None and recorder.first_setpoint is not None:
                    end_ns = recorder.first_setpoint + round(duration * 1e9)
                if end_ns is not None and recorder.last_setpoint is not \
                        None and recorder.last_setpoint >= end_ns:
                    break       # the last pass is over (looped passes)
                if pickup and recorder.joints and end_ns is not None and \
                        recorder.joints[-1][0] >= end_ns - round(
                            (duration - pickup[0]) * 1e9):
                    self._pick_up(*pickup[1:])
                    pickup = None
                if time.monotonic() > deadline:
                    raise LoopError('timed out waiting for the end of the '
                                    'pass')
                self._spin(0.02)
            self._spin(0.3)     # the last measurements
        finally:
            code, err = stop_process(publisher)
        if code != 0:
            raise LoopError(f'setpoint_publisher exited {code}:\n{err}')

    def _pick_up(self, payload, told):
        """Put ``payload`` (kg) on the plant; tell the model if ``told``."""
        clients = [self.recorder.plant] + ([self.recorder.model] if told
                                           else [])
        futures = [c.set_parameters([Parameter('robot.payload',
                                               value=float(payload))])
                   for c in clients]
        for future in futures:
            refused = [r.reason for r in self._call(future).results
                       if not r.successful]
            if refused:
                raise LoopError(f'payload refused: {refused}')
        self._told_ns = self.recorder.get_clock().now().nanoseconds

    def _send_trajectory(self, motion, duration, lead=2.0, hold=0.5):
        """
        Send the motion as one trajectory starting ``lead`` s from now.

        Points at the loop rate, ``time_from_start`` from 0: first ``hold``
        s at rest where the motion begins (the plant's state after the
        reset: a planner's trajectory starts from the robot's state, and
        the controller's transition from its state at reception then ends
        on the static forces), then the motion, from the header stamp plus
        ``hold``, the instant the measurements are compared against.
        Sent again, once, when the controller's diagnostics (about once a
        second) have not counted it after 1.2 s; a LoopError if they have
        not by the start.
        """
        step = 1.0 / self.loop_rate
        times = np.arange(0.0, duration + 0.5 * step, step)
        p, v, a = (np.array(x) for x in zip(*map(motion.sample, times)))
        rest = np.zeros((round(hold / step), 3))
        p = np.vstack([rest + p[0], p])
        v, a = np.vstack([rest, v]), np.vstack([rest, a])
        times = np.r_[np.arange(len(rest)) * step, hold + times]
        recorder = self.recorder
        self._wait(lambda: recorder.cartesian.get_subscription_count() > 0,
                   START_TIMEOUT, 'the feedforward')
        sent = time.monotonic()
        start = recorder.get_clock().now().nanoseconds + round(lead * 1e9)
        msg = cartesian_message(times, p, v, a, divmod(start, 10**9))
        before = recorder.controller_trajectories
        for deadline in (sent + 1.2, sent + lead - 0.1):
            recorder.cartesian.publish(msg)
            while (recorder.controller_trajectories == before
                   and time.monotonic() < deadline):
                self._spin(0.02)
            if recorder.controller_trajectories != before:
                break
        else:
            raise LoopError('the tracking controller did not receive the '
                            'trajectory before its start')
        recorder.first_setpoint = start + round(hold * 1e9)
        end = sent + lead + hold + duration + 0.3
        self._wait(lambda: time.monotonic() > end, lead + hold + duration
                   + PASS_MARGIN, 'the end of the trajectory')

    def wait_for_subscribers(self, topic, count, timeout=START_TIMEOUT):
        """Wait until ``topic`` has ``count`` subscribers (a recorder's)."""
        self._wait(lambda: self.recorder.count_subscribers(topic) >= count,
                   timeout, f'{count} subscribers of {topic}')

    def _set(self, client, parameters):
        results = self._call(client.set_parameters(parameters)).results
        refused = [r.reason for r in results if not r.successful]
        if refused:
            raise LoopError(f'parameters refused: {refused}')

    def _call(self, future):
        self._wait(future.done, CALL_TIMEOUT, 'a service answer')
        return future.result()

    def _wait(self, predicate, timeout, what):
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                raise LoopError(f'timed out waiting for {what}')
            self._spin(0.02)

    def _spin(self, seconds):
        end = time.monotonic() + seconds
        try:
            while time.monotonic() < end:
                self.executor.spin_once(timeout_sec=min(
                    0.02, max(end - time.monotonic(), 0.0)))
        except ExternalShutdownException:
            raise LoopError('the ROS context was shut down') from None


@contextmanager
def demo_loop(load=0, **options):
    """
    Give a demo its closed loop: an rclpy context of its own, ``load`` busy loops.

    ``options`` go to :class:`ClosedLoop`; every node must have exited 0
    afterwards (:meth:`ClosedLoop.check_exits`: a :class:`LoopError`).
    """
    context = rclpy.context.Context()
    rclpy.init(context=context)
    try:
        with busy_loops(load), ClosedLoop(context, **options) as loop:
            yield loop
        loop.check_exits()
    finally:
        rclpy.try_shutdown(context=context)


def median_runs(loop, name, cases, plant, repeats=3, report=None,
                enough=None):
    """
    Run each case ``repeats`` times, interleaved; return its median runs.

    ``cases``: ``{label: (feedforward, model)}`` for :meth:`ClosedLoop.run`
    of the motion ``name`` on ``plant``, each pass by
    :meth:`ClosedLoop.run_unspoiled`.
    Returns ``(medians, passes)``: ``{label: Run}``, the pass of median
    RMS error of each case, and ``{label: [Run, ...]}``, every pass. One
    pass over DDS varies severalfold with the machine's load (the pass's
    latency, which the error includes), the same for every model. ``report(text)``
    (optional) hears about every pass. ``enough(medians)`` (optional):
    when it is false after the first round, a second round of ``repeats``
    passes each, the medians then over both rounds.
    """
    passes = {label: [] for label in cases}
    for _ in range(repeats * (2 if enough else 1)):
        for label, (feedforward, model) in cases.items():
            run = loop.run_unspoiled(name, feedforward, plant=plant,
                                     model=model, report=report,
                                     case=f'{name}, {label}')
            if report:
                report(f'{name}, {label}: {run.samples} samples, position '
                       f'error RMS {run.rms_mm:.3f} mm, max {run.max_mm:.3f}'
                       ' mm' + (f', braked {run.braked}' if run.braked
                                else ''))
            passes[label].append(run)
        medians = {label: sorted(runs, key=lambda r: r.rms_mm)[
            len(runs) // 2] for label, runs in passes.items()}
        if enough and len(passes[label]) == repeats and enough(medians):
            break
    return medians, passes


def within_factor(label, reference, factor):
    """
    Return a :func:`median_runs` ``enough``: ``label`` within ``factor``.

    True when the median RMS error of ``label`` is at most ``factor`` times
    that of ``reference``.
    """
    return lambda medians: (medians[label].rms_mm
                            <= factor * medians[reference].rms_mm)


def rms_mm(run, start=0.0, end=math.inf):
    """Return the RMS position error (mm) of ``run`` from ``start`` to ``end`` s."""
    norm = np.linalg.norm(run.position_error, axis=1) * 1e3
    inside = (run.times >= start) & (run.times < end)
    return float(np.sqrt(np.mean(norm[inside] ** 2)))


def off_path_mm(run, direction, start=0.0, end=math.inf):
    """
    Return the RMS distance (mm) of ``run``'s platform from a straight path.

    The path: the line along ``direction`` (3,) that the motion follows
    (eq. (6)'s, along its target); from ``start`` to ``end`` s. The
    error's component across the path, which timing does not make: a
    sample late or early, a stall, a latency move the platform along its
    path, and only a force the model misses (a weight, an inertia) pushes
    it off.
    """
    along = np.asarray(direction, dtype=float)
    along = along / np.linalg.norm(along)
    inside = (run.times >= start) & (run.times < end)
    error = run.position_error[inside]
    across = error - np.outer(error @ along, along)
    return float(np.sqrt(np.mean(np.sum(across ** 2, axis=1)))) * 1e3


def robot_parameters(robot):
    """Return every ``robot.*`` parameter of ``robot`` (rclpy Parameters)."""
    return [Parameter(f'robot.{name}', value=value)
            for name, value in robot.as_parameters().items()]


def _tracking(label, recorder, motion, duration, period, told_ns=None):
    """
    Compare the recorded pass with the motion: a :class:`Run`.

    ``period``: the plant's step (s), for the time it skipped; ``told_ns``:
    when a pick-up's payload was acknowledged (node clock, ns; None: none).
    """
    if recorder.first_setpoint is None:
        raise LoopError(f'{label}: no setpoint seen')
    start = recorder.first_setpoint
    end = start + round(duration * 1e9)
    samples = [(s, lam, effort) for s, lam, effort in recorder.joints
               if start <= s <= end]
    if len(samples) < 10:
        raise LoopError(f'{label}: only {len(samples)} measurements')
    times = np.array([(s - start) * 1e-9 for s, _, _ in samples])
    lam = np.array([lam for _, lam, _ in samples])
    model = Robot()
    desired = np.array([motion.sample(t)[0] for t in times])
    desired_lam = mechanics.solve_batch(model, desired).lambda_
    position_error = mechanics.forward_kinematics(model, lam) - desired
    norm_mm = np.linalg.norm(position_error, axis=1) * 1e3
    efforts = np.array([effort for _, _, effort in samples])
    held = ~efforts.any(axis=1)
    started = int(np.argmin(held)) if not held.all() else len(held)
    return Run(label, times, position_error, lam - desired_lam,
               float(np.sqrt(np.mean(norm_mm ** 2))), float(norm_mm.max()),
               len(samples), start, lam, efforts,
               int(held[started:].sum()),
               float(np.clip(np.diff(times) - period, 0.0, None).sum()),
               None if told_ns is None else (told_ns - start) * 1e-9,
               longest_same_force(times, efforts, period))


def longest_same_force(times, efforts, period):
    """Return the longest stretch (s) of one unchanged nonzero effort row."""
    first = np.flatnonzero(np.r_[True, (np.diff(efforts, axis=0) != 0).any(
        axis=1)])
    last = np.r_[first[1:], len(times)] - 1
    applied = efforts[first].any(axis=1)
    if not applied.any():
        return 0.0
    return float((times[last] - times[first])[applied].max() + period)


def log_of(run):
    """
    Return a run's measurements as an ``identification.Log``.

    A segment per stretch the plant stepped without skipping time
    (:func:`joined`): across a skip (a simulator woken later than it can
    catch up with) the plant stood still while its stamps ran on, which no
    robot does, and the identification would interpolate a motion over it
    (doc/measurements.md, "Identification over DDS").
    """
    from orthoglide_ros.tools.identification import Log
    period = float(np.median(np.diff(run.times)))
    breaks = np.flatnonzero(np.diff(run.times) > SKIP_FACTOR * period) + 1
    return joined([Log(run.times[a:b], run.lambdas[a:b], run.efforts[a:b],
                       run.label)
                   for a, b in zip(np.r_[0, breaks],
                                   np.r_[breaks, len(run.times)])])


def joined(logs):
    """
    Return ``identification.Log`` s one after the other, a segment each.

    Each starts JOIN_GAP s after the one before ends: a gap that
    ``identification.prepare`` splits at.
    """
    from orthoglide_ros.tools.identification import Log
    times, offset = [], 0.0
    for log in logs:
        times.append(log.times - log.times[0] + offset)
        offset = times[-1][-1] + JOIN_GAP
    return Log(np.concatenate(times),
               np.concatenate([g.lambdas for g in logs]),
               np.concatenate([g.forces for g in logs]), logs[0].source)


def force_lag(plant_rate=PLANT_RATE):
    """
    Return how long before its stamp a state's effort was applied (s).

    The simulator publishes with each state the force it held over the
    step that led to it: on average half a step before the state.
    """
    return 0.5 / plant_rate
