"""
The Orthoglide's constant description: lengths, masses, gravity, terms.

One immutable :class:`Robot`, validated once, is every algorithm's first
argument (as Pinocchio's ``Model``) and never validated again on the hot
path; its fields are :data:`ROWS` (doc/model.md#parameters), each leg's
geometry among them (:mod:`legs`, doc/model.md#the-machine-as-built).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
import math
from typing import Any, Tuple

import numpy as np

from orthoglide_ros.model import legs, terms
from orthoglide_ros.model.kernel import KernelConstants, LegConstants
from orthoglide_ros.model.terms import (  # noqa: F401 (the rows' names)
    FORCE_LIMITS, LENGTH_LIMITS, MASS_LIMITS, NO_FRICTION, Row,
    SPEED_LIMITS)

# The legs' suffixes, in the order of every per-actuator triple.
LEGS = ('a', 'b', 'c')
# The prismatic joints of actuators A, B, C: the default joint_names of
# every node, of the URDF and of the logs.
JOINT_NAMES = tuple(f'slider_{leg}' for leg in LEGS)
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
ZERO = (0.0, 0.0, 0.0)
# A leg's points and offsets lie within 0.1 m of the drawing's (m, each
# coordinate), its axis within MAX_TILT_DEG of the drawing's, a unit vector
# to UNIT_TOLERANCE: far beyond any built Orthoglide's errors.
OFFSET_LIMITS = (-0.1, 0.1)
# A leg's bars within this of the drawing's l3 (m), as its points are.
MAX_LENGTH_DEVIATION = 0.1
DIRECTION_LIMITS = (-1.001, 1.001)
UNIT_TOLERANCE = 1e-3
MAX_TILT_DEG = 10.0

Vector = Tuple[float, float, float]

# The machine as built: each leg's geometry (:mod:`legs`), by default the
# drawing's (doc/model.md#the-machine-as-built).
GEOMETRY_ROWS = tuple(
    Row(f'axis_point_{leg}', (0.0, 0.0, 0.0), 'm', OFFSET_LIMITS,
        f'point a of actuator {leg.upper()}\'s axis where leg {leg.upper()} '
        'holds its platform point when the slider\'s true position is 0 and '
        'the bars lie along the axis (frame 0; the drawing: the origin)')
    for leg in LEGS) + tuple(
    Row(f'axis_direction_{leg}', axis, 'unit vector', DIRECTION_LIMITS,
        f'direction u of +lambda on actuator {leg.upper()}\'s axis (frame '
        f'0), within {MAX_TILT_DEG:g} deg of the drawing\'s')
    for leg, axis in zip(LEGS, legs.DRAWING_AXES)) + (
    Row('joint_offset', (0.0, 0.0, 0.0), 'm', OFFSET_LIMITS,
        'offsets e of the joint readings of A, B, C: a slider\'s true '
        'position is its reading plus its offset'),
    Row('bar_length', None, 'm', LENGTH_LIMITS,
        'length L of the parallelogram bars of legs A, B, C, each within '
        f'{MAX_LENGTH_DEVIATION:g} m of l3; defaults to l3 on each leg',
        'l3'),
) + tuple(
    Row(f'attachment_{leg}', (0.0, 0.0, 0.0), 'm', OFFSET_LIMITS,
        f'leg {leg.upper()}\'s point r on the platform relative to its '
        'centre G (frame 0; the drawing: G itself)')
    for leg in LEGS)
# The paper's parameters (section 2), each leg's geometry, every term's.
ROWS = (
    Row('l', 0.20, 'm', LENGTH_LIMITS, 'side of the cubic platform (body 5)'),
    Row('l1', 0.15, 'm', LENGTH_LIMITS,
        'length of the slider rod A1A2 (body 1)'),
    Row('l2', 0.08, 'm', LENGTH_LIMITS,
        'length of the rods A3A6 (body 2) and A4A7 (body 4)'),
    Row('l3', 0.85, 'm', LENGTH_LIMITS,
        'length of the parallelogram bars A3A4 (body 3) and A6A7 (body 6)'),
    Row('alpha', math.pi / 4, 'rad', (0.0, math.pi / 2),
        'orientation angle of the slider rod about its guide-way',
        open=True),
    Row('m1', 0.35, 'kg', MASS_LIMITS, 'mass of each slider (body 1)'),
    Row('m2', 0.2, 'kg', MASS_LIMITS, 'mass of each rod A3A6 (body 2)'),
    Row('m3', 2.5, 'kg', MASS_LIMITS, 'mass of each bar A3A4 (body 3)'),
    Row('m4', None, 'kg', MASS_LIMITS,
        'mass of each rod A4A7 (body 4); defaults to m2', 'm2'),
    Row('m5', 15.0, 'kg', MASS_LIMITS,
        'mass of the platform (body 5, counted once)'),
    Row('m6', None, 'kg', MASS_LIMITS,
        'mass of each bar A6A7 (body 6); defaults to m3', 'm3'),
    Row('gravity', DEFAULT_GRAVITY, 'm/s^2', (-100.0, 100.0),
        'gravity vector in the base frame 0'),
) + GEOMETRY_ROWS + tuple(row for term in terms.TERMS for row in term.rows)
ROW = {row.name: row for row in ROWS}
# The rows that need another's value on an actuator (Row.needs).
NEEDING = tuple(row for row in ROWS if row.needs)
# The rows of a 3-vector that follow a scalar: one value per actuator,
# each the leader's until given.
PER_ACTUATOR = frozenset({'bar_length'})


def is_vector(row: 'Row') -> bool:
    """
    Whether ``row``'s value is a 3-vector (its own or its leader's).

    A row of :data:`PER_ACTUATOR` is one per actuator, each component
    following its scalar leader.
    """
    if row.name in PER_ACTUATOR:
        return True
    return isinstance(ROW[row.follows].default if row.follows
                      else row.default, tuple)


class ParameterError(ValueError):
    """
    A parameter value breaks a rule; the message names both.

    The one error of a bad value, of a robot (``name`` ``robot.l3``) as of
    a node's parameter (``rate_hz``).
    """

    def __init__(self, name: str, rule: str) -> None:
        """Keep ``name`` and ``rule``; the message is ``name: rule``."""
        super().__init__(f'{name}: {rule}')
        self.name = name
        self.rule = rule


def _row_fields(cls):
    """Give ``cls`` a field per row of ROWS: its name, type and default."""
    cls.__annotations__ = {row.name: Vector if is_vector(row) else float
                           for row in ROWS}
    for row in ROWS:
        setattr(cls, row.name, row.default)
    return cls


@dataclass(frozen=True)
@_row_fields
class Robot:
    """
    Geometry (m, rad), masses (kg), gravity (m/s^2, frame 0), the terms.

    One field per row of :data:`ROWS`, its default, unit, limits and
    meaning there (doc/model.md#parameters). A row that ``follows``
    another (``m4`` and ``m6`` the paper's ``m2`` and ``m3``,
    ``friction_coulomb_negative`` ``friction_coulomb``, ``bar_length``
    ``l3`` on each leg) takes its value until given. Every value must be
    finite and within its row's limits, a vector a 3-vector, and the legs
    must assemble (doc/model.md#the-machine-as-built); otherwise
    :class:`ParameterError` names the parameter (``robot.l3``). By default
    no term and the drawing's legs: the paper's robot. Derived once:
    ``legs``, each leg as built (:class:`legs.Leg`), the one accessor of a
    leg's geometry; ``as_drawn``, whether they are the drawing's.

    >>> Robot().l3
    0.85
    >>> Robot(m5=18.0).m4 == Robot().m2
    True
    >>> Robot(bar_length=(0.85, 0.851, 0.85)).legs[1].length
    0.851
    """

    def __post_init__(self):
        # (Not a field: no part of eq or repr.)
        object.__setattr__(self, 'following', frozenset(
            row.name for row in ROWS
            if row.follows and getattr(self, row.name) is None))
        for name in self.following:
            value = getattr(self, ROW[name].follows)
            object.__setattr__(self, name, (value,) * 3
                               if name in PER_ACTUATOR else value)
        for row in ROWS:
            object.__setattr__(self, row.name, _checked(
                row, getattr(self, row.name)))
        for row in NEEDING:
            _check_needs(row, getattr(self, row.name),
                         getattr(self, row.needs))
        _check_directions(self)
        _check_lengths(self)
        # Derived once (not fields: no part of eq or repr): each leg as
        # built, whether they are the drawing's (then the mechanics take
        # the drawing's closed forms), the kernel's constants, the terms
        # whose force the robot has, and whether friction is among them.
        object.__setattr__(self, 'legs', build_legs(self))
        object.__setattr__(self, 'as_drawn', all(
            leg.point == ZERO and leg.attachment == ZERO
            and leg.offset == 0.0 and leg.length == self.l3
            and leg.direction == axis
            for leg, axis in zip(self.legs, legs.DRAWING_AXES)))
        object.__setattr__(self, 'constants', kernel_constants(self))
        object.__setattr__(self, 'leg_constants',
                           leg_constants(self, self.legs))
        object.__setattr__(self, 'active_terms', terms.active(self))
        object.__setattr__(self, 'has_friction', any(
            term.friction for term in self.active_terms))
        if not self.as_drawn:
            _check_assembly(self)

    @classmethod
    def parameter_names(cls) -> tuple[str, ...]:
        """Names of the parameters, in declaration order (``robot.`` less)."""
        return tuple(f.name for f in fields(cls))

    def as_parameters(self) -> dict[str, Any]:
        """
        Return the description as a ``{name: value}`` dict.

        Scalars as floats, vectors (gravity, friction) as lists of floats:
        the ``robot.*`` parameters' types.
        """
        return {name: list(value) if isinstance(value, tuple)
                else float(value)
                for name, value in ((name, getattr(self, name))
                                    for name in self.parameter_names())}

    def replace(self, **changes: Any) -> 'Robot':
        """
        Return a validated copy with some parameters changed.

        A parameter that follows another (its row's ``follows``) not given (``following``)
        keeps following: ``Robot().replace(friction_coulomb=(5.0, 3.0,
        4.0))`` has the same Coulomb friction both ways,
        ``Robot().replace(m2=0.3).m4`` is 0.3.
        """
        values = self.as_parameters()
        for name in self.following:
            del values[name]
        values.update(changes)
        return Robot(**values)

    def frictionless(self) -> 'Robot':
        """Return a copy with no friction (every friction term's zero)."""
        return self.replace(**{terms.coefficient_name(term): NO_FRICTION
                               for term in terms.FRICTION})


def kernel_constants(robot: Robot) -> KernelConstants:
    """
    Pack the robot's values the kernel uses (lengths m, masses kg).

    ``h3 = l3 / 2`` and ``i3 = l3^2 / 3`` give body 3's centre of mass on
    its -y3 axis and its inertia per unit mass about A3; ``h4 = l2 / 2`` is
    body 4's centre of mass on its x4 axis;
    ``(p5, q5, 0) = (l1 sin(alpha), -l / 2, 0)`` is ``r5G``, the platform's
    centre G seen from A5 in frame 5 (eq. 8). The platform's mass is
    :func:`terms.platform_mass` (a payload rides with it).
    """
    gx, gy, gz = robot.gravity
    return KernelConstants(
        robot.l3, -1.0 / robot.l3, robot.l3 / 2.0, robot.l3 ** 2 / 3.0,
        robot.m1, robot.m2, robot.m3, robot.m4, terms.platform_mass(robot),
        robot.m6, robot.l2 / 2.0, robot.l1 * math.sin(robot.alpha),
        -robot.l / 2.0, gx, gy, gz)


def build_legs(robot: Robot, **changes: Any) -> tuple[legs.Leg, ...]:
    """
    Return ``robot``'s legs (:func:`legs.build`), some rows ``changes``d.

    ``changes``: geometry rows by name (``bar_length=...``) taken instead
    of ``robot``'s values, unchecked.
    """
    def value(name):
        return changes.get(name, getattr(robot, name))
    return legs.build([value(f'axis_point_{leg}') for leg in LEGS],
                      [value(f'axis_direction_{leg}') for leg in LEGS],
                      value('joint_offset'), value('bar_length'),
                      [value(f'attachment_{leg}') for leg in LEGS])


def leg_constants(robot: Robot,
                  built: tuple[legs.Leg, ...]) -> tuple[LegConstants, ...]:
    """
    Pack each leg's values the kernel uses (``kernel.solve_legs``).

    Each leg's :class:`KernelConstants` are the robot's with its own bar
    length ``L_i`` for ``l3`` (``h3 = L_i / 2``, ``i3 = L_i^2 / 3``) and
    gravity in its frame, ``R_i^T g``; its frame row by row, ``r_i -
    a_i`` and ``e_i``.
    """
    k = kernel_constants(robot)
    out = []
    for leg in built:
        length = leg.length
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = leg.frame
        gravity = (r00 * k.gx + r10 * k.gy + r20 * k.gz,
                   r01 * k.gx + r11 * k.gy + r21 * k.gz,
                   r02 * k.gx + r12 * k.gy + r22 * k.gz)
        out.append(LegConstants(
            k._replace(l3=length, minus_inv_l3=-1.0 / length,
                       h3=length / 2.0, i3=length ** 2 / 3.0,
                       gx=gravity[0], gy=gravity[1], gz=gravity[2]),
            (r00, r01, r02, r10, r11, r12, r20, r21, r22),
            tuple(r - a for r, a in zip(leg.attachment, leg.point)),
            leg.offset))
    return tuple(out)


def _check_lengths(robot):
    """
    Refuse a bar length beyond MAX_LENGTH_DEVIATION of ``l3``.

    To 1e-12 m, so that decimal ends (0.3 and 0.4) are within.
    """
    if any(abs(length - robot.l3) > MAX_LENGTH_DEVIATION + 1e-12
           for length in robot.bar_length):
        raise _bad(ROW['bar_length'], (
            f'each component must lie within {MAX_LENGTH_DEVIATION:g} m of '
            f'robot.l3 ({robot.l3:g} m), the drawing\'s, got '
            f'{_shown(robot.bar_length)}'))


def _check_directions(robot):
    """
    Refuse an axis direction not a unit vector, tilted or parallel.

    Each ``axis_direction_*`` must have a norm within UNIT_TOLERANCE of 1,
    no other leg's direction within MAX_TILT_DEG of it (or of its
    opposite: the axes must span space) and its drawing's axis within
    MAX_TILT_DEG (:class:`ParameterError` naming the row).
    """
    seen = []
    for leg, axis in zip(LEGS, legs.DRAWING_AXES):
        name = f'axis_direction_{leg}'
        value = getattr(robot, name)
        norm = math.sqrt(sum(v * v for v in value))
        if abs(norm - 1.0) > UNIT_TOLERANCE:
            raise _bad(ROW[name], f'must be a unit vector (norm within '
                       f'{UNIT_TOLERANCE:g} of 1), got {_shown(value)} of norm '
                       f'{norm:.6g}')
        direction = legs.unit(value)
        for other, earlier in seen:
            apart = math.degrees(legs.angle(direction, earlier))
            if min(apart, 180.0 - apart) < MAX_TILT_DEG:
                raise _bad(ROW[name], (
                    f'parallel to robot.{other} ({apart:.3g} deg apart): '
                    'the three axes must span space'))
        tilt = math.degrees(legs.angle(direction, axis))
        if tilt > MAX_TILT_DEG:
            raise _bad(ROW[name], (
                f'must lie within {MAX_TILT_DEG:g} deg of the drawing\'s '
                f'axis {list(axis)}, got {_shown(value)}, {tilt:.3g} deg from it'))
        seen.append((name, direction))


def _assembly_problem(built, constants):
    """
    Why legs do not assemble at their home, or None where they do.

    Home is the platform's position at ``lambda = (0, 0, 0)`` on the home
    branch (:func:`legs.intersect`); it must stand at least the default
    singularity margin from every singularity, as every figure of the
    drawing's robot does (distance 1 there).
    """
    home, found = legs.intersect(built, ZERO)
    if not found:
        return ('the legs do not assemble: no platform position on the '
                'home branch (every alpha_i > 0) at lambda = (0, 0, 0)')
    _, ratio, conditioning, _ = legs.status(built, constants, home)
    distance = min(float(ratio.min()), float(conditioning))
    margin = legs.DEFAULT_SINGULARITY_MARGIN
    if distance < margin:
        where = ', '.join(f'{v:.6g}' for v in home)
        return (f'the legs assemble at lambda = (0, 0, 0) with the platform '
                f'at [{where}] m, too near a singularity (distance '
                f'{distance:.3g} < {margin:g})')
    return None


def _check_assembly(robot):
    """
    Refuse legs that do not assemble at home, naming the row to blame.

    A leg whose bars are shorter than the distance from its axis to its
    platform point at the drawing's home (G at the origin) is named by
    ``bar_length``; otherwise the first geometry row whose drawing's value
    would make the legs assemble, or else the first that differs.
    """
    problem = _assembly_problem(robot.legs, robot.leg_constants)
    if problem is None:
        return
    for leg in robot.legs:
        w = np.subtract(leg.attachment, leg.point)
        reach = float(np.linalg.norm(w - (w @ leg.direction) * np.asarray(
            leg.direction)))
        if reach >= leg.length:
            raise _bad(ROW['bar_length'], (
                f'leg {leg.name.upper()}\'s bars ({leg.length:g} m) are '
                f'shorter than its reach: its platform point at the '
                f'drawing\'s home is {reach:.4g} m from its axis'))
    drawing = {row.name: row.default for row in GEOMETRY_ROWS}
    drawing['bar_length'] = (robot.l3,) * 3
    differing = [name for name, value in drawing.items()
                 if getattr(robot, name) != value]
    for name in differing:
        changed = build_legs(robot, **{name: drawing[name]})
        if _assembly_problem(changed, leg_constants(robot, changed)) is None:
            raise _bad(ROW[name], f'{problem} (with the drawing\'s value '
                       'they would)')
    raise _bad(ROW[differing[0]], problem)


def _checked(row, value):
    """
    Return ``value`` checked against ``row``: a float or a 3-tuple of them.

    Raises :class:`ParameterError` (``robot.<name>``) for a value of the
    wrong kind, not finite, or beyond the row's limits.
    """
    low, high = row.limits
    within = (lambda v: low < v < high or v == row.none) if row.open \
        else (lambda v: low <= v <= high or v == row.none)
    place = f'lie in {_bounds(row)} {row.unit}' if row.none is None else \
        f'be {row.none:g} (none) or lie in {_bounds(row)} {row.unit}'
    if is_vector(row):
        try:
            values = tuple(value)
        except TypeError:
            raise _bad(row, f'must be a 3-vector, got {_shown(value)}') from None
        if len(values) != 3 or not all(_number(v) for v in values):
            raise _bad(row, f'must be a 3-vector of numbers, got {_shown(value)}')
        if not all(math.isfinite(v) for v in values):
            raise _bad(row, f'must be finite, got {_shown(value)}')
        if not all(within(v) for v in values):
            raise _bad(row, f'each component must {place}, got {_shown(value)}')
        return tuple(float(v) for v in values)
    if not _number(value):
        raise _bad(row, f'must be a number, got {_shown(value)}')
    if not math.isfinite(value):
        raise _bad(row, f'must be finite, got {_shown(value)}')
    if not within(value):
        raise _bad(row, f'must {place}, got {_shown(value)}')
    return float(value)


def _check_needs(row, values, needed):
    """
    Refuse a value on an actuator where ``row.needs`` is none (ParameterError).

    An amplitude of the screw ripple without the screw's lead: the force
    would have no period.
    """
    none = ROW[row.needs].none
    for leg, value, other in zip('ABC', values, needed):
        if value != 0.0 and other == none:
            raise _bad(row, (
                f'actuator {leg} has {value:g} {row.unit} but no '
                f'robot.{row.needs} ({none:g}: none): give its '
                f'{row.needs.replace("_", " ")} or set it to 0.0'))


def _bounds(row):
    """Return ``row``'s limits as a message writes them: ``[1e-4, 100]``."""
    ends = ', '.join('pi/2' if v == math.pi / 2 else f'{v:g}'
                     for v in row.limits)
    return f'({ends})' if row.open else f'[{ends}]'


def _shown(value):
    """
    Return ``value`` as a refusal writes it: numpy's numbers as numbers.

    ``(0.2, 0.0, 0.0)`` for a tuple of numpy floats, ``[0.0, 0.1, 0.0]``
    for an array, ``repr`` otherwise.
    """
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    if isinstance(value, (tuple, list)):
        inner = ', '.join(map(_shown, value))
        return (f'({inner}{"," if len(value) == 1 else ""})'
                if isinstance(value, tuple) else f'[{inner}]')
    return repr(value)


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _bad(row, rule):
    return ParameterError(f'robot.{row.name}', rule)
