"""
The rules of a Cartesian setpoint, written once for one sample and for N.

A setpoint of the feedforward (a pose, twist and accel of one stamp, or one
trajectory point) and every point of a whole Cartesian trajectory meet the
same rules (``doc/feedforward.md``), checked in this order by
:func:`solve_setpoints`:

- ``orientation`` / ``non_finite``: the platform's rotation is finite and
  within ORIENTATION_TOLERANCE of the identity (the Orthoglide only
  translates);
- ``speed_limit`` / ``acceleration_limit``: ``|v|`` and ``|a|`` of G
  within ``max_speed`` and ``max_acceleration``;
- the mechanics' refusals (``non_finite``, ``unreachable``, ``singular``,
  ``overflow``) of :func:`mechanics.solve` / :func:`mechanics.solve_batch`;
- ``velocity_limit`` / ``force_limit``: ``|lambdadot|`` and ``|f|`` of
  each actuator within its limit, and ``|f|`` within ``max_force``.

The frame rule (:func:`check_frame`) is the header's, checked by the
callers before. As in :mod:`orthoglide_ros.model.kernel`, the rules see
components and the operations passed in: :data:`SAMPLE` (floats and
``math``, one control tick) or :data:`POINTS` ((N,) arrays and numpy, a
whole trajectory), so one text serves both. A broken rule raises
:class:`Rejected` with its reason, for N points naming the first point at
fault (``point <i>: ``).
"""

from collections import namedtuple
import math
import operator

import numpy as np

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.model import mechanics

# Largest rotation of the platform accepted as "the identity" (rad).
ORIENTATION_TOLERANCE = 1e-3

Ops = namedtuple('Ops', 'columns isfinite not_ hypot atan2 abs first at '
                        'where solve')
Ops.__doc__ = """What the rules compute with: ``columns`` splits a vector
(or an (N, k) array) into its components; ``first(bad)`` is the index of
the first True (None when none); ``at(values, i)`` the value there;
``where(i)`` the prefix that names it; ``solve`` the mechanics'."""


def _first_true(bad):
    return int(np.argmax(bad)) if bad.any() else None


SAMPLE = Ops(tuple, math.isfinite, operator.not_, math.hypot, math.atan2,
             abs, lambda bad: 0 if bad else None, lambda values, i: values,
             lambda i: '', mechanics.solve)
POINTS = Ops(lambda array: tuple(array.T), np.isfinite, np.logical_not,
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
                    orientation, ops, per_actuator=False):
    """
    Check one setpoint or N points by every rule; return their Solution.

    ``position``, ``velocity``, ``acceleration`` (m, m/s, m/s^2) and
    ``orientation`` (quaternion x y z w): 3- and 4-sequences with
    :data:`SAMPLE`, (N, 3) and (N, 4) arrays with :data:`POINTS`.
    ``per_actuator``: also the per-actuator ``velocity_limit`` and
    ``force_limit`` of a whole trajectory (0.0: none), besides
    ``max_force``. Raises :class:`Rejected` (see the module docstring).
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
        i = ops.first(finite & (norm > bound))
        if i is not None:
            vector = (velocity, acceleration)[reason == 'acceleration_limit']
            raise Rejected(reason, (
                f'{ops.where(i)}{name.removeprefix("max_")} '
                f'{mechanics.format_vector(ops.at(vector, i))} {unit} is '
                f'beyond {name} {bound:g} {unit}'))
    try:
        solution = ops.solve(settings.robot, position, velocity,
                             acceleration, settings.singularity_margin)
    except mechanics.WorkspaceError as error:
        raise Rejected(error.reason, ops.where(error.row) + error.detail) \
            from None
    _check_actuators(settings, solution, ops, per_actuator)
    return solution


def _check_orientation(ops, q):
    """Refuse a rotation not finite, zero, or beyond the tolerance."""
    x, y, z, w = q
    finite = ops.isfinite(x) & ops.isfinite(y) & ops.isfinite(z) \
        & ops.isfinite(w)
    i = ops.first(ops.not_(finite))
    if i is not None:
        raise Rejected('non_finite', (
            f'{ops.where(i)}orientation {_quaternion(ops, q, i)} is not '
            'finite'))
    # hypot: no squares to overflow (1e200) or underflow (1e-200).
    vector = ops.hypot(ops.hypot(x, y), z)
    i = ops.first((vector == 0.0) & (w == 0.0))
    if i is not None:
        raise Rejected('orientation', f'{ops.where(i)}orientation is the '
                       'zero quaternion')
    angle = 2.0 * ops.atan2(vector, ops.abs(w))
    i = ops.first(angle > ORIENTATION_TOLERANCE)
    if i is not None:
        raise Rejected('orientation', (
            f'{ops.where(i)}platform orientation turns '
            f'{ops.at(angle, i):.3g} rad from the identity (tolerance '
            f'{ORIENTATION_TOLERANCE:g} rad): the Orthoglide only '
            'translates'))


def _quaternion(ops, q, i):
    return tuple(float(ops.at(c, i)) for c in q)


def _check_actuators(settings, solution, ops, per_actuator):
    """Refuse a |lambdadot| or |f| beyond an actuator's limit (first point)."""
    for reason, values, limits, unit in (
            ('velocity_limit', solution.lambdadot,
             settings.velocity_limit if per_actuator else (0.0,) * 3, 'm/s'),
            ('force_limit', solution.force,
             settings.force_limit if per_actuator else (0.0,) * 3, 'N')):
        beyond = []
        for leg, (component, limit) in enumerate(zip(ops.columns(values),
                                                     limits)):
            name = f'the limit of actuator {"ABC"[leg]}'
            if reason == 'force_limit' and not 0.0 < limit < \
                    settings.max_force:
                limit, name = settings.max_force, 'max_force'
            i = ops.first(ops.abs(component) > limit) if limit else None
            if i is not None:
                beyond.append((i, leg, ops.at(component, i), limit, name))
        if beyond:
            i, leg, value, limit, name = min(beyond)
            raise Rejected(reason, (
                f'{ops.where(i)}actuator {"ABC"[leg]} needs {value:.6g} '
                f'{unit}, beyond {name} {limit:g} {unit}'))
