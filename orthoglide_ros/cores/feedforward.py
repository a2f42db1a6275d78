"""
The feedforward's logic without ROS: setpoints in, joint targets out.

:class:`Feedforward` pairs, checks and solves each setpoint (eqs.
(9)-(25)); :func:`convert_trajectory` converts a whole Cartesian
trajectory, all or nothing. The rules: doc/feedforward.md.
"""

from collections import namedtuple
import math
import time

import numpy as np

from orthoglide_ros.model.mechanics import ZERO
from orthoglide_ros.cores import realtime, setpoint_rules
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.inputs import (check_stamp, check_time,
                                         NANOSECONDS, Rejected,
                                         trajectory_times)
from orthoglide_ros.cores.parameters import (
    arrival_timeout_spec, at_most, base_frame_spec, every_joint,
    joint_limit_name, joint_limit_specs, joint_limits_rule,
    joint_names_spec, singularity_margin_spec, Spec, Table)
from orthoglide_ros.cores.status import OK, WARN

# Most partial setpoints held at once; beyond, the oldest is dropped.
MAX_PENDING = 1000
# Period of the tick while rate_hz is 0.0 (it then only waits), s.
IDLE_TICK = 0.1
# Why a whole Cartesian trajectory was refused: 'rejected trajectory <r>'.
TRAJECTORY_REASONS = ('empty', 'frame', 'stamp', 'time', 'malformed',
                      'orientation', 'non_finite', 'speed_limit',
                      'acceleration_limit', 'unreachable', 'singular',
                      'overflow', 'velocity_limit', 'force_limit', 'oversize')

REASONS = ('non_finite', 'speed_limit', 'acceleration_limit', 'unreachable',
           'singular', 'overflow', 'velocity_limit', 'force_limit', 'frame',
           'orientation', 'stamp', 'malformed', 'oversize', 'unpaired')
INPUTS = ('pose', 'twist', 'accel', 'trajectory', 'cartesian_trajectory')

Conversion = namedtuple('Conversion', 'stamp frame time solution')
Conversion.__doc__ = """A converted Cartesian trajectory.

``stamp`` (sec, nanosec) and ``frame`` of its header, unchanged; ``time``
(N, 2) the points' time_from_start (sec, nanosec); ``solution`` the
:class:`mechanics.Solution` of the N points, (N, 3) arrays."""

Output = namedtuple('Output', 'stamp solution')
Output.__doc__ = """A result: ``stamp`` (sec, nanosec) of its setpoint and
the :class:`mechanics.Solution`."""


def convert_trajectory(settings, waypoints):
    """
    Convert every point of a Cartesian trajectory, or refuse it whole.

    ``waypoints``: :class:`orthoglide_ros.formats.cdr.Waypoints`. The first
    rule broken (doc/feedforward.md#whole-trajectories, in its order:
    ``empty``, ``frame``, ``stamp``, ``malformed``, ``time``, then
    :func:`setpoint_rules.solve_setpoints`) raises :class:`Rejected` with a
    reason of TRAJECTORY_REASONS and, where a point is at fault, its 0-based
    index. Returns a :class:`Conversion`.
    """
    w = waypoints
    if len(w.time) == 0:
        raise Rejected('empty', 'trajectory without points')
    setpoint_rules.check_frame(w.frame, settings, 'trajectory')
    check_stamp(w.stamp, zero_allowed=True)
    _first_bad('malformed', ~w.transform, 'has no transform')
    velocity, acceleration = w.linear_velocity, w.linear_acceleration
    if settings.pose_only:
        velocity = np.where(w.velocity[:, None], velocity, 0.0)
        acceleration = np.where(w.acceleration[:, None], acceleration, 0.0)
    else:
        _first_bad('malformed', ~w.velocity, 'has no velocity (set '
                   'pose_only to take it as zero)')
        _first_bad('malformed', ~w.acceleration, 'has no acceleration (set '
                   'pose_only to take it as zero)')
    trajectory_times(w.time)
    with np.errstate(all='ignore'):     # a NaN or an inf: refused inside
        solution = setpoint_rules.solve_setpoints(
            settings, w.position, velocity, acceleration, w.orientation,
            setpoint_rules.N_POINTS)
    return Conversion(w.stamp, w.frame, w.time, solution)


# The actuators' limits by default: every force within 10 kN (about 40
# times the paper's largest), a plausibility bound until the drives'
# ratings are set; no velocity limit.
LIMITS = every_joint(max_effort=10000.0)


def _first_bad(reason, bad, what):
    """Raise Rejected(reason) naming the first point where ``bad``."""
    if bad.any():
        raise Rejected(reason, f'point {int(np.argmax(bad))} {what}')


PARAMETERS = Table('Settings', (
    joint_names_spec('names of the prismatic joints of actuators A, B, C '
                     'in feedforward/joint_states'),
    base_frame_spec('frame of the setpoints (the paper\'s frame 0); a '
                    'setpoint stamped with another non-empty frame is '
                    'rejected'),
    Spec('rate_hz', 'double', 0.0,
         'control tick in Hz: 0.0 computes and publishes once per new '
         'setpoint; a positive value publishes the newest setpoint\'s '
         'result at this fixed rate', (0.0, 10000.0)),
    arrival_timeout_spec('setpoint_timeout', 0.1, 0.001,
                         'without a fresh setpoint after which the node '
                         'stops publishing until the next fresh setpoint'),
    Spec('pairing_timeout', 'double', 0.05,
         'seconds a partial setpoint (pose, twist or accel of one stamp) '
         'waits for its partners before it is dropped; at most '
         'setpoint_timeout', (0.0001, 3600.0)),
    singularity_margin_spec(
        'smallest accepted singularity distance, min(alpha_i / L_i, '
        '1 / kappa_F(J_lambda)) with L_i leg i\'s bar length, both 1 at '
        'the drawing\'s home and 0 at a singularity of J1 or J2'),
    Spec('pose_only', 'bool', False,
         'serve each pose alone as a setpoint with zero velocity and '
         'acceleration (twist and accel topics ignored); trajectory points '
         'may then omit velocities and accelerations'),
    Spec('max_speed', 'double', 5.0,
         'largest speed |v| of G (m/s) of a setpoint or a trajectory point: '
         'one beyond it is refused (speed_limit)', (0.001, 1000.0)),
    Spec('max_acceleration', 'double', 100.0,
         'largest acceleration |a| of G (m/s^2) of a setpoint or a '
         'trajectory point: one beyond it is refused (acceleration_limit)',
         (0.001, 1.0e5)),
    *joint_limit_specs(LIMITS, {
        'max_velocity': 'a setpoint or trajectory point that needs more is '
                        'refused (velocity_limit)',
        'max_effort': 'a setpoint or trajectory point that needs more is '
                      'refused (force_limit): no force beyond it is '
                      'published'}),
    *realtime.SPECS,
), rules=(at_most('pairing_timeout', 'setpoint_timeout', 's'),
          joint_limits_rule), robot=True, retired={
    'velocity_limit': joint_limit_name('max_velocity'),
    'force_limit': joint_limit_name('max_effort'),
    'max_force': joint_limit_name('max_effort')})


class Feedforward(Core):
    """
    Pairing, checks, mechanics and counters of the feedforward node.

    The core of :mod:`orthoglide_ros.cores.core`: every method takes
    ``now``, a monotonic time in seconds, so tests can drive time. The
    input methods return the :class:`Output` to publish at once (with
    ``rate_hz`` 0.0; else None, :meth:`tick` publishes) or raise
    :class:`Rejected`, already counted.
    """

    INPUTS = INPUTS
    REASONS = REASONS

    def __init__(self, settings, now=0.0):
        super().__init__(settings, now)
        self.latest = None
        self.latest_arrival = None
        self.computed = 0
        self.compute_ns_total = 0
        self.compute_ns_max = 0
        self.published = 0
        self.trajectories = 0           # Cartesian trajectories converted
        self.trajectory_points = 0
        self.trajectory_seconds = math.nan      # the last one's, s
        self.trajectory_seconds_max = 0.0       # the period's largest, s
        self.trajectory_rejected = dict.fromkeys(TRAJECTORY_REASONS, 0)
        self.withheld = 0       # outputs not published while inactive
        self._pending = {}

    def pose(self, stamp, frame, position, orientation, now):
        """Take a pose of G (m) and the platform orientation (quaternion)."""
        self.received['pose'] += 1
        if self.settings.pose_only:
            self._check_stamp(stamp)
            return self._complete(stamp, (frame,), position, ZERO, ZERO,
                                  orientation, now)
        return self._part(stamp, 0, (frame, position, orientation), now)

    def twist(self, stamp, frame, velocity, now):
        """Take the linear velocity of G (m/s); ignored with pose_only."""
        self.received['twist'] += 1
        if not self.settings.pose_only:
            return self._part(stamp, 1, (frame, velocity), now)
        return None

    def accel(self, stamp, frame, acceleration, now):
        """Take the linear acceleration of G (m/s^2); ignored with pose_only."""
        self.received['accel'] += 1
        if not self.settings.pose_only:
            return self._part(stamp, 2, (frame, acceleration), now)
        return None

    def trajectory_point(self, stamp, frame, position, orientation,
                         velocity, acceleration, now):
        """
        Take one atomic setpoint; ``velocity``/``acceleration`` may be None.

        A point without velocity or acceleration is ``malformed`` unless
        ``pose_only`` lets them be zero. ``stamp`` (header stamp plus
        ``time_from_start``) must be a valid stamp as for the other inputs.
        """
        self.received['trajectory'] += 1
        self._check_stamp(stamp)
        if velocity is None or acceleration is None:
            if not self.settings.pose_only:
                self.refuse('trajectory', 'malformed', (
                    'trajectory point without velocities or accelerations '
                    '(set pose_only to accept them as zero)'))
            velocity = velocity or ZERO
            acceleration = acceleration or ZERO
        return self._complete(stamp, (frame,), position, velocity,
                              acceleration, orientation, now)

    def trajectory_message(self, header_stamp, time_from_start, clock_stamp,
                           frame, position, orientation, velocity,
                           acceleration, now):
        """
        Take a trajectory message's point: its stamp, then the setpoint.

        The point's stamp is ``header_stamp + time_from_start``, both
        ``(sec, nanosec)`` valid times (:func:`check_time`); a zero header
        stamp means "now", ``clock_stamp`` (the node's clock at arrival),
        as for ``trajectory_msgs`` in general. Then as
        :meth:`trajectory_point`.
        """
        try:
            check_time('header stamp', *header_stamp)
            check_time('time_from_start', *time_from_start)
        except Rejected as rejection:
            self.reject('trajectory', rejection)
            raise
        if header_stamp == (0, 0):
            header_stamp = clock_stamp
        stamp = divmod((header_stamp[0] + time_from_start[0]) * NANOSECONDS
                       + header_stamp[1] + time_from_start[1], NANOSECONDS)
        return self.trajectory_point(stamp, frame, position, orientation,
                                     velocity, acceleration, now)

    def cartesian_trajectory(self, conversion, converted, now):
        """
        Take a converted Cartesian trajectory; return ``converted`` to publish.

        ``conversion``: its :class:`Conversion`; ``converted``: what the
        node publishes (the JointTrajectory, serialized); ``now``: its
        arrival, so that the time to its publication (the node's side of
        a conversion: reading, the kernel, writing) is counted. None
        (withheld) while inactive.
        """
        self.received['cartesian_trajectory'] += 1
        if not self.active:
            self.withheld += 1
            return None
        seconds = time.monotonic() - now
        self.trajectories += 1
        self.trajectory_points += len(conversion.time)
        self.trajectory_seconds = seconds
        self.trajectory_seconds_max = max(self.trajectory_seconds_max,
                                          seconds)
        return converted

    def count(self, source, rejection):
        """Count a refusal: a whole trajectory's apart from setpoints'."""
        if source == 'cartesian_trajectory':
            self.trajectory_rejected[rejection.reason] += 1
        else:
            super().count(source, rejection)

    def expire(self, now):
        """Drop the partial setpoints older than pairing_timeout; count them."""
        limit = now - self.settings.pairing_timeout
        pending = self._pending
        dropped = 0
        while pending:      # oldest first: the dict keeps arrival order
            stamp = next(iter(pending))
            if pending[stamp][3] >= limit and len(pending) <= MAX_PENDING:
                break
            del pending[stamp]
            dropped += 1
        self.rejected['unpaired'] += dropped
        return dropped

    def fresh(self, now):
        """Whether the newest result's setpoint arrived within the timeout."""
        return (self.latest_arrival is not None
                and now - self.latest_arrival <= self.settings.setpoint_timeout)

    def tick(self, now):
        """
        Return the result to publish at a tick of the fixed rate, or None.

        None with ``rate_hz`` 0.0 (each setpoint is published as it
        completes) or when no result is fresh (:meth:`fresh`). Counted as
        published; withheld while inactive.
        """
        if self.settings.rate_hz == 0.0 or not self.fresh(now):
            return None
        return self._published(self.latest)

    def _published(self, output):
        """Count ``output`` as published and return it; withheld if inactive."""
        if not self.active:
            self.withheld += 1
            return None
        self.published += 1
        return output

    def tick_period(self):
        """Return the tick's period (s): 1 / rate_hz, IDLE_TICK at 0.0."""
        rate = self.settings.rate_hz
        return 1.0 / rate if rate > 0.0 else IDLE_TICK

    @property
    def pending(self):
        """Count the partial setpoints waiting for partners."""
        return len(self._pending)

    # Status: ERROR after an internal error; WARN when setpoints or
    # trajectories were rejected in the period, or when stale; else OK
    # (``waiting for the first setpoint`` until there is one).
    def period_counters(self):
        """Return the counters of the period's rates."""
        return dict(published=self.published, computed=self.computed,
                    compute_ns=self.compute_ns_total,
                    trajectories_rejected=sum(
                        self.trajectory_rejected.values()))

    def status_rules(self, now, seconds, increases):
        """Return the rejections, the wait and staleness steps."""
        age = self._age(now)
        return (
            (increases['rejected'], WARN,
             f'{increases["rejected"]} setpoint(s) rejected in the last '
             'period'),
            (increases['trajectories_rejected'], WARN,
             f'{increases["trajectories_rejected"]} trajectory(ies) '
             'rejected in the last period'),
            (age is None, OK, 'waiting for the first setpoint'),
            (not self.fresh(now), WARN,
             f'stale: no fresh setpoint for {age or 0.0:.2f} s, outputs '
             'stopped'))

    def values(self, now, seconds, increases):
        """Return the rates, compute times and counters (maxima restart)."""
        age = self._age(now)
        mean_us = increases['compute_ns'] / increases['computed'] / 1e3 \
            if increases['computed'] else 0.0
        distance = self.latest.solution.singularity_distance \
            if self.latest is not None else math.nan
        values = [
            ('tick rate (Hz)', increases['published'] / seconds),
            ('compute time mean (us)', mean_us),
            ('compute time max (us)', self.compute_ns_max / 1e3),
            ('setpoints computed', self.computed),
            ('outputs published', self.published),
            ('outputs withheld (inactive)', self.withheld),
            ('stale', not self.fresh(now)),
            ('time since last setpoint (s)',
             age if age is not None else math.nan),
            ('singularity distance', distance),
            ('singularity margin', self.settings.singularity_margin),
            ('payload (kg)', self.settings.robot.payload),
            ('pending partial setpoints', self.pending),
            ('rate_hz', self.settings.rate_hz),
            ('trajectories converted', self.trajectories),
            ('trajectory points converted', self.trajectory_points),
            ('trajectory receive to publish last (ms)',
             self.trajectory_seconds * 1e3),
            ('trajectory receive to publish max (ms)',
             self.trajectory_seconds_max * 1e3),
        ]
        values += [(f'rejected trajectory {r}', self.trajectory_rejected[r])
                   for r in TRAJECTORY_REASONS]
        self.trajectory_seconds_max = 0.0
        self.compute_ns_max = 0
        return values

    def _age(self, now):
        return None if self.latest_arrival is None \
            else now - self.latest_arrival

    def _check_stamp(self, stamp):
        try:
            check_stamp(stamp)
        except Rejected as rejection:
            self.count('stamp', rejection)
            raise

    def _part(self, stamp, slot, value, now):
        self._check_stamp(stamp)
        self.expire(now)
        entry = self._pending.get(stamp)
        if entry is None:
            entry = self._pending[stamp] = [None, None, None, now]
            if len(self._pending) > MAX_PENDING:
                self.expire(now)
        entry[slot] = value
        if entry[0] is None or entry[1] is None or entry[2] is None:
            return None
        del self._pending[stamp]
        superseded = [s for s in self._pending if s < stamp]
        for s in superseded:
            del self._pending[s]
        self.rejected['unpaired'] += len(superseded)
        (pose_frame, position, orientation), (twist_frame, velocity), \
            (accel_frame, acceleration) = entry[:3]
        return self._complete(
            stamp, (pose_frame, twist_frame, accel_frame), position,
            velocity, acceleration, orientation, now)

    def _complete(self, stamp, frames, position, velocity, acceleration,
                  orientation, now):
        """
        Check and solve a complete setpoint; return it if published now.

        The rules of :mod:`setpoint_rules` on one sample; the result
        becomes the newest (:attr:`latest`), published at once with
        ``rate_hz`` 0.0 (else by :meth:`tick`).
        """
        settings = self.settings
        start = time.perf_counter_ns()
        try:
            for frame in frames:
                setpoint_rules.check_frame(frame, settings)
            solution = setpoint_rules.solve_setpoints(
                settings, position, velocity, acceleration, orientation,
                setpoint_rules.ONE_SAMPLE)
        except Rejected as rejection:
            self.count('setpoint', rejection)
            raise
        spent = time.perf_counter_ns() - start
        self.computed += 1
        self.compute_ns_total += spent
        if spent > self.compute_ns_max:
            self.compute_ns_max = spent
        self.latest = Output(stamp, solution)
        self.latest_arrival = now
        if settings.rate_hz != 0.0:
            return None
        return self._published(self.latest)
