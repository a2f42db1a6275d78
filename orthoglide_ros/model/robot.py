"""
The Orthoglide's constant description: lengths, masses, gravity, friction.

One immutable :class:`Robot` is built and validated once; every algorithm of
the package takes it as its first argument (in the manner of Pinocchio's
``Model``) and never validates it again on the hot path.

The parameter names are the paper's (section 2) and those of the
``robot.*`` ROS parameters of ``config/orthoglide.yaml``; see ``doc/model.md``
for the bodies they describe.
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass, fields
import math
from typing import Any, Tuple

from orthoglide_ros.model.kernel import kernel_constants

# The legs' suffixes, in the order of every per-actuator triple.
LEGS = ('a', 'b', 'c')
# The prismatic joints of actuators A, B, C: the default joint_names of
# every node, of the URDF and of the logs.
JOINT_NAMES = tuple(f'slider_{leg}' for leg in LEGS)
# Friction on the sliders (not in the paper, which neglects it): none by
# default, so that the paper's figures stand. The smoothing speed of the
# Coulomb term: tanh(1) = 76 % of the Coulomb force at 1 mm/s. The Stribeck
# excess falls to exp(-1) = 37 % of itself at its velocity. No drive
# inertia reflected onto the sliders, nothing on the platform.
NO_FRICTION = (0.0, 0.0, 0.0)
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)

Vector = Tuple[float, float, float]

# Bounds of every value (inclusive unless said): far beyond any
# Orthoglide, they keep every derived quantity of the kernel finite (a
# length of 1e200 m would overflow its l3^2).
LENGTH_LIMITS = (1e-4, 100.0)       # m
MASS_LIMITS = (1e-6, 1e6)           # kg
FORCE_LIMITS = (0.0, 1e6)           # N, N s/m: friction, each actuator
SPEED_LIMITS = (1e-6, 10.0)         # m/s

Row = namedtuple('Row', ('name', 'default', 'unit', 'limits', 'description',
                         'follows', 'open'), defaults=(None, False))
Row.__doc__ = """One robot parameter: the one home of its rules.

``name`` (the ``robot.*`` parameter less ``robot.``, the paper's);
``default`` (a float, or a 3-tuple for a vector; None when it
``follows`` another parameter until given); ``unit``; ``limits``
``(low, high)`` of the value or of each component, inclusive unless
``open``; ``description``, in words. The :class:`Robot`'s fields and
checks, the nodes' ``robot.*`` parameters
(:data:`orthoglide_ros.cores.parameters.ROBOT_SPECS`) and the docs' tables
(``test/test_docs.py``) all come from :data:`ROWS`."""

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
    Row('friction_viscous', NO_FRICTION, 'N s/m', FORCE_LIMITS,
        'viscous friction of the sliders A, B, C: a force c lambdadot '
        'against the motion'),
    Row('friction_coulomb', NO_FRICTION, 'N', FORCE_LIMITS,
        'Coulomb friction of the sliders A, B, C: a force F tanh(lambdadot / '
        'friction_velocity) against the motion (moving +lambda, and both '
        'ways unless friction_coulomb_negative is set)'),
    Row('friction_velocity', 0.001, 'm/s', SPEED_LIMITS,
        'slider speed that smooths the Coulomb friction (tanh(1) = 76 % of '
        'it at this speed)'),
    Row('friction_coulomb_negative', None, 'N', FORCE_LIMITS,
        'Coulomb friction of the sliders A, B, C moving -lambda; defaults to '
        'friction_coulomb', 'friction_coulomb'),
    Row('friction_stribeck', NO_FRICTION, 'N', FORCE_LIMITS,
        'Stribeck friction of the sliders A, B, C: the breakaway excess S, a '
        'force S exp(-(lambdadot / friction_stribeck_velocity)^2) '
        'tanh(lambdadot / friction_velocity) against the motion'),
    Row('friction_stribeck_velocity', 0.01, 'm/s', SPEED_LIMITS,
        'slider speed at which the Stribeck excess has fallen to exp(-1) = '
        '37 % of itself'),
    Row('armature', (0.0, 0.0, 0.0), 'kg', (0.0, 1e6),
        'inertia of the drives of A, B, C reflected onto their sliders, J (2 '
        'pi / lead)^2 for a ball screw: a force armature lambdaddot on each '
        'actuator'),
    Row('payload', 0.0, 'kg', (0.0, 1e6),
        'mass carried rigidly on the platform (a tool, a part): exactly a '
        'heavier platform'),
)
ROW = {row.name: row for row in ROWS}


def is_vector(row: 'Row') -> bool:
    """Whether ``row``'s value is a 3-vector (its own or its leader's)."""
    return isinstance(ROW[row.follows].default if row.follows
                      else row.default, tuple)


# The friction parameters that are forces (zero: a frictionless robot).
FRICTION_FORCES = ('friction_viscous', 'friction_coulomb',
                   'friction_coulomb_negative', 'friction_stribeck')


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


@dataclass(frozen=True)
class Robot:
    """
    Geometry (m, rad), masses (kg), gravity (m/s^2, frame 0), friction.

    Each field is a row of :data:`ROWS`, its default, unit, limits and
    meaning there. ``m4`` and ``m6`` default to ``m2`` and ``m3`` (the
    paper's ``m4 = m2``, ``m6 = m3``). Every value must be finite and
    within its row's limits, a vector a 3-vector; otherwise
    :class:`ParameterError` names the parameter (``robot.l3``).

    Friction on each slider (actuators A, B, C), which the paper neglects:
    ``friction_viscous`` ``c_j`` (N s/m), ``friction_coulomb`` ``F_j`` and
    ``friction_coulomb_negative`` ``F_j^-`` (N, moving +lambda and -lambda;
    the second defaults to the first), ``friction_stribeck`` ``S_j`` (N),
    3-vectors of values >= 0, and the speeds ``friction_velocity`` ``v_s``
    and ``friction_stribeck_velocity`` ``v_b`` (m/s, > 0): the actuator
    must add the force of :func:`mechanics.friction_force`. None by
    default: the paper's robot.

    The drives and what the platform carries, which the paper does not
    have either: ``armature`` (kg, a 3-vector of values >= 0), each drive's
    inertia reflected onto its slider (a motor of rotor inertia ``J`` on a
    ball screw of lead ``p``: ``J (2 pi / p)^2``), a force ``armature_j
    lambdaddot_j`` on actuator j; ``payload`` (kg, >= 0), a mass rigidly on
    the platform, which only translates: the dynamics of a platform of
    mass ``m5 + payload``. Both 0 by default.

    >>> Robot().l3
    0.85
    >>> Robot(m5=18.0).m4 == Robot().m2
    True
    """

    l: float = ROW['l'].default
    l1: float = ROW['l1'].default
    l2: float = ROW['l2'].default
    l3: float = ROW['l3'].default
    alpha: float = ROW['alpha'].default
    m1: float = ROW['m1'].default
    m2: float = ROW['m2'].default
    m3: float = ROW['m3'].default
    m4: float = ROW['m4'].default       # None given: follows m2
    m5: float = ROW['m5'].default
    m6: float = ROW['m6'].default       # None given: follows m3
    gravity: Vector = ROW['gravity'].default
    friction_viscous: Vector = ROW['friction_viscous'].default
    friction_coulomb: Vector = ROW['friction_coulomb'].default
    friction_velocity: float = ROW['friction_velocity'].default
    friction_coulomb_negative: Vector = \
        ROW['friction_coulomb_negative'].default
    friction_stribeck: Vector = ROW['friction_stribeck'].default
    friction_stribeck_velocity: float = \
        ROW['friction_stribeck_velocity'].default
    armature: Vector = ROW['armature'].default
    payload: float = ROW['payload'].default

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
        # Derived once (not fields: no part of eq or repr): the kernel's
        # constants, whether the sliders have friction at all, and whether
        # it goes beyond viscous + symmetric Coulomb (mechanics' general
        # law, else its plain one).
        object.__setattr__(self, 'constants', kernel_constants(self))
        object.__setattr__(self, 'has_friction', any(
            sum((getattr(self, n) for n in FRICTION_FORCES), ())))
        object.__setattr__(self, 'plain_friction', not any(
            self.friction_stribeck) and (self.friction_coulomb_negative
                                         == self.friction_coulomb))

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
        """Return a copy with no friction (every FRICTION_FORCES zero)."""
        return self.replace(**dict.fromkeys(FRICTION_FORCES, NO_FRICTION))


def _checked(row, value):
    """
    Return ``value`` checked against ``row``: a float or a 3-tuple of them.

    Raises :class:`ParameterError` (``robot.<name>``) for a value of the
    wrong kind, not finite, or beyond the row's limits.
    """
    low, high = row.limits
    within = (lambda v: low < v < high) if row.open \
        else (lambda v: low <= v <= high)
    ends = ', '.join('pi/2' if v == math.pi / 2 else f'{v:g}'
                     for v in (low, high))
    bounds = f'({ends})' if row.open else f'[{ends}]'
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
            raise _bad(row, f'each component must lie in {bounds} '
                       f'{row.unit}, got {value!r}')
        return tuple(float(v) for v in values)
    if not _number(value):
        raise _bad(row, f'must be a number, got {value!r}')
    if not math.isfinite(value):
        raise _bad(row, f'must be finite, got {value!r}')
    if not within(value):
        raise _bad(row, f'must lie in {bounds} {row.unit}, got {value!r}')
    return float(value)


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _bad(row, rule):
    return ParameterError(f'robot.{row.name}', rule)
