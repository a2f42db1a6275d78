"""
The setpoint publisher's logic without ROS: which setpoint, when.

:class:`Stream` turns the node clock's time into setpoints of a motion
(the paper's trajectory, eq. (6), or the periodic excitation), each
sampled at its own stamp (doc/setpoint_publisher.md).

>>> stream = Stream(PARAMETERS.parse({'duration': 1.0}))
>>> stream.next(5 * 10**9)[0] == (0.0, 0.0, 0.0)
True
>>> stream.next(7 * 10**9) is None, stream.done
(True, True)
"""

from orthoglide_ros.model import trajectory
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.status import OK
from orthoglide_ros.cores.parameters import (one_of, ParameterError, Spec,
                                             Table, triple)

INPUTS = ('trajectory', 'topics')
MOTIONS = ('paper', 'excitation')
SEED_RANGE = (0, 2**31 - 1)


def _excitation_has_a_period(settings):
    if settings.motion == 'excitation' and not settings.duration > 0.0:
        raise ParameterError('duration', (
            'the period of the excitation must be above 0 s, got '
            f'{settings.duration}'))


PARAMETERS = Table('SetpointSettings', (
    Spec('rate_hz', 'double', 500.0, 'setpoints per second (Hz)',
         (0.1, 10000.0), read_only=True),
    Spec('input', 'string', 'trajectory',
         "'trajectory': one MultiDOFJointTrajectory on setpoint/trajectory; "
         "'topics': pose, twist and accel of equal stamp on "
         'setpoint/pose|twist|accel', check=one_of(INPUTS), read_only=True),
    Spec('motion', 'string', 'paper',
         "'paper': eq. (6) (target, omega); 'excitation': the periodic "
         'motion for identification (seed; period duration)',
         check=one_of(MOTIONS), read_only=True),
    Spec('duration', 'double', trajectory.PAPER_DURATION,
         'length of one pass (s): of eq. (6), or the period of the '
         'excitation (then above 0)', (0.0, 3600.0), read_only=True),
    Spec('target', 'double_array', list(trajectory.PAPER_TARGET),
         'r* of eq. (6): three coordinates (m) in frame_id', check=triple,
         read_only=True),
    Spec('omega', 'double', trajectory.PAPER_OMEGA,
         'omega of eq. (6) (rad/s)', (-1000.0, 1000.0), read_only=True),
    Spec('seed', 'integer', 0,
         'seed of the excitation\'s coefficients (the same seed, the same '
         'motion)', SEED_RANGE, read_only=True),
    Spec('loop', 'bool', False,
         'repeat the pass until Ctrl-C (else exit 0 after one pass); each '
         'pass of eq. (6) is followed by a smooth way back to its start, '
         'the excitation\'s passes follow each other', read_only=True),
    Spec('return_duration', 'double', trajectory.RETURN_DURATION,
         'with loop and motion paper: time of the way back from the end '
         'of a pass to its start (s), a quintic continuous in position, '
         'velocity and acceleration', (0.1, 3600.0), read_only=True),
    Spec('start_delay', 'double', 1.0,
         'longest wait (s) before the first setpoint: it comes earlier, '
         '0.25 s after every output has min_subscribers matched '
         'subscribers', (0.0, 3600.0), read_only=True),
    Spec('min_subscribers', 'integer', 1,
         'matched subscribers per output that end the start_delay wait '
         'early', (0, 1000), read_only=True),
    Spec('frame_id', 'string', 'base_link',
         'frame of the setpoints (header.frame_id)', read_only=True),
    *realtime.SPECS,
), rules=(_excitation_has_a_period,))


class Stream(Core):
    """
    The setpoints of the passes, and the counters of the summary.

    The core of :mod:`orthoglide_ros.cores.core`, without inputs:
    :meth:`next` takes the stamp (ns) the next setpoint would carry and
    returns its ``(position, velocity, acceleration)`` (m, m/s, m/s^2), or
    None while inactive and once the last pass is over (:attr:`done`).
    Activated again, the motion starts over from its start (home, at
    rest): a stream stopped in mid-motion does not jump to where it would
    have been.
    """

    INACTIVE = 'inactive: no setpoint published'

    def __init__(self, settings, now=0.0):
        """Start before the first pass (nothing published yet)."""
        super().__init__(settings, now)
        self.done = False
        self.published = 0
        self.passes = 0
        self.largest_gap_ns = 0
        self._first_ns = None       # stamp of the very first setpoint
        self._last_ns = None
        self._excitation = None
        self._way_back = None
        if settings.motion == 'excitation':
            self._excitation = trajectory.excitation(settings.seed,
                                                     settings.duration)
        else:
            self._way_back = trajectory.quintic(
                self._pass(settings.duration), self._pass(0.0),
                settings.return_duration)

    def activate(self):
        """Publish again, the motion from its start."""
        self.active = True
        self._first_ns = self._last_ns = None

    def next(self, stamp_ns):
        """Return the setpoint at ``stamp_ns`` (ns), or None (see above)."""
        if self.done or not self.active:
            return None
        if self._first_ns is None:
            self._first_ns = stamp_ns
        t = (stamp_ns - self._first_ns) / 1e9
        sample = self.sample(t)
        if sample is None:
            self.done = True
            return None
        if self._last_ns is not None:
            self.largest_gap_ns = max(self.largest_gap_ns,
                                      stamp_ns - self._last_ns)
        self._last_ns = stamp_ns
        self.published += 1
        return sample

    def sample(self, t):
        """
        Return the motion at ``t`` s after the first setpoint, or None.

        None past the single pass without ``loop``; with it, the pass and
        the way back repeat with period ``duration + return_duration``, or
        the excitation's passes with period ``duration``.
        """
        settings = self.settings
        if settings.loop:
            period = settings.duration + (
                0.0 if self._excitation else settings.return_duration)
            self.passes = int(t // period) + 1
            t %= period
        elif t > settings.duration:
            return None
        else:
            self.passes = 1
        if t <= settings.duration:
            return self._pass(t)
        return self._way_back(t - settings.duration)

    def _pass(self, t):
        if self._excitation is not None:
            return trajectory.excitation_sample(self._excitation, t)
        return trajectory.paper_sample(t, self.settings.target,
                                       self.settings.omega)

    def summary(self):
        """Return the one-line summary of what was published."""
        if not self.published:
            return 'published no setpoint'
        span = (self._last_ns - self._first_ns) / 1e9
        rate = (self.published - 1) / span if span > 0.0 else 0.0
        return (f'published {self.published} setpoints '
                f'({self.settings.input}) over {span:.3f} s in '
                f'{self.passes} pass(es): mean {rate:.1f} Hz, largest gap '
                f'{self.largest_gap_ns / 1e6:.2f} ms')

    def period_counters(self):
        """Return the counters of the period's rate."""
        return dict(published=self.published)

    def status_rules(self, now, seconds, increases):
        """Return the end and the wait steps."""
        return ((self.done, OK, f'done: {self.summary()}'),
                (self.published == 0, OK, 'waiting to start'))

    def values(self, now, seconds, increases):
        """Return the rate, the counters and the motion."""
        return [('setpoint rate (Hz)', increases['published'] / seconds),
                ('setpoints published', self.published),
                ('passes', self.passes),
                ('largest gap (ms)', self.largest_gap_ns / 1e6),
                ('motion', self.settings.motion),
                ('input', self.settings.input)]
