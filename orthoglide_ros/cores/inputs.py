"""
Rules every node applies to what it receives, without ROS.

:class:`Rejected` (a refused input, counted under its ``reason``), the
time rule, joint states and trajectories read by name, the byte limits
(doc/robustness.md#inputs).
"""

from collections import namedtuple
import math

import numpy as np


# Largest stamp seconds an output can carry (builtin_interfaces/Time: int32).
STAMP_SEC_MAX = 2**31 - 1
NANOSECONDS = 10**9
# Byte limit of an input whose messages are small (a pose, a joint state of
# a few hundred joints, a command): 64 KiB, about 100 times the size of
# the largest well-formed one the package expects.
SMALL_MESSAGE_BYTES = 64 * 1024
# The byte limits of the inputs whose messages are long, all here:
# setpoint/trajectory (its first point is used): 4 MiB, about 20,000
# points;
TRAJECTORY_MESSAGE_BYTES = 4 * 1024 * 1024
# cartesian_trajectory (every point is converted): 8 MiB, about 45,000
# points (10,000 points take 1.8 MB);
CARTESIAN_TRAJECTORY_BYTES = 8 * 1024 * 1024
# joint_trajectory: 8 MiB, about 60,000 points of three joints (a
# 10,000-point trajectory takes 1.4 MB);
JOINT_TRAJECTORY_BYTES = 8 * 1024 * 1024
# a message recorded by `orthoglide record`: 4 MiB.
RECORD_MESSAGE_BYTES = 4 * 1024 * 1024


class Rejected(ValueError):
    """An input refused by a rule; ``reason`` says which rule."""

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


def check_time(what, sec, nanosec, reason='stamp'):
    """
    Refuse (``reason``) a Time or Duration whose nanosec is not in [0, 1e9).

    The one check of a ``builtin_interfaces`` time, which every stamp and
    time_from_start of every input passes: outside that range the same
    instant would have two spellings, which never pair. ``sec`` and
    ``nanosec`` may be (N,) arrays (every point of a trajectory): the
    first point at fault is named.
    """
    bad = (np.asarray(nanosec) < 0) | (np.asarray(nanosec) >= NANOSECONDS)
    if bad.any():
        if bad.ndim:
            i = int(np.argmax(bad))
            what, sec, nanosec = f'point {i}: {what}', sec[i], nanosec[i]
        raise Rejected(reason, f'{what} {sec} s + {nanosec} ns: nanosec '
                       'must lie in [0, 1e9)')


def check_stamp(stamp, zero_allowed=False):
    """
    Refuse a stamp ``(sec, nanosec)`` that is not a ROS time.

    Raises :class:`Rejected` (``stamp``) for nanoseconds outside [0, 1e9), a
    negative stamp, seconds beyond int32 and a zero stamp unless
    ``zero_allowed`` (doc/robustness.md#inputs, one stamp rule).

    >>> check_stamp((12, 5))
    >>> check_stamp((0, 0), zero_allowed=True)
    >>> for bad in ((12, 10**9), (-1, 0), (0, 0)):
    ...     try:
    ...         check_stamp(bad)
    ...     except Rejected as error:
    ...         print(error.reason, '|', error)
    stamp | stamp 12 s + 1000000000 ns: nanosec must lie in [0, 1e9)
    stamp | stamp -1.000000000 is negative: a ROS time is not
    stamp | stamp 0.000000000 cannot pair pose, twist and accel: stamp \
setpoints with their time
    """
    sec, nanosec = stamp
    check_time('stamp', sec, nanosec)
    if sec < 0:
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} is negative: a ROS time is not'))
    if stamp == (0, 0) and not zero_allowed:
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} cannot pair pose, twist and '
            'accel: stamp setpoints with their time'))
    if sec > STAMP_SEC_MAX:
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} is beyond the int32 seconds '
            'of builtin_interfaces/Time'))


def trajectory_times(time):
    """
    Return a trajectory's time_from_start (N, 2) as (N,) seconds.

    Raises :class:`Rejected` (``time``) naming the first point whose
    nanosec is not in [0, 1e9) (:func:`check_time`), that is negative or
    not after the point before it.
    """
    seconds, nanoseconds = time[:, 0], time[:, 1]
    check_time('time_from_start', seconds, nanoseconds, 'time')
    total = seconds * NANOSECONDS + nanoseconds
    for bad, what in ((total < 0, 'negative time_from_start'),
                      (np.r_[False, np.diff(total) <= 0],
                       'not later than the point before it')):
        if bad.any():
            raise Rejected('time', f'point {int(np.argmax(bad))}: {what}')
    return total / NANOSECONDS


JointValues = namedtuple('JointValues', 'position velocity effort')
JointValues.__doc__ = """One joint state in joint_names order: 3-tuples of
lambda (m), lambdadot (m/s, None when optional and absent) and effort (N,
None when not needed)."""


def read_joint_state(joint_names, names, position, velocity, effort,
                     need_effort, optional_velocity=False):
    """
    Pick ``joint_names``' values out of one JointState's arrays.

    ``names``, ``position``, ``velocity``, ``effort``: the message's
    sequences, in the message's order; joints not in ``joint_names`` are
    ignored. Returns :class:`JointValues` in ``joint_names`` order
    (``effort`` None unless ``need_effort``; ``velocity`` None when
    ``optional_velocity`` and the message has none). Raises
    :class:`Rejected` (not counted here) when one of ``joint_names`` is
    absent (``missing_joint``), names repeat or an array is neither empty
    nor as long as the names (``malformed``), an array needed is empty
    (``missing_position``, ``missing_velocity``, ``missing_effort``) or a
    value read is not finite (``non_finite``).

    >>> read_joint_state(('a', 'b', 'c'), ['c', 'x', 'a', 'b'],
    ...                  [3.0, 9.0, 1.0, 2.0], [], [], False, True)
    JointValues(position=(1.0, 2.0, 3.0), velocity=None, effort=None)
    """
    count = len(names)
    rows = joint_columns(joint_names, names)
    fields = [('position', position)]
    if len(velocity) or not optional_velocity:
        fields.append(('velocity', velocity))
    if need_effort:
        fields.append(('effort', effort))
    values = {}
    for field, array in fields:
        size = len(array)
        if size == 0:
            raise Rejected(f'missing_{field}', f'no {field} values')
        if size != count:
            raise Rejected('malformed', (
                f'{size} {field} values for {count} names'))
        picked = (float(array[rows[0]]), float(array[rows[1]]),
                  float(array[rows[2]]))
        if not math.isfinite(picked[0] + picked[1] + picked[2]) and not all(
                math.isfinite(x) for x in picked):
            raise Rejected('non_finite', (
                f'{field} {picked} of {list(joint_names)} is not finite'))
        values[field] = picked
    return JointValues(values['position'], values.get('velocity'),
                       values.get('effort'))


def joint_columns(joint_names, names):
    """
    Return where each of ``joint_names`` stands in a message's ``names``.

    Raises :class:`Rejected`: ``malformed`` when names repeat,
    ``missing_joint`` when one of ``joint_names`` is absent.
    """
    index = {name: i for i, name in enumerate(names)}
    if len(index) != len(names):
        raise Rejected('malformed', f'joint names repeat: {list(names)!r}')
    rows = []
    for name in joint_names:
        i = index.get(name)
        if i is None:
            raise Rejected('missing_joint', (
                f'joint {name!r} absent (names: {list(names)!r})'))
        rows.append(i)
    return rows


def read_joint_trajectory(joint_names, points, need_effort):
    """
    Pick ``joint_names``' columns out of a JointTrajectory's points.

    ``points``: :class:`orthoglide_ros.formats.cdr.JointPoints` (names, lengths,
    positions, velocities, accelerations, efforts, time). Returns ``(times
    (N,) s, positions, velocities, efforts)``, (N, 3) arrays in
    ``joint_names`` order (efforts zero unless ``need_effort``). Raises
    :class:`Rejected` (not counted here): ``empty``; the joint-state
    reasons of :func:`read_joint_state` for a point; ``time`` for a
    time_from_start whose nanosec is not in [0, 1e9), that is negative or
    not after the point before it. Accelerations are not read.
    """
    names = points.names
    n = len(points.time)
    if n == 0:
        raise Rejected('empty', 'joint trajectory without points')
    columns = joint_columns(joint_names, names)
    fields = [('position', 0, points.positions),
              ('velocity', 1, points.velocities)]
    if need_effort:
        fields.append(('effort', 3, points.efforts))
    arrays = []
    for field, row, values in fields:
        lengths = points.lengths[row]
        for bad, reason, what in (
                (lengths == 0, f'missing_{field}', f'no {field} values'),
                (lengths != len(names), 'malformed',
                 f'{field} values not one per name')):
            if bad.any():
                raise Rejected(reason, f'point {int(np.argmax(bad))}: {what}')
        picked = values[:, columns]
        finite = np.isfinite(picked).all(1)
        if not finite.all():
            raise Rejected('non_finite', (
                f'point {int(np.argmin(finite))}: {field} of '
                f'{list(joint_names)} not finite'))
        arrays.append(picked)
    times = trajectory_times(points.time)
    efforts = arrays[2] if need_effort else np.zeros((n, 3))
    return times, arrays[0], arrays[1], efforts
