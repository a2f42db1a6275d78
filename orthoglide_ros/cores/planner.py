"""
The planner node's logic without ROS: a path in, the fastest motion out.

A ``nav_msgs/Path`` (poses of G in ``base_frame``, untimed) is a polyline
followed as the smooth curve it samples, within ``path_tolerance`` of
every pose
(:func:`orthoglide_ros.planning.path.from_waypoints`), and planned by
:func:`orthoglide_ros.planning.parametrization.plan`: the fastest motion
from rest at the first pose to rest at the last, within the
``joint_limits.<joint>.*`` of actuators A, B, C under the robot's own
dynamics (``robot.*``) and ``max_speed``, sampled at ``rate_hz``. The node
publishes it on ``cartesian_trajectory``, the feedforward's whole-motion
input.

Rules (``doc/planner.md`` states them for users): a path is refused,
counted by reason, and publishes nothing, when its frame (or a pose's) is
neither empty nor ``base_frame`` (``frame``), a position is not finite
(``non_finite``), it has fewer than two poses or none away from the first
(``too_few_poses``), or the robot cannot follow it within its limits
(``infeasible``: out of the workspace, statics beyond ``max_effort``,
nothing that bounds it; the reason names the pose, from 1); one refused
before it is read counts as ``oversize`` or ``malformed``, and so does one
whose plan would not fit the node's bounds (``oversize``: more gridpoints
than PLAN_BYTES holds, or a motion longer than the output message holds,
both counted before they are made) or takes longer than
``max_planning_time`` (``timeout``). Orientations are not used: the
platform only translates.
"""

import math
import time

import numpy as np

from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import (base_frame_spec, field,
                                             joint_limit_specs,
                                             joint_limits_rule, Spec, Table)
from orthoglide_ros.cores.inputs import CARTESIAN_TRAJECTORY_BYTES
from orthoglide_ros.cores.status import OK
from orthoglide_ros.formats import cdr
from orthoglide_ros.model.robot import JOINT_NAMES
from orthoglide_ros.planning.moves import EMPTY, ProgramError, TOO_LARGE
from orthoglide_ros.planning.limits import (KINDS, limits_from_parameters,
                                            PAPER_LIMITS)
from orthoglide_ros.planning.parametrization import (most_pieces, plan,
                                                     TIMEOUT)
from orthoglide_ros.planning.path import from_waypoints

REASONS = ('frame', 'non_finite', 'too_few_poses', 'infeasible',
           'malformed', 'oversize', 'timeout')
# The nav_msgs/Path read whole: 100,000 poses (about 8 MB).
PATH_BYTES = 8 * 1024 * 1024
MAX_POSES = 100_000
# The memory a path's plan may take (bytes: parametrization's bounds per
# pose, gridpoint and sample), with the 100,000 poses of a path at most.
PLAN_BYTES = 512_000_000


def max_points(frame):
    """
    Return the most points of a motion published in ``frame``.

    Its message within what the feedforward reads (CARTESIAN_TRAJECTORY_BYTES,
    the input's PATH_BYTES): the header (64 bytes and the frame's) and
    cdr's bytes a point.
    """
    return (CARTESIAN_TRAJECTORY_BYTES - 64 - len(frame.encode())) \
        // cdr.MULTI_DOF_POINT_BYTES


PARAMETERS = Table('PlannerSettings', (
    base_frame_spec('frame of the path\'s poses and of the published motion'),
    Spec('max_speed', 'double', 0.0,
         'largest speed of G (m/s); 0.0: none beside the limits',
         (0.0, 100.0)),
    Spec('path_tolerance', 'double', 1e-5,
         'a path\'s polyline is followed as the smooth curve it samples '
         'within this distance (m) of every pose, its corners blended '
         'within it; 0.0: G stops at every corner', (0.0, 0.01)),
    Spec('rate_hz', 'double', 1000.0,
         'points per second of the published motion (Hz)',
         (100.0, 100000.0)),
    Spec('max_planning_time', 'double', 10.0,
         'a path whose plan takes longer (s) is refused (timeout)',
         (0.01, 600.0)),
    *joint_limit_specs(PAPER_LIMITS),
    *realtime.SPECS,
), rules=(joint_limits_rule,), robot=True)


# The node's reason for a refusal of the planner's.
_REASONS = {EMPTY: 'too_few_poses', TOO_LARGE: 'oversize',
            TIMEOUT: 'timeout'}


def limits_of(settings):
    """Return the :class:`Limits` of the settings' ``joint_limits.*``."""
    values = {}
    for joint in JOINT_NAMES:
        for key, has, _, _ in KINDS:
            for name in (has, key):
                full = f'joint_limits.{joint}.{name}'
                values[full] = getattr(settings, field(full))
    for joint in JOINT_NAMES:   # a max of 0.0 where its flag is off: none
        for key, has, _, _ in KINDS:
            if not values[f'joint_limits.{joint}.{has}']:
                del values[f'joint_limits.{joint}.{key}']
    return limits_from_parameters(values)


class Planner(Core):
    """
    Inputs, rules and counters of the planner.

    :meth:`path` returns ``(frame, Motion)`` to publish, or raises
    :class:`Rejected`, already counted.
    """

    INPUTS = ('path',)
    REASONS = REASONS

    def __init__(self, settings, now=0.0):
        super().__init__(settings, now)
        self.limits = limits_of(settings)
        self.planned = 0
        self.withheld = 0
        self.last_seconds = math.nan      # planning time of the last path
        self.last_duration = math.nan     # its motion's duration
        self.last_points = 0

    def configure(self, settings):
        """Use new settings (and their limits) from the next path on."""
        super().configure(settings)
        self.limits = limits_of(settings)

    def path(self, frame, frames, positions, now):
        """
        Take one path; return ``(frame, Motion)`` to publish.

        ``frame``: the header's; ``frames``: each pose's; ``positions``:
        (N, 3) m. None (withheld) while inactive.
        """
        self.received['path'] += 1
        try:
            motion = self._plan(frame, frames, positions)
        except Rejected as rejection:
            self.count('path', rejection)
            raise
        if motion is None:
            self.withheld += 1
            return None
        self.planned += 1
        return self.settings.base_frame, motion

    def _plan(self, frame, frames, positions):
        settings = self.settings
        base = settings.base_frame
        for k, name in enumerate((frame, *frames)):
            if name and name != base:
                where = 'the path' if k == 0 else f'pose {k}'
                raise Rejected('frame', f'{where} in frame {name!r}, '
                               f'expected {base!r}')
        positions = np.asarray(positions, dtype=float).reshape(-1, 3)
        if not np.isfinite(positions).all():
            k = int(np.argmin(np.isfinite(positions).all(1))) + 1
            raise Rejected('non_finite', f'pose {k}: position '
                           f'{positions[k - 1].tolist()} is not finite')
        if len(positions) < 2:
            raise Rejected('too_few_poses', f'{len(positions)} pose(s): a '
                           'path needs two at least')
        if not self.active:
            return None
        start = time.monotonic()
        try:
            path = from_waypoints(positions, None,
                                  list(range(1, len(positions) + 1)),
                                  settings.path_tolerance,
                                  most_pieces(PLAN_BYTES))
            motion = plan(settings.robot, path, self.limits,
                          settings.rate_hz, settings.max_speed or math.inf,
                          max_samples=max_points(base), max_bytes=PLAN_BYTES,
                          max_seconds=settings.max_planning_time)
        except ProgramError as error:
            where = '' if error.line is None else f'pose {error.line}: '
            raise Rejected(_REASONS.get(error.reason, 'infeasible'),
                           where + error.detail) from None
        self.last_seconds = time.monotonic() - start
        self.last_duration = motion.duration
        self.last_points = len(motion.t)
        return motion

    def period_counters(self):
        """Return the counters of the period's rates."""
        return dict(planned=self.planned)

    def status_rules(self, now, seconds, increases):
        """Return the rejections and the wait steps."""
        return (
            self.rejected_rule(increases, 'path(s)'),
            (self.received['path'] == 0, OK, 'waiting for a path'))

    def values(self, now, seconds, increases):
        """Return the counters and the last plan's figures."""
        return [
            ('paths planned', self.planned),
            ('paths received', self.received['path']),
            ('paths withheld (inactive)', self.withheld),
            ('last planning time (s)', self.last_seconds),
            ('last motion duration (s)', self.last_duration),
            ('last motion points', self.last_points),
        ]
