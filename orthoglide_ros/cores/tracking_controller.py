"""
The tracking controller's logic without ROS: joint states in, forces out.

:class:`Tracking`: ``f_i = f_ff,i + Kp_i (lambda_d,i - lambda_i) + Kd_i
(lambdadot_d,i - lambdadot_i)``, clipped to its actuator's
``joint_limits.<joint>.max_effort`` (N), and a
joint trajectory followed as joint_trajectory_controller does
(doc/tracking_controller.md).
"""

from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.cores.inputs import (JointValues, read_joint_state,
                                         read_joint_trajectory, Rejected)
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.mechanics import ZERO
from orthoglide_ros.model.joint_plan import JointPlan
from orthoglide_ros.model.robot import JOINT_NAMES
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import (
    arrival_timeout_spec, every_joint, joint_limit, joint_limit_name,
    joint_limit_specs, joint_limits_rule, joint_names_spec,
    nonnegative_triple, Spec, Table)
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.status import ERROR, OK, WARN

# The drives it commands: each saturates at 1000 N (the simulator's).
DRIVES = every_joint(max_effort=1000.0)
# The effort limits' names, as a refusal says them.
EFFORT_NAMES = tuple(f'joint_limits.{joint}.max_effort'
                     for joint in JOINT_NAMES)
INPUTS = ('desired', 'measured', 'trajectory')
REASONS = ('missing_joint', 'malformed', 'missing_position',
           'missing_velocity', 'missing_effort', 'non_finite',
           'position_limit', 'velocity_limit', 'effort_limit', 'overflow',
           'oversize', 'empty', 'time')
SKIPS = ('no_measurement', 'stale_measurement', 'trajectory_active',
         'inactive')
FOLLOWING, HOLDING = 'following', 'holding'
# Largest |lambdadot_d - lambdadot| (m/s) of a desired state that re-arms.
REARM_SPEED = 0.01

PARAMETERS = Table('ControllerSettings', (
    Spec('kp', 'double_array', [20000.0, 20000.0, 20000.0],
         'proportional gains of actuators A, B, C in joint_names order '
         '(N/m): three finite values >= 0', check=nonnegative_triple),
    Spec('kd', 'double_array', [1200.0, 1200.0, 1200.0],
         'derivative gains of actuators A, B, C in joint_names order '
         '(N s/m): three finite values >= 0', check=nonnegative_triple),
    Spec('feedforward', 'bool', True,
         'add the desired effort (feedforward force, N) to the PD output; '
         'false: PD alone, desired efforts not needed'),
    *joint_limit_specs(DRIVES, {
        'max_effort': 'a command beyond it is clipped to it and counted; '
                      'a desired effort beyond it is refused (effort_limit)'
    }),
    joint_names_spec(
        'names of the prismatic joints of actuators A, B, C: the order of '
        'the command\'s values; joint states are matched by these names'),
    arrival_timeout_spec('measurement_timeout', 0.05, 0.0001,
                         'after which a measurement is too old to compute a '
                         'command with: nothing is published until a fresh '
                         'one arrives'),
    Spec('rate_hz', 'double', 250.0,
         'loop rate (Hz) at which a received joint_trajectory is sampled '
         'and a command published while it is followed',
         (1.0, 2000.0)),
    Spec('path_tolerance', 'double_array', [0.05, 0.05, 0.05],
         'largest |lambda_d - lambda| per actuator A, B, C (m) while '
         'following; beyond it the controller holds the measured position '
         '(ERROR) until a desired state comes within half of it; 0.0: no '
         'limit for that actuator', check=nonnegative_triple),
    arrival_timeout_spec('stall_timeout', 0.1, 0.0,
                         'between two commands while following beyond which '
                         'the loop stalled: the next desired state is '
                         'followed only if it starts where the robot is (the '
                         're-arm rule of path_tolerance), else the controller '
                         'holds the measured position (ERROR) until one '
                         'does; 0.0: off'),
    Spec('max_position', 'double', 1.5,
         'largest |lambda| (m) of a measured or desired slider position, '
         'trajectory points included: a joint state or trajectory beyond '
         'it is refused (position_limit); the paper\'s robot reaches '
         '-0.80 to 1.27 m within the default singularity margin',
         (0.001, 100.0)),
    Spec('max_velocity', 'double', 2.0,
         'largest |lambdadot| (m/s) of a measured or desired slider '
         'velocity, a joint trajectory\'s planned motion included: beyond '
         'it the input is refused (velocity_limit)', (0.001, 1000.0)),
    *realtime.SPECS,
), rules=(joint_limits_rule,), robot=True,
    retired={'force_limit': joint_limit_name('max_effort')})

Command = namedtuple('Command', 'force error clipped')
Command.__doc__ = """One command: ``force`` the 3 forces (N) after
clipping, ``error`` lambda_d - lambda (m), ``clipped`` how many of the three
were clipped."""


def control_law(settings, desired, measured):
    """
    Return the :class:`Command` of one desired state and measurement.

    ``f = f_ff + Kp (lambda_d - lambda) + Kd (lambdadot_d - lambdadot)``
    per actuator (f_ff omitted when ``settings.feedforward`` is off), then
    clipped to +-``joint_limits.<joint>.max_effort``. Raises
    :class:`Rejected` (``overflow``) if a force before clipping is not
    finite.
    """
    forces = []
    errors = []
    clipped = 0
    for i, limit in enumerate(joint_limit(settings, 'max_effort')):
        error = desired.position[i] - measured.position[i]
        force = settings.kp[i] * error + settings.kd[i] * (
            desired.velocity[i] - measured.velocity[i])
        if settings.feedforward:
            force = desired.effort[i] + force
        if not math.isfinite(force):
            raise Rejected('overflow', (
                f'force of {settings.joint_names[i]!r} overflows: '
                f'error {error!r} m'))
        if force > limit:
            force, clipped = limit, clipped + 1
        elif force < -limit:
            force, clipped = -limit, clipped + 1
        forces.append(force)
        errors.append(error)
    return Command(tuple(forces), tuple(errors), clipped)


class Tracking(Core):
    """
    Inputs, freshness, the law and the counters of the tracking controller.

    The core of :mod:`orthoglide_ros.cores.core`: every method takes
    ``now``, a monotonic time in seconds, so tests can drive time.
    :meth:`desired` and :meth:`tick` return the :class:`Command` to
    publish or None (skipped); the inputs raise :class:`Rejected`, already
    counted.
    """

    INPUTS = INPUTS
    REASONS = REASONS
    REJECTED_BY_INPUT = True

    def __init__(self, settings, now=0.0):
        super().__init__(settings, now)
        self.measurement = None
        self.measurement_arrival = None
        self.latest = None
        self.skipped = dict.fromkeys(SKIPS, 0)
        self.commands = 0
        self.clipped = 0
        self.mode = FOLLOWING
        self.trips = 0
        self.stalls = 0
        self._last_command = None   # monotonic time of the last command
        self.hold = None            # JointValues held while holding
        self.hold_message = None    # why it holds
        self._bias = None           # the last force sent while following
        self.plan = None            # the joint trajectory followed, if any
        self.plan_finished = False  # past its last point (holding it)
        self.trajectories = 0
        self.superseded = 0
        self._incoming = None       # a trajectory waiting for the next tick
        self._accepted = None       # monotonic time of the last acceptance
        self.hold_is_fault = True  # holding after a trip or a stall

    def configure(self, settings):
        """
        Use new settings from the next message on.

        New joint names also forget the measurement, read by the old ones.
        """
        if settings.joint_names != self.settings.joint_names:
            self.measurement = self.measurement_arrival = None
        self.settings = settings

    def deactivate(self):
        """
        Stop commanding at once: inputs are still read and counted.

        The trajectory followed is dropped, and the controller holds its
        last safe command: the position measured now with the bias of the
        last command that clipped nothing (:meth:`_hold`). Activated again,
        it commands that hold until a desired state starts where the robot
        is (the re-arm rule): a stream that moved on meanwhile is not
        chased.
        """
        self.active = False
        self.plan = self._incoming = None
        self.plan_finished = False
        if self.measurement is not None:
            self._hold(JointValues(self.measurement.position, ZERO, ZERO),
                       'deactivated', fault=False)

    def activate(self):
        """Command again (holding first if :meth:`deactivate` held)."""
        self.active = True

    def measured(self, stamp, frame, names, position, velocity, effort, now):
        """
        Take a measured joint state; it becomes the newest measurement.

        The fields of a JointState (``stamp`` and ``frame`` not used), as
        :func:`orthoglide_ros.formats.cdr.joint_state` reads them.
        """
        self.received['measured'] += 1
        values = self._read('measured', names, position, velocity, effort,
                            False)
        self.measurement = values
        self.measurement_arrival = now

    def desired(self, stamp, frame, names, position, velocity, effort, now):
        """
        Take a desired joint state; return its Command, or None if skipped.

        The fields of a JointState, as for :meth:`measured`.
        Skipped (and counted) when no measurement is fresh: none yet
        (``no_measurement``) or older than measurement_timeout
        (``stale_measurement``), or while a joint trajectory runs
        (``trajectory_active``); once it has ended, a desired state ends it.
        """
        self.received['desired'] += 1
        settings = self.settings
        values = self._read('desired', names, position, velocity, effort,
                            settings.feedforward)
        if self.plan is not None:
            if not self.plan_finished:
                self.skipped['trajectory_active'] += 1
                return None
            self.plan = None
        return self._command('desired', values, now)

    def trajectory(self, points, clock, now):
        """
        Take a joint trajectory; it replaces any other, from its own start.

        ``points``: :class:`orthoglide_ros.formats.cdr.JointPoints`; ``clock``: the
        node clock now (s), the start when the header stamp is zero (else
        the stamp). Refused (counted, raised) by
        :func:`read_joint_trajectory` and the bounds of :func:`_bounded`,
        or as ``time`` when a non-zero stamp makes it end before ``clock``
        (as joint_trajectory_controller refuses it). Accepted at once
        (:meth:`_accept`) unless one was accepted less than ``1 / rate_hz``
        ago: then it waits for the next :meth:`tick`.
        """
        self.received['trajectory'] += 1
        settings = self.settings
        try:
            times, positions, velocities, efforts = read_joint_trajectory(
                settings.joint_names, points, settings.feedforward)
            _bounded(settings, positions, velocities,
                     efforts if settings.feedforward else None)
            sec, nanosec = points.stamp
            start = clock if (sec, nanosec) == (0, 0) \
                else sec + nanosec * 1e-9
            if (sec, nanosec) != (0, 0) and start + times[-1] < clock:
                raise Rejected('time', (
                    f'it ends in the past: its last point at '
                    f'{start + times[-1]:.9f} s, received at {clock:.9f} s '
                    '(node clock)'))
        except Rejected as rejection:
            self.count('trajectory', rejection)
            raise
        if not self.active:
            self.skipped['inactive'] += 1
            return
        if self._incoming is not None:
            self.superseded += 1
        self._incoming = (start, times, positions, velocities, efforts)
        if (self._accepted is None
                or now - self._accepted >= 1.0 / settings.rate_hz):
            self._accept(clock, now)

    def _accept(self, clock, now):
        """
        Make the waiting trajectory the plan, from the state at ``clock``.

        From the desired state of the plan being followed, if any (a
        replacement); else from the newest measurement when it is fresh,
        else from the first point at rest, with the force that holds the
        robot (:meth:`_held_force`). Refused (``velocity_limit``, counted,
        raised) when the plan's motion exceeds ``max_velocity``.
        """
        start, times, positions, velocities, efforts = self._incoming
        self._incoming = None
        if self.plan is not None and self.mode == FOLLOWING:
            state = self.plan.sample(clock)
        else:
            held = self._held_force(tuple(efforts[0]))
            state = (self.measurement.position, self.measurement.velocity,
                     held) if self.fresh(now) else (tuple(positions[0]),
                                                    ZERO, held)
        plan = JointPlan(start, times, positions, velocities, efforts,
                         state, clock)
        peak, joint = plan.peak_velocity()
        if peak > self.settings.max_velocity:
            self.refuse('trajectory', 'velocity_limit', (
                f'its motion from the current state needs {peak:.4g} m/s on '
                f'{self.settings.joint_names[joint]!r}, beyond max_velocity '
                f'{self.settings.max_velocity:g} m/s'))
        self.plan = plan
        self.plan_finished = False
        self.trajectories += 1
        self._accepted = now

    def tick(self, clock, now):
        """
        Sample the joint trajectory; return its Command.

        ``clock``: the node clock now (s); ``now``: the monotonic time.
        A trajectory waiting since :meth:`trajectory` is accepted first
        (raising its refusal, if any). The plan is sampled at the instant
        the newest measurement arrived (``clock`` less its age), as
        joint_trajectory_controller samples its trajectory at the instant
        it read the state interfaces: the desired and the measured state
        then describe the same instant. None when no trajectory is
        followed or no measurement is fresh (skipped, counted). The same
        law and path tolerance as a desired state's.
        """
        if self._incoming is not None:
            self._accept(clock, now)
        if self.plan is None:
            return None
        if self.measurement_arrival is not None:
            clock -= now - self.measurement_arrival
        self.plan_finished = self.plan.finished(clock)
        position, velocity, effort = self.plan.sample(clock)
        payload = self.settings.robot.payload
        if payload and self.settings.feedforward:
            try:
                carried = mechanics.payload_force(
                    self.settings.robot, payload, position, velocity,
                    self.plan.acceleration(clock))
            except mechanics.WorkspaceError as error:
                self.refuse('trajectory', 'position_limit', (
                    f'the payload\'s force is undefined at lambda '
                    f'{mechanics.format_vector(position)} m: {error}'))
            effort = tuple(e + c for e, c in zip(effort, carried))
        return self._command('trajectory', JointValues(
            position, velocity, effort), now)

    def _held_force(self, effort):
        """
        Return the force that holds the robot where it is (N, 3-tuple).

        The last command sent while following that clipped no force;
        before any, ``effort`` (the desired one) with the feedforward on,
        else zero.
        """
        return tuple(self._bias or (effort if self.settings.feedforward
                                    else ZERO))

    def _command(self, source, values, now):
        """Apply the law to one desired state of ``source`` (None: skipped)."""
        settings = self.settings
        if not self.active:
            self.skipped['inactive'] += 1
            return None
        if self.measurement is None:
            self.skipped['no_measurement'] += 1
            return None
        if not self.fresh(now):
            self.skipped['stale_measurement'] += 1
            return None
        stall = settings.stall_timeout
        if (stall and self.mode == FOLLOWING and self._last_command is not None
                and now - self._last_command > stall
                and not self._starts_here(values)):
            self.stalls += 1
            self._hold(values, (
                f'holding: no command for {now - self._last_command:.3g} s '
                f'(stall_timeout {stall:g} s) and the desired state does not '
                'start where the robot is'))
        self._check_path(values)
        try:
            if self.mode == HOLDING:
                command = control_law(settings._replace(feedforward=True),
                                      self.hold, self.measurement)
            else:
                command = control_law(settings, values, self.measurement)
                if not command.clipped:
                    self._bias = command.force
        except Rejected as rejection:
            self.count(source, rejection)
            raise
        self.commands += 1
        self._last_command = now
        self.clipped += command.clipped
        self.latest = command
        return command

    def _check_path(self, desired):
        """Trip to holding, or re-arm, by the path tolerance (see above)."""
        settings = self.settings
        if self.mode == HOLDING:
            if self._starts_here(desired):
                self.mode, self.hold, self.hold_message = FOLLOWING, None, None
            return
        errors = [d - m for d, m in zip(desired.position,
                                        self.measurement.position)]
        tolerance = settings.path_tolerance
        beyond = [i for i, (e, t) in enumerate(zip(errors, tolerance))
                  if t > 0.0 and abs(e) > t]
        if not beyond:
            return
        i = beyond[0]
        self.trips += 1
        self._hold(desired, (
            f'holding: path tolerance exceeded on '
            f'{settings.joint_names[i]!r} (desired - measured = '
            f'{errors[i]:.4g} m, path_tolerance {tolerance[i]:g} m)'))

    def _starts_here(self, desired):
        """
        Whether ``desired`` starts where the robot is (the re-arm rule).

        Within half of path_tolerance of the measured position (any
        position where it is 0.0) and within REARM_SPEED of the measured
        velocity, on every actuator.
        """
        measured = self.measurement
        return all((t == 0.0 or abs(d - m) <= 0.5 * t)
                   and abs(v - w) <= REARM_SPEED
                   for d, m, t, v, w in zip(
                       desired.position, measured.position,
                       self.settings.path_tolerance, desired.velocity,
                       measured.velocity))

    def _hold(self, desired, why, fault=True):
        """
        Hold the measured position, with the bias of :meth:`_held_force`.

        ``fault``: a trip or a stall (ERROR in the status), else a
        deactivation (WARN once active again).
        """
        measured = self.measurement.position
        self.mode = HOLDING
        self.hold_is_fault = fault
        self.hold = JointValues(measured, ZERO,
                                self._held_force(desired.effort))
        self.hold_message = (
            f'{why}; holds lambda = {[round(x, 6) for x in measured]} m, '
            're-arms on a desired state within half of path_tolerance and '
            f'{REARM_SPEED:g} m/s of the measured state')

    @property
    def idle(self):
        """Whether no joint trajectory is followed or waiting."""
        return self.plan is None and self._incoming is None

    def fresh(self, now):
        """Whether the newest measurement arrived within the timeout."""
        return (self.measurement_arrival is not None
                and now - self.measurement_arrival
                <= self.settings.measurement_timeout)

    # Status: ERROR after an internal error or while holding (path
    # tolerance exceeded, or a stall); WARN when desired states were
    # skipped (no fresh measurement) or joint states rejected in the
    # period; else OK (``waiting for desired states`` until one came).
    def inactive_message(self):
        """Return the inactive message, with the hold if any."""
        return self.INACTIVE + (f' ({self.hold_message})'
                                if self.mode == HOLDING else '')

    def period_counters(self):
        """Return the counters of the period's rates."""
        return dict(commands=self.commands,
                    skipped=sum(self.skipped.values()))

    def status_rules(self, now, seconds, increases):
        """Return the hold, skips, rejections and the wait steps."""
        age = self._age(now)
        what = 'no measurement yet' if age is None \
            else f'newest measurement {age:.3f} s old'
        return (
            (self.mode == HOLDING, ERROR if self.hold_is_fault else WARN,
             self.hold_message),
            (increases['skipped'], WARN,
             f'{increases["skipped"]} desired state(s) without a fresh '
             f'measurement ({what}): nothing commanded'),
            (increases['rejected'], WARN,
             f'{increases["rejected"]} joint state(s) rejected in the last '
             'period'),
            (self.received['desired'] == 0 and self.plan is None, OK,
             'waiting for desired states'))

    def values(self, now, seconds, increases):
        """Return the rates, errors, skips, trajectory and mode values."""
        settings = self.settings
        age = self._age(now)
        errors = self.latest.error if self.latest is not None \
            else (math.nan,) * 3
        values = [
            ('command rate (Hz)', increases['commands'] / seconds),
            ('commands published', self.commands),
            ('clipped forces', self.clipped),
            ('time since last measurement (s)',
             age if age is not None else math.nan),
            ('measurement fresh', self.fresh(now)),
        ]
        values += [(f'tracking error {name} (m)', e)
                   for name, e in zip(settings.joint_names, errors)]
        values += [(f'skipped {s}', self.skipped[s]) for s in SKIPS]
        values += [
            ('trajectory', 'none' if self.plan is None else
             'holding its last point' if self.plan_finished else 'running'),
            ('trajectories received', self.trajectories),
            ('trajectories superseded', self.superseded),
            ('mode', self.mode),
            ('path tolerance trips', self.trips),
            ('stall holds', self.stalls),
            ('feedforward', settings.feedforward),
            ('payload (kg)', settings.robot.payload),
            ('max_effort A, B, C (N)', ', '.join(
                f'{limit:.6g}' for limit in joint_limit(settings,
                                                        'max_effort'))),
        ]
        return values

    def _age(self, now):
        return None if self.measurement_arrival is None \
            else now - self.measurement_arrival

    def _read(self, source, names, position, velocity, effort, need_effort):
        settings = self.settings
        try:
            values = read_joint_state(settings.joint_names, names, position,
                                      velocity, effort, need_effort)
            _bounded(settings, values.position, values.velocity,
                     values.effort if need_effort else None)
        except Rejected as rejection:
            self.count(source, rejection)
            raise
        return values


def _bounded(settings, positions, velocities, efforts):
    """
    Refuse values beyond the plausibility bounds, naming the joint.

    ``positions``, ``velocities``, ``efforts`` (None: not checked): a
    joint state's 3-tuples (m, m/s, N; plain floats, the per-message
    path) or a trajectory's (N, 3) arrays, bounded in magnitude by
    ``max_position``, ``max_velocity`` and each actuator's
    ``joint_limits.<joint>.max_effort`` (an effort it could not command
    is not plausible). Raises :class:`Rejected` (``position_limit``,
    ``velocity_limit``, ``effort_limit``), not counted here.
    """
    for reason, values, bounds, names, unit in (
            ('position_limit', positions, (settings.max_position,) * 3,
             ('max_position',) * 3, 'm'),
            ('velocity_limit', velocities, (settings.max_velocity,) * 3,
             ('max_velocity',) * 3, 'm/s'),
            ('effort_limit', efforts, joint_limit(settings, 'max_effort'),
             EFFORT_NAMES, 'N')):
        if values is None:
            continue
        if isinstance(values, np.ndarray):
            beyond = np.argwhere(np.abs(values) > np.asarray(bounds))
            if not len(beyond):
                continue
            point, joint = beyond[0]
            where, value = f'point {point}: ', values[point, joint]
        else:
            joint = next((j for j, v in enumerate(values)
                          if abs(v) > bounds[j]), None)
            if joint is None:
                continue
            where, value = '', values[joint]
        raise Rejected(reason, (
            f'{where}{settings.joint_names[joint]!r} at {value:.4g} {unit}, '
            f'beyond {names[joint]} {bounds[joint]:g} {unit}'))
