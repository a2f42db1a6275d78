"""
The Orthoglide's constant description: lengths, masses, gravity, terms.

One immutable :class:`Robot`, validated once, is every algorithm's first
argument (as Pinocchio's ``Model``) and never validated again on the hot
path; its fields are :data:`ROWS` (doc/model.md#parameters).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
import math
from typing import Any, Tuple

from orthoglide_ros.model import terms
from orthoglide_ros.model.kernel import KernelConstants
from orthoglide_ros.model.terms import (  # noqa: F401 (the rows' names)
    FORCE_LIMITS, LENGTH_LIMITS, MASS_LIMITS, NO_FRICTION, Row,
    SPEED_LIMITS)

# The legs' suffixes, in the order of every per-actuator triple.
LEGS = ('a', 'b', 'c')
# The prismatic joints of actuators A, B, C: the default joint_names of
# every node, of the URDF and of the logs.
JOINT_NAMES = tuple(f'slider_{leg}' for leg in LEGS)
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)

Vector = Tuple[float, float, float]

# The paper's parameters (section 2), then every term's.
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
) + tuple(row for term in terms.TERMS for row in term.rows)
ROW = {row.name: row for row in ROWS}
# The rows that need another's value on an actuator (Row.needs).
NEEDING = tuple(row for row in ROWS if row.needs)


def is_vector(row: 'Row') -> bool:
    """Whether ``row``'s value is a 3-vector (its own or its leader's)."""
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
    ``friction_coulomb_negative`` ``friction_coulomb``) takes its value
    until given. Every value must be finite and within its row's limits, a
    vector a 3-vector; otherwise :class:`ParameterError` names the
    parameter (``robot.l3``). By default no term: the paper's robot.

    >>> Robot().l3
    0.85
    >>> Robot(m5=18.0).m4 == Robot().m2
    True
    """

    def __post_init__(self):
        # (Not a field: no part of eq or repr.)
        object.__setattr__(self, 'following', frozenset(
            row.name for row in ROWS
            if row.follows and getattr(self, row.name) is None))
        for name in self.following:
            object.__setattr__(self, name, getattr(self, ROW[name].follows))
        for row in ROWS:
            object.__setattr__(self, row.name, _checked(
                row, getattr(self, row.name)))
        for row in NEEDING:
            _check_needs(row, getattr(self, row.name),
                         getattr(self, row.needs))
        # Derived once (not fields: no part of eq or repr): the kernel's
        # constants, the terms whose force the robot has, and whether
        # friction is among them.
        object.__setattr__(self, 'constants', kernel_constants(self))
        object.__setattr__(self, 'active_terms', terms.active(self))
        object.__setattr__(self, 'has_friction', any(
            term.friction for term in self.active_terms))

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


def _checked(row, value):
    """
    Return ``value`` checked against ``row``: a float or a 3-tuple of them.

    Raises :class:`ParameterError` (``robot.<name>``) for a value of the
    wrong kind, not finite, or beyond the row's limits.
    """
    low, high = row.limits
    within = (lambda v: low < v < high or v == row.none) if row.open \
        else (lambda v: low <= v <= high or v == row.none)
    ends = ', '.join('pi/2' if v == math.pi / 2 else f'{v:g}'
                     for v in (low, high))
    bounds = f'({ends})' if row.open else f'[{ends}]'
    place = f'lie in {bounds} {row.unit}' if row.none is None else \
        f'be {row.none:g} (none) or lie in {bounds} {row.unit}'
    if is_vector(row):
        try:
            values = tuple(value)
        except TypeError:
            raise _bad(row, f'must be a 3-vector, got {value!r}') from None
        if len(values) != 3 or not all(_number(v) for v in values):
            raise _bad(row, f'must be a 3-vector of numbers, got {value!r}')
        if not all(math.isfinite(v) for v in values):
            raise _bad(row, f'must be finite, got {value!r}')
        if not all(within(v) for v in values):
            raise _bad(row, f'each component must {place}, got {value!r}')
        return tuple(float(v) for v in values)
    if not _number(value):
        raise _bad(row, f'must be a number, got {value!r}')
    if not math.isfinite(value):
        raise _bad(row, f'must be finite, got {value!r}')
    if not within(value):
        raise _bad(row, f'must {place}, got {value!r}')
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


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _bad(row, rule):
    return ParameterError(f'robot.{row.name}', rule)
