"""
The rules of a Cartesian setpoint, written once for one sample and for N.

:func:`solve_setpoints` checks a feedforward setpoint and every point of a
Cartesian trajectory by the rules of doc/feedforward.md, in its order; as
in :mod:`orthoglide_ros.model.kernel`, one text serves floats and
``math`` (:data:`ONE_SAMPLE`) and arrays and numpy (:data:`N_POINTS`).
"""

from collections import namedtuple
import math
import operator

import numpy as np

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import joint_limit
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import JOINT_NAMES

# Largest rotation of the platform accepted as "the identity" (rad).
ORIENTATION_TOLERANCE = 1e-3

Ops = namedtuple('Ops', 'columns isfinite not_ hypot atan2 abs '
                        'first_bad_index value_at point_prefix solve')
Ops.__doc__ = """What the rules compute with: ``columns`` splits a vector
(or an (N, k) array) into its components; ``first_bad_index(bad)`` is the
index of the first True (None when none); ``value_at(values, i)`` the value
there; ``point_prefix(i)`` the prefix that names it in a message (``point
<i>: ``, empty for one sample); ``solve`` the mechanics'."""


def _first_true(bad):
    return int(np.argmax(bad)) if bad.any() else None


ONE_SAMPLE = Ops(tuple, math.isfinite, operator.not_, math.hypot,
                 math.atan2, abs, lambda bad: 0 if bad else None,
                 lambda values, i: values, lambda i: '', mechanics.solve)
N_POINTS = Ops(lambda array: tuple(array.T), np.isfinite, np.logical_not,
               np.hypot, np.arctan2, np.abs, _first_true,
               lambda values, i: values[i], lambda i: f'point {i}: ',
               mechanics.solve_batch)


def check_frame(frame, settings, what='setpoint'):
    """Refuse (``frame``) a frame neither empty nor ``base_frame``."""
    if frame and frame != settings.base_frame:
        raise Rejected('frame', (
            f'{what} in frame {frame!r}, expected {settings.base_frame!r} '
            '(or empty)'))


def solve_setpoints(settings, position, velocity, acceleration,
                    orientation, ops):
    """
    Check one setpoint or N points by every rule; return their Solution.

    ``position``, ``velocity``, ``acceleration`` (m, m/s, m/s^2) and
    ``orientation`` (quaternion x y z w): 3- and 4-sequences with
    :data:`ONE_SAMPLE`, (N, 3) and (N, 4) arrays with :data:`N_POINTS`.
    Last, each actuator's ``joint_limits.<joint>.max_velocity`` and
    ``max_effort``. Raises :class:`Rejected` with the reason of the first
    rule broken, for N points naming the first point at fault (``point
    <i>: ``).
    """
    _check_orientation(ops, ops.columns(orientation))
    columns = [ops.columns(v) for v in (position, velocity, acceleration)]
    finite = True
    for component in (*columns[0], *columns[1], *columns[2]):
        finite = finite & ops.isfinite(component)
    for reason, (cx, cy, cz), bound, name, unit in (
            ('speed_limit', columns[1], settings.max_speed, 'max_speed',
             'm/s'),
            ('acceleration_limit', columns[2], settings.max_acceleration,
             'max_acceleration', 'm/s^2')):
        # hypot: no squares to overflow. A NaN or an infinity in a
        # setpoint is the mechanics' non_finite, checked next.
        norm = ops.hypot(ops.hypot(cx, cy), cz)
        i = ops.first_bad_index(finite & (norm > bound))
        if i is not None:
            vector = (velocity, acceleration)[reason == 'acceleration_limit']
            value = mechanics.format_vector(ops.value_at(vector, i))
            raise Rejected(reason, (
                f'{ops.point_prefix(i)}{name.removeprefix("max_")} '
                f'{value} {unit} is beyond {name} {bound:g} {unit}'))
    try:
        solution = ops.solve(settings.robot, position, velocity,
                             acceleration, settings.singularity_margin)
    except mechanics.WorkspaceError as error:
        raise Rejected(error.reason,
                       ops.point_prefix(error.row) + error.detail) from None
    _check_actuators(settings, solution, ops)
    return solution


def _check_orientation(ops, q):
    """Refuse a rotation not finite, zero, or beyond the tolerance."""
    x, y, z, w = q
    finite = ops.isfinite(x) & ops.isfinite(y) & ops.isfinite(z) \
        & ops.isfinite(w)
    i = ops.first_bad_index(ops.not_(finite))
    if i is not None:
        raise Rejected('non_finite', (
            f'{ops.point_prefix(i)}orientation {_quaternion(ops, q, i)} is '
            'not finite'))
    # hypot: no squares to overflow (1e200) or underflow (1e-200).
    vector = ops.hypot(ops.hypot(x, y), z)
    i = ops.first_bad_index((vector == 0.0) & (w == 0.0))
    if i is not None:
        raise Rejected('orientation', f'{ops.point_prefix(i)}orientation '
                       'is the zero quaternion')
    angle = 2.0 * ops.atan2(vector, ops.abs(w))
    i = ops.first_bad_index(angle > ORIENTATION_TOLERANCE)
    if i is not None:
        raise Rejected('orientation', (
            f'{ops.point_prefix(i)}platform orientation turns '
            f'{ops.value_at(angle, i):.3g} rad from the identity (tolerance '
            f'{ORIENTATION_TOLERANCE:g} rad): the Orthoglide only '
            'translates'))


def _quaternion(ops, q, i):
    return tuple(float(ops.value_at(c, i)) for c in q)


def _check_actuators(settings, solution, ops):
    """Refuse a |lambdadot| or |f| beyond an actuator's joint limit."""
    for reason, values, key, unit in (
            ('velocity_limit', solution.lambdadot, 'max_velocity', 'm/s'),
            ('force_limit', solution.force, 'max_effort', 'N')):
        beyond = []
        for leg, (component, limit, joint) in enumerate(zip(
                ops.columns(values), joint_limit(settings, key),
                JOINT_NAMES)):
            i = ops.first_bad_index(ops.abs(component) > limit)
            if i is not None:
                beyond.append((i, leg, ops.value_at(component, i), limit,
                               joint))
        if beyond:
            i, leg, value, limit, joint = min(beyond)
            raise Rejected(reason, (
                f'{ops.point_prefix(i)}actuator {"ABC"[leg]} needs '
                f'{value:.6g} {unit}, beyond joint_limits.{joint}.{key} '
                f'{limit:g} {unit}'))
