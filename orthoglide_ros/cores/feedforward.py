"""
The feedforward's logic without ROS: setpoints in, joint targets out.

:class:`Feedforward` pairs the pose, twist and accel of one setpoint by their
exact stamp, checks the setpoint, runs :func:`mechanics.solve` on it and keeps
the counters the diagnostics report. The ROS node (``feedforward_node``)
only converts messages to and from the plain values used here, so every rule
below is testable without DDS.

Rules (``doc/feedforward.md`` states them for users):

- A setpoint is complete when a pose, a twist and an accel with the same
  stamp have arrived (or a pose alone with ``pose_only``), or when one
  trajectory point arrives. A zero or negative stamp cannot be paired and
  is rejected; so is a trajectory point whose stamp (header plus
  ``time_from_start``) is zero, negative or beyond an output stamp's int32
  seconds.
- A partial setpoint waits at most ``pairing_timeout`` (by arrival time) for
  its partners; it is dropped as ``unpaired`` when that runs out, or at once
  when a newer setpoint completes (its partners can no longer come in order).
- A complete setpoint is rejected, and counted by reason, if a frame is
  neither empty nor ``base_frame`` (``frame``), its orientation turns more than
  1e-3 rad from the identity (``orientation``), its speed or acceleration
  (norms) exceed ``max_speed`` or ``max_acceleration`` (``speed_limit``,
  ``acceleration_limit``), the mechanics refuse it (``non_finite``,
  ``unreachable``, ``singular``, ``overflow``) or an actuator would need a
  force beyond ``max_force`` (``force_limit``): no force beyond it is ever
  published. A rejected setpoint changes nothing: the previous result
  stays the newest.
- Freshness is judged by arrival time on a monotonic clock, never by stamp:
  the newest result is fresh for ``setpoint_timeout`` after its setpoint
  completed.
- A whole Cartesian trajectory (:func:`convert_trajectory`) is converted
  point by point with :func:`mechanics.solve_batch`, all or nothing: one
  bad point refuses it whole, with the reason and the point's index
  (:data:`TRAJECTORY_REASONS`, counted apart from the setpoints').
"""

from collections import namedtuple
import math
import time

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.inputs import check_stamp, NANOSECONDS, Rejected
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import joint_names_spec, \
    nonnegative_triple, ParameterError, Spec, Table
from orthoglide_ros.cores.status import first, OK, Period, Status, WARN

# Largest rotation of the platform accepted as "the identity" (rad).
ORIENTATION_TOLERANCE = 1e-3
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
           'singular', 'overflow', 'force_limit', 'frame', 'orientation',
           'stamp', 'malformed', 'oversize', 'unpaired')
INPUTS = ('pose', 'twist', 'accel', 'trajectory')

Conversion = namedtuple('Conversion', 'stamp frame time solution')
Conversion.__doc__ = """A converted Cartesian trajectory.

``stamp`` (sec, nanosec) and ``frame`` of its header, unchanged; ``time``
(N, 2) the points' time_from_start (sec, nanosec); ``solution`` the
:class:`mechanics.Solution` of the N points, (N, 3) arrays."""

Output = namedtuple('Output', 'stamp solution')
Output.__doc__ = """A result: ``stamp`` (sec, nanosec) of its setpoint and
the :class:`mechanics.Solution`."""

_ZERO = (0.0, 0.0, 0.0)


def convert_trajectory(settings, waypoints):
    """
    Convert every point of a Cartesian trajectory, or refuse it whole.

    ``waypoints``: :class:`orthoglide_ros.formats.cdr.Waypoints` (the arrays of a
    MultiDOFJointTrajectory). The rules, in this order, the first broken
    one raising :class:`Rejected` with a reason of TRAJECTORY_REASONS and,
    where a point is at fault, its 0-based index:

    - ``empty``: no point; ``frame``: a frame neither empty nor
      ``base_frame``; ``stamp``: a header nanosec outside [0, 1e9) or
      negative seconds (a zero stamp means "start now" and passes
      unchanged);
    - ``malformed``: a point without a transform, or without a velocity or
      acceleration (unless ``pose_only``: zero);
    - ``time``: a time_from_start with nanosec outside [0, 1e9), negative,
      or not after the previous point's;
    - ``orientation`` / ``non_finite``: a rotation more than
      ORIENTATION_TOLERANCE from the identity, or not finite;
    - ``speed_limit`` / ``acceleration_limit``: a speed or acceleration of
      G beyond ``max_speed`` or ``max_acceleration``;
    - the mechanics' refusals (``non_finite``, ``unreachable``,
      ``singular``, ``overflow``) of :func:`mechanics.solve_batch`;
    - ``velocity_limit`` / ``force_limit``: a |lambdadot| or |f| beyond
      the node's limit of that actuator (0.0: none), or an |f| beyond
      ``max_force``.

    Returns a :class:`Conversion`.
    """
    w = waypoints
    n = len(w.time)
    if n == 0:
        raise Rejected('empty', 'trajectory without points')
    if w.frame and w.frame != settings.base_frame:
        raise Rejected('frame', (
            f'trajectory in frame {w.frame!r}, expected '
            f'{settings.base_frame!r} (or empty)'))
    sec, nanosec = w.stamp
    if sec < 0 or not 0 <= nanosec < NANOSECONDS:
        raise Rejected('stamp', (
            f'header stamp {sec} s + {nanosec} ns: seconds must be >= 0 and '
            'nanosec in [0, 1e9)'))
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
    seconds, nanoseconds = w.time[:, 0], w.time[:, 1]
    _first_bad('time', (nanoseconds < 0) | (nanoseconds >= NANOSECONDS),
               'has a time_from_start nanosec outside [0, 1e9)')
    total = seconds * NANOSECONDS + nanoseconds
    _first_bad('time', total < 0, 'has a negative time_from_start')
    _first_bad('time', np.r_[False, np.diff(total) <= 0],
               'is not later than the point before it')
    q = w.orientation
    _first_bad('non_finite', ~np.isfinite(q).all(1), 'has a rotation that '
               'is not finite')
    with np.errstate(all='ignore'):
        vector = np.sqrt((q[:, :3] ** 2).sum(1))
        angle = 2.0 * np.arctan2(vector, np.abs(q[:, 3]))
    _first_bad('orientation', ~(angle <= ORIENTATION_TOLERANCE) |
               ((vector == 0.0) & (q[:, 3] == 0.0)),
               f'turns the platform more than {ORIENTATION_TOLERANCE:g} rad '
               'from the identity (the Orthoglide only translates)')
    finite = np.isfinite(w.position).all(1) & np.isfinite(
        velocity).all(1) & np.isfinite(acceleration).all(1)
    for reason, values, (bound, name, unit) in zip(
            ('speed_limit', 'acceleration_limit'), (velocity, acceleration),
            _motion_bounds(settings)):
        # A NaN or an infinity in a point is the mechanics' non_finite.
        with np.errstate(invalid='ignore'):
            norms = np.hypot(np.hypot(values[:, 0], values[:, 1]),
                             values[:, 2])
            beyond = (norms > bound) & finite
        _first_bad(reason, beyond, (
            f'has a {name.removeprefix("max_")} beyond {name} {bound:g} '
            f'{unit}'))
    try:
        solution = mechanics.solve_batch(settings.robot, w.position,
                                         velocity, acceleration,
                                         settings.singularity_margin)
    except mechanics.WorkspaceError as error:
        raise Rejected(error.reason, f'point {error.row}: '
                       + str(error).split(': ', 1)[-1]) from None
    for reason, values, limits, unit in (
            ('velocity_limit', solution.lambdadot, settings.velocity_limit,
             'm/s'),
            ('force_limit', solution.force, settings.force_limit, 'N')):
        limit = np.where(np.asarray(limits) > 0.0, limits, np.inf)
        if reason == 'force_limit':
            limit = np.minimum(limit, settings.max_force)
        beyond = np.abs(values) > limit
        if beyond.any():
            row, leg = np.argwhere(beyond)[0]
            raise Rejected(reason, (
                f'point {row}: actuator {"ABC"[leg]} needs '
                f'{values[row, leg]:.6g} {unit}, beyond its limit '
                f'{limit[leg]:g} {unit}'))
    return Conversion(w.stamp, w.frame, w.time, solution)


def _motion_bounds(settings):
    """Return the (bound, name, unit) of a setpoint's speed and accel."""
    return ((settings.max_speed, 'max_speed', 'm/s'),
            (settings.max_acceleration, 'max_acceleration', 'm/s^2'))


def _first_bad(reason, bad, what):
    """Raise Rejected(reason) naming the first point where ``bad``."""
    if bad.any():
        raise Rejected(reason, f'point {int(np.argmax(bad))} {what}')


def _pairing_within_setpoint_timeout(settings):
    if settings.pairing_timeout > settings.setpoint_timeout:
        raise ParameterError('pairing_timeout', (
            f'must not exceed setpoint_timeout ({settings.pairing_timeout} '
            f'> {settings.setpoint_timeout} s)'))


PARAMETERS = Table('Settings', (
    joint_names_spec('names of the prismatic joints of actuators A, B, C '
                     'in feedforward/joint_states'),
    Spec('base_frame', 'string', 'base_link',
         'frame of the setpoints (the paper\'s frame 0); a setpoint stamped '
         'with another non-empty frame is rejected'),
    Spec('rate_hz', 'double', 0.0,
         'control tick in Hz: 0.0 computes and publishes once per new '
         'setpoint; a positive value publishes the newest setpoint\'s '
         'result at this fixed rate', (0.0, 10000.0)),
    Spec('setpoint_timeout', 'double', 0.1,
         'seconds (by arrival time) without a fresh setpoint after which '
         'the node stops publishing until the next fresh setpoint',
         (0.001, 3600.0)),
    Spec('pairing_timeout', 'double', 0.05,
         'seconds a partial setpoint (pose, twist or accel of one stamp) '
         'waits for its partners before it is dropped; at most '
         'setpoint_timeout', (0.0001, 3600.0)),
    Spec('singularity_margin', 'double', mechanics.DEFAULT_SINGULARITY_MARGIN,
         'smallest accepted singularity distance, min(alpha_i / l3, '
         '1 / kappa_F(J_lambda)), both 1 at home and 0 at a singularity of '
         'J1 or J2', (0.0, 0.99)),
    Spec('pose_only', 'bool', False,
         'serve each pose alone as a setpoint with zero velocity and '
         'acceleration (twist and accel topics ignored); trajectory points '
         'may then omit velocities and accelerations'),
    Spec('velocity_limit', 'double_array', [0.0, 0.0, 0.0],
         'largest |lambdadot| per actuator A, B, C (m/s) of a converted '
         'cartesian_trajectory: one beyond it is refused whole; 0.0: no '
         'limit', check=nonnegative_triple),
    Spec('force_limit', 'double_array', [0.0, 0.0, 0.0],
         'largest |f| per actuator A, B, C (N) of a converted '
         'cartesian_trajectory: one beyond it is refused whole; 0.0: no '
         'limit', check=nonnegative_triple),
    Spec('max_speed', 'double', 5.0,
         'largest speed |v| of G (m/s) of a setpoint or a trajectory point: '
         'one beyond it is refused (speed_limit)', (0.001, 1000.0)),
    Spec('max_acceleration', 'double', 100.0,
         'largest acceleration |a| of G (m/s^2) of a setpoint or a '
         'trajectory point: one beyond it is refused (acceleration_limit)',
         (0.001, 1.0e5)),
    Spec('max_force', 'double', 10000.0,
         'largest |f| (N) of any actuator force the node publishes: a '
         'setpoint or trajectory that needs more is refused (force_limit)',
         (0.001, 1.0e7)),
    *realtime.SPECS,
), rules=(_pairing_within_setpoint_timeout,), robot=True)


class Feedforward:
    """
    Pairing, checks, mechanics and counters of the feedforward node.

    Every method takes ``now``, a monotonic time in seconds, so tests can
    drive time. Methods that complete a setpoint return its :class:`Output`
    or raise :class:`Rejected`; the rejection is already counted.
    """

    def __init__(self, settings, now=0.0):
        self.settings = settings
        self.latest = None
        self.latest_arrival = None
        self.received = dict.fromkeys(INPUTS, 0)
        self.rejected = dict.fromkeys(REASONS, 0)
        self.computed = 0
        self.compute_ns_total = 0
        self.compute_ns_max = 0
        self.published = 0
        self.trajectories = 0           # Cartesian trajectories converted
        self.trajectory_points = 0
        self.trajectory_seconds = math.nan      # the last one's, s
        self.trajectory_seconds_max = 0.0       # the period's largest, s
        self.trajectory_rejected = dict.fromkeys(TRAJECTORY_REASONS, 0)
        self.active = True      # a lifecycle node's state: outputs go out
        self.withheld = 0       # outputs not published while inactive
        self._pending = {}
        self._period = Period(now)

    def configure(self, settings):
        """Use new settings from the next setpoint on (one assignment)."""
        self.settings = settings

    def activate(self):
        """Publish outputs (a lifecycle node's ``active`` state)."""
        self.active = True

    def deactivate(self):
        """Publish nothing; inputs are still taken and counted."""
        self.active = False

    def pose(self, stamp, frame, position, orientation, now):
        """Take a pose of G (m) and the platform orientation (quaternion)."""
        self.received['pose'] += 1
        if self.settings.pose_only:
            self._check_stamp(stamp)
            return self._complete(stamp, (frame,), position, _ZERO, _ZERO,
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
                self._reject('malformed', (
                    'trajectory point without velocities or accelerations '
                    '(set pose_only to accept them as zero)'))
            velocity = velocity or _ZERO
            acceleration = acceleration or _ZERO
        return self._complete(stamp, (frame,), position, velocity,
                              acceleration, orientation, now)

    def trajectory_message(self, header_stamp, time_from_start, clock_stamp,
                           frame, position, orientation, velocity,
                           acceleration, now):
        """
        Take a trajectory message's point: its stamp, then the setpoint.

        The point's stamp is ``header_stamp + time_from_start``, both
        ``(sec, nanosec)`` with nanoseconds in [0, 1e9); a zero header
        stamp means "now", ``clock_stamp`` (the node's clock), as for
        ``trajectory_msgs`` in general. Then as :meth:`trajectory_point`.
        """
        try:
            for what, (sec, nanosec) in (('header stamp', header_stamp),
                                         ('time_from_start',
                                          time_from_start)):
                if not 0 <= nanosec < NANOSECONDS:
                    raise Rejected('stamp', (
                        f'{what} {sec} s + {nanosec} ns: nanosec must lie in '
                        '[0, 1e9)'))
        except Rejected as rejection:
            self.reject('trajectory', rejection)
            raise
        if header_stamp == (0, 0):
            header_stamp = clock_stamp
        stamp = divmod((header_stamp[0] + time_from_start[0]) * NANOSECONDS
                       + header_stamp[1] + time_from_start[1], NANOSECONDS)
        return self.trajectory_point(stamp, frame, position, orientation,
                                     velocity, acceleration, now)

    def count_trajectory(self, conversion, seconds):
        """
        Count a converted Cartesian trajectory; return whether to publish it.

        ``conversion``: a :class:`Conversion`; ``seconds``: from its
        reception to its publication (the node's side of a conversion:
        reading, the kernel, writing). Not published while inactive.
        """
        if not self.active:
            self.withheld += 1
            return False
        self.trajectories += 1
        self.trajectory_points += len(conversion.time)
        self.trajectory_seconds = seconds
        self.trajectory_seconds_max = max(self.trajectory_seconds_max,
                                          seconds)
        return True

    def reject(self, source, rejection):
        """
        Count a message on input ``source`` refused whole.

        ``cartesian_trajectory`` counts among the trajectories' refusals,
        any other input among the setpoints'.
        """
        if source == 'cartesian_trajectory':
            self.trajectory_rejected[rejection.reason] += 1
        else:
            self.received[source] += 1
            self.rejected[rejection.reason] += 1

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
        """Return the newest result if it is fresh, else None (timer mode)."""
        return self.latest if self.fresh(now) else None

    def output_now(self, output):
        """
        Return ``output`` (a completed setpoint, or None) to publish at once.

        With ``rate_hz`` 0.0 each setpoint is published once, as it
        completes; else None (the tick publishes). Counts it as published.
        """
        if output is None or self.settings.rate_hz != 0.0:
            return None
        return self._published(output)

    def output_at_tick(self, now):
        """
        Return the result to publish at a tick of the fixed rate, or None.

        None with ``rate_hz`` 0.0 (each setpoint is published as it
        completes) or when stale (:meth:`tick`). Counts it as published.
        """
        output = self.tick(now) if self.settings.rate_hz != 0.0 else None
        return None if output is None else self._published(output)

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

    def status(self, now, internal_errors=0):
        """
        Return the :class:`Status` of the period ending at ``now``.

        ERROR after an internal error; WARN when setpoints or
        trajectories were rejected in the period, or when stale; else OK
        (``waiting for the first setpoint`` until there is one). The values: rates over the period,
        compute times (the maximum restarts with each period), counters.
        """
        rejected = sum(self.rejected.values())
        seconds, new = self._period.advance(
            now, published=self.published, computed=self.computed,
            compute_ns=self.compute_ns_total, rejected=rejected,
            trajectories_rejected=sum(self.trajectory_rejected.values()))
        age = None if self.latest_arrival is None \
            else now - self.latest_arrival
        fresh = self.fresh(now)
        level, message = first(
            internal_errors,
            (not self.active, OK, 'inactive: inputs taken, no output '
             'published'),
            (new['rejected'], WARN,
             f'{new["rejected"]} setpoint(s) rejected in the last period'),
            (new['trajectories_rejected'], WARN,
             f'{new["trajectories_rejected"]} trajectory(ies) rejected in '
             'the last period'),
            (age is None, OK, 'waiting for the first setpoint'),
            (not fresh, WARN,
             f'stale: no fresh setpoint for {age or 0.0:.2f} s, outputs '
             'stopped'))
        mean_us = new['compute_ns'] / new['computed'] / 1e3 \
            if new['computed'] else 0.0
        distance = self.latest.solution.singularity_distance \
            if self.latest is not None else math.nan
        values = [
            ('tick rate (Hz)', new['published'] / seconds),
            ('compute time mean (us)', mean_us),
            ('compute time max (us)', self.compute_ns_max / 1e3),
            ('setpoints computed', self.computed),
            ('outputs published', self.published),
            ('outputs withheld (inactive)', self.withheld),
            ('stale', not fresh),
            ('time since last setpoint (s)',
             age if age is not None else math.nan),
            ('singularity distance', distance),
            ('singularity margin', self.settings.singularity_margin),
            ('payload (kg)', self.settings.robot.payload),
            ('pending partial setpoints', self.pending),
            ('rate_hz', self.settings.rate_hz),
            ('internal errors', internal_errors),
        ]
        values += [(f'received {k}', v) for k, v in self.received.items()]
        values += [(f'rejected {r}', self.rejected[r]) for r in REASONS]
        values += [('trajectories converted', self.trajectories),
                   ('trajectory points converted', self.trajectory_points),
                   ('trajectory receive to publish last (ms)',
                    self.trajectory_seconds * 1e3),
                   ('trajectory receive to publish max (ms)',
                    self.trajectory_seconds_max * 1e3)]
        self.trajectory_seconds_max = 0.0
        values += [(f'rejected trajectory {r}', self.trajectory_rejected[r])
                   for r in TRAJECTORY_REASONS]
        self.compute_ns_max = 0
        return Status(level, message, values)

    def _check_stamp(self, stamp):
        try:
            check_stamp(stamp)
        except Rejected as rejection:
            self.rejected[rejection.reason] += 1
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
        settings = self.settings
        for frame in frames:
            if frame and frame != settings.base_frame:
                self._reject('frame', (
                    f'setpoint in frame {frame!r}, expected '
                    f'{settings.base_frame!r} (or empty)'))
        self._check_orientation(orientation)
        # A NaN or an infinity anywhere is the mechanics' non_finite.
        finite = all(math.isfinite(c)
                     for c in (*position, *velocity, *acceleration))
        for reason, vector, (bound, name, unit) in zip(
                ('speed_limit', 'acceleration_limit'),
                (velocity, acceleration), _motion_bounds(settings)):
            # hypot: no squares to overflow.
            if finite and math.hypot(*vector) > bound:
                self._reject(reason, (
                    f'{name.removeprefix("max_")} '
                    f'{mechanics.format_vector(vector)} {unit} is beyond '
                    f'{name} {bound:g} {unit}'))
        start = time.perf_counter_ns()
        try:
            solution = mechanics.solve(
                settings.robot, position, velocity, acceleration,
                settings.singularity_margin)
        except mechanics.WorkspaceError as error:
            self._reject(error.reason, str(error))
        largest = max(abs(f) for f in solution.force)
        if largest > settings.max_force:
            self._reject('force_limit', (
                f'it needs {largest:.6g} N on an actuator, beyond max_force '
                f'{settings.max_force:g} N'))
        spent = time.perf_counter_ns() - start
        self.computed += 1
        self.compute_ns_total += spent
        if spent > self.compute_ns_max:
            self.compute_ns_max = spent
        self.latest = Output(stamp, solution)
        self.latest_arrival = now
        return self.latest

    def _check_orientation(self, q):
        x, y, z, w = q
        if not math.isfinite(x + y + z + w) and not all(
                math.isfinite(c) for c in q):
            self._reject('non_finite', f'orientation {q} is not finite')
        # hypot: no squares to overflow (1e200) or underflow (1e-200).
        vector = math.hypot(x, y, z)
        if vector == 0.0 and w == 0.0:
            self._reject('orientation', 'orientation is the zero quaternion')
        angle = 2.0 * math.atan2(vector, abs(w))
        if angle > ORIENTATION_TOLERANCE:
            self._reject('orientation', (
                f'platform orientation turns {angle:.3g} rad from the '
                f'identity (tolerance {ORIENTATION_TOLERANCE:g} rad): the '
                'Orthoglide only translates'))

    def _reject(self, reason, message):
        self.rejected[reason] += 1
        raise Rejected(reason, message)
