"""
Serialized ROS 2 messages (CDR) read and written with struct and numpy.

Only the fields the package uses are read, whole trajectories written,
XCDR1 little-endian only. :class:`CdrError` (a buffer not understood) and
:class:`LimitError` (a list whose reading would grow unused) are both
``malformed`` (doc/decisions.md#runtime-and-middleware,
doc/robustness.md#inputs).
"""

from __future__ import annotations

from typing import Optional, Sequence
from collections import namedtuple
import struct

import numpy as np

from orthoglide_ros.model.types import Array, Stamp, Triple

# The OMG CDR encoding of the ROS 2 message definitions (XCDR1): a 4-byte
# encapsulation header, then each primitive aligned to its size counted from
# the end of that header; a string is a length that counts its NUL, then
# its bytes; a sequence is a count, then its items.
_STAMP = struct.Struct('<iI')          # stamp.sec, stamp.nanosec
_COUNT = struct.Struct('<I')
_VECTOR = struct.Struct('<3d')
_POSE = struct.Struct('<7d')           # position, orientation (x, y, z, w)
_DURATION = struct.Struct('<iI')
_LITTLE_ENDIAN_CDR = (b'\x00\x01', b'\x00\x03')   # CDR_LE, PL_CDR_LE
# Joint names a MultiDOFJointTrajectory may carry (the platform's one, and
# room to spare): the reader skips them one by one.
MAX_JOINT_NAMES = 64
# The rosbag2 storages of the logs the package writes (orthoglide record)
# and reads (orthoglide identify): the first is the default.
BAG_STORAGES = ('mcap', 'sqlite3')


class CdrError(ValueError):
    """A buffer this reader cannot read: not a message it knows."""


class LimitError(ValueError):
    """A well-formed buffer beyond what this reader reads (refuse it)."""


def pose_stamped(buf: bytes) -> tuple[Stamp, str, Triple, tuple[float, float, float, float]]:
    """Return ``(stamp, frame, position, orientation)`` of a PoseStamped."""
    stamp, frame, offset = _header(buf)
    values = _unpack(_POSE, buf, _align(offset, 8))
    return stamp, frame, values[:3], values[3:]


def vector3_stamped(buf: bytes) -> tuple[Stamp, str, Triple]:
    """Return ``(stamp, frame, linear)`` of a TwistStamped or AccelStamped."""
    stamp, frame, offset = _header(buf)
    offset = _align(offset, 8)
    _unpack(_VECTOR, buf, offset + _VECTOR.size)      # the angular part
    return stamp, frame, _unpack(_VECTOR, buf, offset)


def trajectory_point(buf: bytes) -> tuple[Stamp, str, Optional[tuple]]:
    """
    Read a MultiDOFJointTrajectory's header and first point.

    Returns ``(stamp, frame, point)``; ``point`` is None when there is no
    point or its first point has no transform, else ``(translation,
    rotation, velocity or None, acceleration or None, time_from_start)``
    with ``time_from_start`` as ``(sec, nanosec)``.
    """
    stamp, frame, offset = _trajectory_header(buf)
    points, offset = _count(buf, offset)
    if points == 0:
        return stamp, frame, None
    transforms, offset = _count(buf, offset)
    if transforms == 0:
        return stamp, frame, None
    offset = _align(offset, 8)
    pose = _unpack(_POSE, buf, offset)
    offset += _POSE.size * transforms
    linear = []
    for _ in range(2):                 # velocities, then accelerations
        twists, offset = _count(buf, offset)
        if twists:
            offset = _align(offset, 8)
            linear.append(_unpack(_VECTOR, buf, offset))
            offset += 48 * twists      # linear and angular Vector3
        else:
            linear.append(None)
    duration = _unpack(_DURATION, buf, _align(offset, 4))
    return stamp, frame, (pose[:3], pose[3:], linear[0], linear[1],
                          duration)


def joint_state(buf: bytes) -> tuple:
    """
    Read a JointState: ``(stamp, frame, names, position, velocity, effort)``.

    ``names`` a tuple of strings, the three arrays tuples of floats, each
    as long as the message has it.
    """
    stamp, frame, offset = _header(buf)
    count, offset = _count(buf, offset)
    names = []
    for _ in range(count):
        name, offset = _string(buf, offset)
        names.append(name)
    arrays = []
    for _ in range(3):
        values, offset = _doubles(buf, offset)
        arrays.append(values)
    return (stamp, frame, tuple(names), *arrays)


def float64_array(buf: bytes) -> tuple[float, ...]:
    """Read a Float64MultiArray's ``data`` as a tuple of floats."""
    _encapsulation(buf)
    dims, offset = _count(buf, 4)
    for _ in range(dims):
        _, offset = _string(buf, offset)
        offset = _align(offset, 4) + 8      # size, stride
    offset = _align(offset, 4) + 4          # data_offset
    return _doubles(buf, offset)[0]


Waypoints = namedtuple('Waypoints', (
    'stamp', 'frame', 'transform', 'velocity', 'acceleration', 'position',
    'orientation', 'linear_velocity', 'linear_acceleration', 'time'))
Waypoints.__doc__ = """The points of a MultiDOFJointTrajectory, as arrays.

``transform``, ``velocity``, ``acceleration``: (N,) bools, whether point k
has one; ``position`` (N, 3) and ``orientation`` (N, 4, x y z w) of its
first transform, ``linear_velocity``, ``linear_acceleration`` (N, 3) of its
first twists (NaN where absent); ``time`` (N, 2) int64: time_from_start
(sec, nanosec)."""


def cartesian_trajectory(buf: bytes) -> 'Waypoints':
    """
    Read every point of a MultiDOFJointTrajectory; return :class:`Waypoints`.

    The offsets of each point's fields are found from its counts, the
    numbers then gathered with numpy in one pass. When every point has the
    first point's counts (the common case: one transform, one velocity, one
    acceleration), the offsets follow from the first two points' layouts
    (a point's layout depends only on its start's alignment) and are
    checked with numpy instead of walked in Python.
    """
    stamp, frame, offset = _trajectory_header(buf)
    points, offset = _count(buf, offset)
    # Each point holds at least three counts and a duration: 20 bytes.
    if 20 * points > len(buf) - offset:
        raise CdrError('truncated message')
    size = len(buf)
    words = np.frombuffer(buf, dtype='<u4', count=size // 4)
    found = _offsets_if_repeating(buf, words, offset, points)
    first, times = found if found is not None else _walk_points(
        buf, offset, points)
    doubles = np.frombuffer(buf, dtype='<f8', offset=4,
                            count=(size - 4) // 8)
    present = first >= 0
    pose, twists = (_gather(doubles, first[j], present[j], width)
                    for j, width in ((0, 7), (slice(1, 3), 3)))
    time = np.column_stack((words[times // 4].view('<i4').astype(np.int64),
                            words[times // 4 + 1].astype(np.int64)))
    return Waypoints((stamp[0], stamp[1]), frame, present[0], present[1],
                     present[2], pose[:, :3], pose[:, 3:], twists[0],
                     twists[1], time)


def _gather(doubles, first, present, width):
    """
    Read ``width`` doubles from each first-item offset; NaN where absent.

    ``first``, ``present``: (N,) or (K, N); the result has a trailing axis
    of ``width``. Only the items present are read (an absent one's offset
    is -1, which must not be dereferenced, even masked).
    """
    out = np.full(first.shape + (width,), np.nan)
    out[present] = doubles[((first[present] - 4) // 8)[:, None]
                           + np.arange(width)]
    return out


_POINT_ITEM_BYTES = (56, 48, 48)   # bytes of a Transform, a Twist, a Twist


def _walk_points(buf, offset, points):
    """Walk every point; return (first-item offsets (3, N), time offsets)."""
    first = np.full((3, points), -1, dtype=np.int64)
    times = np.empty(points, dtype=np.int64)
    for k in range(points):
        offset, _, first[:, k], _ = _point(buf, offset)
        times[k] = offset - 8
    return first, times


def _point(buf, offset):
    """
    Read one point from ``offset``.

    Returns ``(end, count offsets, first-item offsets or -1, counts)`` of
    its transforms, velocities and accelerations.
    """
    size = len(buf)
    at, first, counts = [], [], []
    for item in _POINT_ITEM_BYTES:
        offset += -(offset - 4) % 4
        if offset + 4 > size:
            raise CdrError('truncated message')
        count = _COUNT.unpack_from(buf, offset)[0]
        at.append(offset)
        counts.append(count)
        offset += 4
        first.append(-1)
        if count:
            offset += -(offset - 4) % 8
            first[-1] = offset
            offset += item * count
    offset += -(offset - 4) % 4
    if offset + 8 > size:
        raise CdrError('truncated message')
    return offset + 8, at, first, counts


def _offsets_if_repeating(buf, words, offset, points):
    """
    Return the offsets if every point repeats the first point's counts.

    Else None (the caller walks the points). A point's layout depends only
    on its counts and on its start's alignment, which alternates between
    two values: the first two points give both layouts, and one numpy pass
    checks that every point's count words hold those counts.
    """
    if points < 2:
        return None
    shapes, origin = [], offset
    for _ in range(2):
        end, at, first, counts = _point(buf, origin)
        shapes.append((end - origin, np.array(at) - origin,
                       np.array(first) - origin, counts))
        origin = end
    (s0, at0, f0, c0), (s1, at1, f1, c1) = shapes
    if c0 != c1:
        return None
    starts, end = _alternating_starts(offset, s0, s1, points)
    if end > len(buf):
        return None
    # Point k has point 0's layout where its start has point 0's
    # alignment, else point 1's.
    second = ((starts - offset) % 8 != 0)[:, None]
    at = starts[:, None] + np.where(second, at1, at0)       # (N, 3)
    if not np.array_equal(words[at // 4],
                          np.broadcast_to(np.array(c0), at.shape)):
        return None
    present = np.array(c0) > 0
    first = np.where(present, starts[:, None] + np.where(second, f1, f0),
                     -1).T
    times = starts + np.where(second[:, 0], s1, s0) - 8
    return first, times


def _alternating_starts(origin, first, second, count):
    """
    Return the start offsets of ``count`` items and the end of the last.

    ``first``: the size of an item starting with ``origin``'s alignment
    (mod 8), ``second``: with the other alignment. Alignments then go
    constant, alternate, or switch once and stay.
    """
    k = np.arange(count)
    if first % 8 == 0:                      # every item aligned as the 1st
        starts = origin + k * first
        return starts, origin + count * first
    if second % 8 != 0:                     # alternating
        starts = origin + (k // 2) * (first + second) + (k % 2) * first
        return starts, origin + (count // 2) * (first + second) + \
            (count % 2) * first
    starts = origin + np.where(k > 0, first + (k - 1) * second, 0)
    return starts, origin + (first + (count - 1) * second if count else 0)


JointPoints = namedtuple('JointPoints', (
    'stamp', 'frame', 'names', 'lengths', 'positions', 'velocities',
    'accelerations', 'efforts', 'time'))
JointPoints.__doc__ = """The points of a JointTrajectory, as arrays.

``names``: the joint names; ``lengths`` (4, N) ints: how many values point
k holds in its positions, velocities, accelerations, efforts; those four
(N, J) arrays hold them (J the number of names; NaN where a point holds
fewer, extra values dropped); ``time`` (N, 2) int64 time_from_start."""


def joint_trajectory_points(buf: bytes,
                            max_names: int = MAX_JOINT_NAMES) -> 'JointPoints':
    """Read a whole JointTrajectory; return :class:`JointPoints`."""
    stamp, frame, offset = _header(buf)
    count, offset = _count(buf, offset)
    if count > max_names:
        raise LimitError(f'{count} joint_names: at most {max_names}')
    names = []
    for _ in range(count):
        name, offset = _string(buf, offset)
        names.append(name)
    points, offset = _count(buf, offset)
    # Each point holds four counts and a duration: 24 bytes at least.
    if 24 * points > len(buf) - offset:
        raise CdrError('truncated message')
    lengths = np.zeros((4, points), dtype=np.int64)
    first = np.zeros((4, points), dtype=np.int64)
    times = np.empty(points, dtype=np.int64)
    size = len(buf)
    for k in range(points):
        for field in range(4):
            offset += -(offset - 4) % 4
            if offset + 4 > size:
                raise CdrError('truncated message')
            n = _COUNT.unpack_from(buf, offset)[0]
            offset += 4
            if n:
                offset += -(offset - 4) % 8
            lengths[field, k], first[field, k] = n, offset
            offset += 8 * n
        offset += -(offset - 4) % 4
        times[k] = offset
        offset += 8
    if offset > size:
        raise CdrError('truncated message')
    doubles = np.frombuffer(buf, dtype='<f8', offset=4,
                            count=(size - 4) // 8)
    words = np.frombuffer(buf, dtype='<u4', count=size // 4)
    columns = np.arange(count)
    arrays = []
    for field in range(4):
        has = columns[None, :] < lengths[field][:, None]        # (N, J)
        index = np.where(has, (first[field][:, None] - 4) // 8
                         + columns[None, :], 0)
        arrays.append(np.where(has, doubles[index] if len(doubles) else
                               0.0, np.nan))
    time = np.column_stack((words[times // 4].view('<i4').astype(np.int64),
                            words[times // 4 + 1].astype(np.int64)))
    return JointPoints(stamp, frame, tuple(names), lengths, *arrays, time)


def joint_trajectory(stamp: Stamp, frame: str, names: Sequence[str],
                     time: Array, positions: Array, velocities: Array,
                     accelerations: Array, efforts: Array) -> bytes:
    """
    Serialize a ``trajectory_msgs/JointTrajectory`` (little-endian CDR).

    ``stamp`` (sec, nanosec), ``frame`` and ``names`` (strings); ``time``
    (N, 2) ints, time_from_start (sec, nanosec); ``positions``,
    ``velocities``, ``accelerations``, ``efforts``: (N, J) arrays, J the
    number of names. Returns the bytes ``Publisher.publish`` sends as is.
    A point's layout depends only on its start's alignment (two values):
    the points are written by numpy, each with the layout of its
    alignment (:func:`_alternating_starts`).
    """
    n, joints = len(time), len(names)
    head = bytearray(b'\x00\x01\x00\x00')
    head += _STAMP.pack(*stamp)
    _put_string(head, frame)
    head += bytes(-(len(head) - 4) % 4) + _COUNT.pack(joints)
    for name in names:
        head += bytes(-(len(head) - 4) % 4)
        _put_string(head, name)
    head += bytes(-(len(head) - 4) % 4) + _COUNT.pack(n)
    start = len(head)
    layouts = [_point_layout(start, joints)]
    layouts.append(_point_layout(start + layouts[0][0], joints))
    origin, end = _alternating_starts(start, layouts[0][0], layouts[1][0], n)
    k = np.arange(n)
    second = (origin - start) % 8 != 0
    out = np.zeros(-(-end // 8) * 8 + 8, dtype=np.uint8)
    out[:start] = np.frombuffer(bytes(head), dtype=np.uint8)
    words = out.view('<u4')
    doubles = out[4:len(out) - 4].view('<f8')
    for parity in (0, 1):
        points = k[second == parity]
        base = origin[points]
        _, counts, data, clock = layouts[parity]
        for count, at, values in zip(counts, data, (
                positions, velocities, accelerations, efforts)):
            words[(base + count) // 4] = joints
            index = (base + at - 4)[:, None] // 8 + np.arange(joints)
            doubles[index] = np.asarray(values, dtype=float)[points]
        words[(base + clock) // 4] = np.asarray(
            time, dtype=np.int64)[points, 0].astype('<i4').view('<u4')
        words[(base + clock) // 4 + 1] = np.asarray(
            time, dtype=np.int64)[points, 1]
    return out[:end].tobytes()


def multi_dof_trajectory(stamp: Stamp, frame: str, names: Sequence[str],
                         time: Array, positions: Array, velocities: Array,
                         accelerations: Array) -> bytes:
    """
    Serialize a ``trajectory_msgs/MultiDOFJointTrajectory`` of one body.

    Each point holds one transform (``positions`` (N, 3) m, the identity
    rotation), one twist (``velocities`` (N, 3) m/s linear, no angular)
    and one acceleration (``accelerations`` (N, 3) m/s^2), and its
    ``time`` (N, 2) (sec, nanosec); ``names``: the body's joint name.
    Returns the bytes ``Publisher.publish`` sends as is (little-endian CDR;
    the reader is :func:`cartesian_trajectory`).
    """
    out = bytearray(b'\x00\x01\x00\x00')
    out += _STAMP.pack(*stamp)
    _put_string(out, frame)
    out += bytes(-(len(out) - 4) % 4) + _COUNT.pack(len(names))
    for name in names:
        out += bytes(-(len(out) - 4) % 4)
        _put_string(out, name)
    out += bytes(-(len(out) - 4) % 4) + _COUNT.pack(len(time))
    one = _COUNT.pack(1)
    zero3 = (0.0, 0.0, 0.0)
    for k in range(len(time)):
        for count, values in ((one, (*positions[k], 0.0, 0.0, 0.0, 1.0)),
                              (one, (*velocities[k], *zero3)),
                              (one, (*accelerations[k], *zero3))):
            out += bytes(-(len(out) - 4) % 4) + count
            out += bytes(-(len(out) - 4) % 8)
            out += struct.pack(f'<{len(values)}d', *values)
        out += bytes(-(len(out) - 4) % 4)
        out += _STAMP.pack(int(time[k][0]), int(time[k][1]))
    return bytes(out)


def _point_layout(origin, joints):
    """
    Return one JointTrajectoryPoint's layout when it starts at ``origin``.

    ``(size, count offsets, data offsets, time offset)``, offsets from the
    point's start, for four arrays of ``joints`` doubles and the duration.
    """
    offset, counts, data = origin, [], []
    for _ in range(4):
        offset += -(offset - 4) % 4
        counts.append(offset - origin)
        offset += 4
        if joints:
            offset += -(offset - 4) % 8
        data.append(offset - origin)
        offset += 8 * joints
    offset += -(offset - 4) % 4
    clock = offset - origin
    return offset + 8 - origin, counts, data, clock


def _put_string(out, text):
    data = text.encode('utf-8') + b'\x00'
    out += _COUNT.pack(len(data)) + data


def _encapsulation(buf):
    if bytes(buf[:2]) not in _LITTLE_ENDIAN_CDR:
        raise CdrError(f'encapsulation {bytes(buf[:2]).hex(" ")} is not '
                       'read: ROS 2 hosts write little-endian CDR (00 01)')


def _string(buf, offset):
    """Read a CDR string at ``offset``; return it and the next offset."""
    length, offset = _count(buf, offset)
    end = offset + length
    if length == 0 or end > len(buf) or buf[end - 1] != 0:
        raise CdrError('bad string')
    try:
        return bytes(buf[offset:end - 1]).decode('utf-8'), end
    except UnicodeDecodeError:
        raise CdrError('a string is not UTF-8') from None


def _doubles(buf, offset):
    """Read a float64 sequence at ``offset``; return it and the next one."""
    count, offset = _count(buf, offset)
    if count:
        offset = _align(offset, 8)
    end = offset + 8 * count
    if end > len(buf):
        raise CdrError('truncated message')
    return struct.unpack_from(f'<{count}d', buf, offset), end


def _header(buf):
    """Read the encapsulation and std_msgs/Header; return the next offset."""
    _encapsulation(buf)
    sec, nanosec = _unpack(_STAMP, buf, 4)
    frame, end = _string(buf, 12)
    return (sec, nanosec), frame, end


def _trajectory_header(buf):
    """
    Read a trajectory's header and joint_names (at most MAX_JOINT_NAMES).

    Returns the stamp, the frame and the offset of the points.
    """
    stamp, frame, offset = _header(buf)
    names, offset = _count(buf, offset)
    if names > MAX_JOINT_NAMES:
        raise LimitError(f'{names} joint_names: at most {MAX_JOINT_NAMES}')
    for _ in range(names):
        _, offset = _string(buf, offset)
    return stamp, frame, offset


def _count(buf, offset):
    offset = _align(offset, 4)
    return _unpack(_COUNT, buf, offset)[0], offset + 4


def _align(offset, size):
    """Align ``offset`` to ``size`` counted from the end of the header."""
    return offset + (-(offset - 4) % size)


def _unpack(layout, buf, offset):
    if offset + layout.size > len(buf):
        raise CdrError('truncated message')
    return layout.unpack_from(buf, offset)


def _multi_dof_point_bytes():
    """Return the bytes of each point after the first (all the same)."""
    one, two = (len(multi_dof_trajectory(
        (0, 0), '', ('platform',), np.zeros((n, 2), dtype=np.int64),
        *(np.zeros((n, 3)) for _ in range(3)))) for n in (1, 2))
    return two - one


# Bytes of a point of :func:`multi_dof_trajectory` (a multiple of 8, so
# every point but the first, whose padding may add 4, takes as much).
MULTI_DOF_POINT_BYTES = _multi_dof_point_bytes()
