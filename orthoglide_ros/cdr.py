"""
Read setpoints straight from serialized (CDR) messages, without rclpy.

rclpy turns each received message into Python objects, which costs more CPU
than everything the feedforward does with it (measured here: about 80 us for
a MultiDOFJointTrajectory and 60 us for a PoseStamped, against 20-25 us to
take the raw bytes and read the few fields with ``struct``). The node
therefore subscribes with ``raw=True`` and reads only what it uses:

- ``PoseStamped``: stamp, frame, position, orientation;
- ``TwistStamped`` / ``AccelStamped``: stamp, frame, linear part;
- ``MultiDOFJointTrajectory``: stamp, frame and, of the first point, the
  first transform, velocity, acceleration and ``time_from_start``;
- ``JointState``: stamp, frame, names, positions, velocities, efforts;
- ``Float64MultiArray``: the data (the layout is skipped).

The layout is the OMG CDR encoding of the ROS 2 message definitions
(XCDR1: a 4-byte encapsulation header, then each primitive aligned to its
size counted from the end of that header; strings as a length that counts
the terminating NUL, then the bytes; sequences as a count, then the items).
A buffer this reader does not understand (big-endian, truncated, bad text)
raises :class:`CdrError`; the node then falls back to rclpy's deserializer
(for short messages), so this is a fast path, never the only path. A
well-formed buffer whose cost to read would grow with a list the node does
not use (``joint_names``) raises :class:`LimitError` beyond
:data:`MAX_JOINT_NAMES`: what a message holds cannot make reading it slow.
"""

import struct

_STAMP = struct.Struct('<iI')          # stamp.sec, stamp.nanosec
_COUNT = struct.Struct('<I')
_VECTOR = struct.Struct('<3d')
_POSE = struct.Struct('<7d')           # position, orientation (x, y, z, w)
_DURATION = struct.Struct('<iI')
_LITTLE_ENDIAN_CDR = (b'\x00\x01', b'\x00\x03')   # CDR_LE, PL_CDR_LE
# Joint names a MultiDOFJointTrajectory may carry (the platform's one, and
# room to spare): the reader skips them one by one.
MAX_JOINT_NAMES = 64


class CdrError(ValueError):
    """A buffer this reader does not understand (use the deserializer)."""


class LimitError(ValueError):
    """A well-formed buffer beyond what this reader reads (refuse it)."""


def pose_stamped(buf):
    """Return ``(stamp, frame, position, orientation)`` of a PoseStamped."""
    stamp, frame, offset = _header(buf)
    values = _unpack(_POSE, buf, _align(offset, 8))
    return stamp, frame, values[:3], values[3:]


def vector3_stamped(buf):
    """Return ``(stamp, frame, linear)`` of a TwistStamped or AccelStamped."""
    stamp, frame, offset = _header(buf)
    offset = _align(offset, 8)
    _unpack(_VECTOR, buf, offset + _VECTOR.size)      # the angular part
    return stamp, frame, _unpack(_VECTOR, buf, offset)


def trajectory_point(buf):
    """
    Read a MultiDOFJointTrajectory's header and first point.

    Returns ``(stamp, frame, point)``; ``point`` is None when there is no
    point or its first point has no transform, else ``(translation,
    rotation, velocity or None, acceleration or None, time_from_start)``
    with ``time_from_start`` as ``(sec, nanosec)``.
    """
    stamp, frame, offset = _header(buf)
    names, offset = _count(buf, offset)
    if names > MAX_JOINT_NAMES:
        raise LimitError(f'{names} joint_names: at most {MAX_JOINT_NAMES}')
    for _ in range(names):
        length, offset = _count(buf, offset)
        offset += length
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


def joint_state(buf):
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


def float64_array(buf):
    """Read a Float64MultiArray's ``data`` as a tuple of floats."""
    _encapsulation(buf)
    dims, offset = _count(buf, 4)
    for _ in range(dims):
        _, offset = _string(buf, offset)
        offset = _align(offset, 4) + 8      # size, stride
    offset = _align(offset, 4) + 4          # data_offset
    return _doubles(buf, offset)[0]


def _encapsulation(buf):
    if bytes(buf[:2]) not in _LITTLE_ENDIAN_CDR:
        raise CdrError('not little-endian CDR')


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
