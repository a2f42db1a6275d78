"""
The logs identification reads: CSV files and rosbag2 bags, without ROS.

:func:`read_log` returns a :class:`Log` (times, the sliders' ``lambda``,
the actuators' forces, optionally measured ``lambdadot``; s, m, N, m/s);
:func:`check_log` refuses what cannot be identified from, naming the
sample and the column; :func:`crop` takes a window. rosbags is imported
only to read a bag. See doc/identification.md#logs.
"""

from __future__ import annotations

from typing import Callable, Optional, Sequence
from collections import namedtuple
import math
import os

import numpy as np

from orthoglide_ros.formats import cdr, csvfile
from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.model.robot import JOINT_NAMES, LEGS
from orthoglide_ros.model.types import Path
# The log's columns in a CSV file (those `orthoglide batch` writes); the
# measured velocities are optional.
LOG_GROUPS = (('time', ('t',), True),
              ('lambda', ('lambda_a', 'lambda_b', 'lambda_c'), True),
              ('force', ('force_a', 'force_b', 'force_c'), True),
              ('lambdadot', ('lambdadot_a', 'lambdadot_b', 'lambdadot_c'),
               False))
# The largest magnitude a log's value may have, by quantity: beyond it no
# robot the package models has it, and the arithmetic of identification
# (squares, sums over millions of samples) would leave the finite
# numbers. Time: 1e10 s (a Unix time in s holds until the year 2286);
# lambda: 1e3 m (ten times the longest length a robot may have,
# robot.LENGTH_LIMITS); force: 1e9 N (the largest joint_limits
# max_effort a node accepts, planning.limits.LIMIT_BOUND); lambdadot: 1e3
# m/s (the largest max_speed the feedforward accepts).
LIMITS = {'t': (1e10, 's'), 'lambda': (1e3, 'm'), 'force': (1e9, 'N'),
          'lambdadot': (1e3, 'm/s')}
JOINT_STATE_TYPE = 'sensor_msgs/msg/JointState'
DEFAULT_TOPIC = '/joint_states'
BAG_SUFFIXES = ('.mcap', '.db3')

Log = namedtuple('Log', ('times', 'lambdas', 'forces', 'source', 'origin',
                         'lambdadots'), defaults=(0, None))
Log.__doc__ = """A measured log: ``times`` (N,) s, ``lambdas`` (N, 3) m and
``forces`` (N, 3) N of actuators A, B, C; ``source`` names it; ``times``
are counted from ``origin`` (ns; a bag's first header stamp, else 0);
``lambdadots`` (N, 3) m/s: measured velocities, or None."""


class LogError(ValueError):
    """A log that cannot be read or used; the message says why."""


def check_log(log: 'Log',
              where: Optional[Callable[[int], str]] = None) -> None:
    """
    Refuse a :class:`Log` that cannot be identified from (:class:`LogError`).

    Shapes (``times`` (N,), the others (N, 3)), every value finite and
    within its quantity's LIMITS, times strictly increasing, at least
    three samples. ``where(k)`` names the 0-based sample ``k`` in the
    message (default ``'sample k + 1'``; a CSV file's data row, a bag's
    message).
    """
    where = where or (lambda k: f'sample {k + 1}')
    times = np.asarray(log.times, dtype=float)
    arrays = [('lambda', log.lambdas), ('force', log.forces)]
    if log.lambdadots is not None:
        arrays.append(('lambdadot', log.lambdadots))
    arrays = [(q, np.asarray(a, dtype=float)) for q, a in arrays]
    if times.ndim != 1 or any(a.shape != (len(times), 3) for _, a in arrays):
        raise LogError(f'{log.source}: times (N,), lambdas, forces and '
                       'lambdadots (N, 3) expected')
    for quantity, values in [('t', times[:, None])] + arrays:
        limit, unit = LIMITS[quantity]
        bad = ~(np.abs(values) <= limit)
        if bad.any():
            k, j = (int(i) for i in np.argwhere(bad)[0])
            column = 't' if quantity == 't' else f'{quantity}_{LEGS[j]}'
            value = float(values[k, j])
            raise LogError(f'{log.source}: {where(k)}: {column} is '
                           f'{value!r}, ' + (
                               f'outside [{-limit:g}, {limit:g}] {unit}, the '
                               'range a log may hold' if math.isfinite(value)
                               else 'not a finite number'))
    late = np.flatnonzero(np.diff(times) <= 0.0)
    if len(late):
        k = int(late[0]) + 1
        raise LogError(f'{log.source}: {where(k)}: time {float(times[k])!r} '
                       f's is not after the sample before '
                       f'({float(times[k - 1])!r} s): time must increase '
                       'strictly')
    if len(times) < 3:
        raise LogError(f'{log.source}: {len(times)} sample(s): too few to '
                       'identify anything')


def crop(log: 'Log', start: Optional[float] = None,
         end: Optional[float] = None) -> 'Log':
    """
    Return the samples of ``log`` from ``start`` to ``end`` (s, inclusive).

    Both counted from the log's first sample (its earliest time); None:
    from the first, to the last. Raises :class:`LogError` when nothing is
    left.

    >>> log = Log(np.array([5.0, 5.5, 6.0]), np.zeros((3, 3)),
    ...           np.zeros((3, 3)), 'log')
    >>> crop(log, 0.5).times.tolist()
    [5.5, 6.0]
    """
    times = np.asarray(log.times, dtype=float)
    first = times.min() if len(times) else 0.0
    keep = np.ones(len(times), dtype=bool)
    if start is not None:
        keep &= times >= first + start
    if end is not None:
        keep &= times <= first + end
    if not keep.any():
        raise LogError(f'{log.source}: no sample between {start} s and '
                       f'{end} s from its first')
    return Log(times[keep], np.asarray(log.lambdas)[keep],
               np.asarray(log.forces)[keep], log.source, log.origin,
               None if log.lambdadots is None
               else np.asarray(log.lambdadots)[keep])


def read_log(path: Path, topic: str = DEFAULT_TOPIC,
             joint_names: Sequence[str] = JOINT_NAMES) -> 'Log':
    """
    Read a log: a rosbag2 bag (:func:`read_bag`) or a CSV (:func:`read_csv`).

    A directory, or a ``.mcap`` or ``.db3`` file, is a bag; anything else
    a CSV file.
    """
    path = str(path)
    if os.path.isdir(path) or path.endswith(BAG_SUFFIXES) \
            and os.path.isfile(path):
        return read_bag(path, topic, joint_names)
    return read_csv(path)


def read_csv(path: Path) -> 'Log':
    """
    Read a log from a CSV file and check it (:func:`check_log`).

    Columns ``t`` (s), ``lambda_a``, ``lambda_b``, ``lambda_c`` (m),
    ``force_a``, ``force_b``, ``force_c`` (N) and, optional,
    ``lambdadot_a``, ``lambdadot_b``, ``lambdadot_c`` (m/s), matched by
    name as :func:`csvfile.read_columns` does (the columns of ``orthoglide
    batch``); others ignored. Raises :class:`LogError`.
    """
    try:
        values, lines = read_columns(path, LOG_GROUPS)
    except CsvError as error:
        raise LogError(str(error)) from None
    log = Log(values['time'][:, 0], values['lambda'], values['force'],
              str(path), lambdadots=values['lambdadot'])
    check_log(log, lambda k: f'data row {k + 1} (line {lines[k]})')
    return log


def read_bag(path: Path, topic: str = DEFAULT_TOPIC,
             joint_names: Sequence[str] = JOINT_NAMES) -> 'Log':
    """
    Read a log from the ``sensor_msgs/JointState`` messages of a rosbag2 bag.

    ``path``: the bag's directory, or its ``.mcap`` or ``.db3`` file (the
    bag of its directory when a ``metadata.yaml`` is beside it, else the
    file alone); ``topic`` (a leading ``/`` is added); ``joint_names``: the
    joints of actuators A, B, C. Time from the header stamps, in s from the
    earliest (``origin``, ns); the velocity is not read; at most
    ``csvfile.MAX_ROWS`` messages (doc/identification.md#logs). Checked by
    :func:`check_log`. Raises :class:`LogError`.
    """
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:
        raise LogError('reading a rosbag2 bag needs the rosbags package '
                       '(pip install rosbags)') from None
    name = topic if topic.startswith('/') else '/' + topic
    source = str(path)
    if os.path.isfile(path) and os.path.isfile(os.path.join(
            os.path.dirname(source), 'metadata.yaml')):
        path = os.path.dirname(source) or '.'
    times, lambdas, forces = [], [], []
    orders = {}
    try:
        with Reader(path) as reader:
            connections = [c for c in reader.connections if c.topic == name]
            if not connections:
                topics = sorted({c.topic for c in reader.connections})
                raise LogError(f'{source}: no topic {name} in the bag (it '
                               f'has {", ".join(topics) or "none"})')
            for connection in connections:
                if connection.msgtype != JOINT_STATE_TYPE:
                    raise LogError(f'{source}: {name} carries '
                                   f'{connection.msgtype}, not '
                                   f'{JOINT_STATE_TYPE}')
            for _, _, raw in reader.messages(connections=connections):
                if len(times) == csvfile.MAX_ROWS:
                    raise LogError(f'{source}: more than {len(times)} '
                                   f'messages on {name}: crop the bag')
                stamp, names, position, effort = _joint_state(raw)
                order = orders.get(names)
                if order is None:
                    order = orders[names] = _joint_order(
                        source, names, joint_names, len(position),
                        len(effort))
                times.append(stamp)
                lambdas.append([position[k] for k in order])
                forces.append([effort[k] for k in order])
    except LogError:
        raise
    except Exception as error:  # rosbags' errors, unreadable files
        raise LogError(f'{source}: cannot read the bag: {error}') from None
    if not times:
        raise LogError(f'{source}: no message on {name}')
    stamps = np.array(times, dtype=np.int64)
    origin = int(stamps.min())
    log = Log((stamps - origin) * 1e-9, np.array(lambdas), np.array(forces),
              source, origin)
    check_log(log, lambda k: f'message {k + 1} on {name}')
    return log


def _joint_state(raw):
    """Return ``(stamp ns, names, position, effort)`` of a JointState."""
    try:
        (sec, nanosec), _, names, position, _, effort = cdr.joint_state(raw)
    except ValueError:      # not little-endian CDR: the full deserializer
        from rosbags.typesys import get_typestore, Stores
        msg = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(
            raw, JOINT_STATE_TYPE)
        sec, nanosec = msg.header.stamp.sec, msg.header.stamp.nanosec
        names, position, effort = (tuple(msg.name), tuple(msg.position),
                                   tuple(msg.effort))
    return sec * 10**9 + nanosec, names, position, effort


def _joint_order(path, names, joint_names, positions, efforts):
    """Return the indices of ``joint_names`` in a message's ``names``."""
    missing = [j for j in joint_names if j not in names]
    if missing:
        raise LogError(f'{path}: joint states without {missing[0]!r} '
                       f'(names {list(names)}): set the joint names')
    order = [names.index(j) for j in joint_names]
    if max(order) >= min(positions, efforts):
        raise LogError(f'{path}: joint states without a position and an '
                       'effort per joint: the force must be in effort')
    return order
