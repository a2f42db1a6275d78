"""
The Orthoglide's constant description: lengths, masses, gravity, friction.

One immutable :class:`Robot` is built and validated once; every algorithm of
the package takes it as its first argument (in the manner of Pinocchio's
``Model``) and never validates it again on the hot path.

The parameter names are the paper's (section 2) and those of the
``robot.*`` ROS parameters of ``config/orthoglide.yaml``; see ``doc/model.md``
for the bodies they describe.
"""

from dataclasses import dataclass, field, fields
import math

from orthoglide_ros.model.kernel import kernel_constants

# The paper's example robot (section 2): lengths in m, masses in kg.
PAPER_VALUES = {
    'l': 0.20, 'l1': 0.15, 'l2': 0.08, 'l3': 0.85, 'alpha': math.pi / 4,
    'm1': 0.35, 'm2': 0.2, 'm3': 2.5, 'm5': 15.0,
}
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
# The prismatic joints of actuators A, B, C: the default joint_names of
# every node, of the URDF and of the logs.
JOINT_NAMES = ('slider_a', 'slider_b', 'slider_c')
# Friction on the sliders (not in the paper, which neglects it): none by
# default, so that the paper's figures stand. The smoothing speed of the
# Coulomb term: tanh(1) = 76 % of the Coulomb force at 1 mm/s.
NO_FRICTION = (0.0, 0.0, 0.0)
DEFAULT_FRICTION_VELOCITY = 0.001   # m/s

# Units of every parameter, for messages, descriptions and the docs.
UNITS = {
    'l': 'm', 'l1': 'm', 'l2': 'm', 'l3': 'm', 'alpha': 'rad',
    'm1': 'kg', 'm2': 'kg', 'm3': 'kg', 'm4': 'kg', 'm5': 'kg', 'm6': 'kg',
    'gravity': 'm/s^2', 'friction_viscous': 'N s/m',
    'friction_coulomb': 'N', 'friction_velocity': 'm/s',
}

# Bounds of every value (inclusive): far beyond any Orthoglide, they keep
# every derived quantity of the kernel finite (a length of 1e200 m would
# overflow its l3^2). alpha lies in (0, pi/2) rad, checked apart.
LENGTH_LIMITS = (1e-4, 100.0)       # m
MASS_LIMITS = (1e-6, 1e6)           # kg
GRAVITY_LIMITS = (-100.0, 100.0)    # m/s^2, each component
VISCOUS_LIMITS = (0.0, 1e6)         # N s/m, each actuator
COULOMB_LIMITS = (0.0, 1e6)         # N, each actuator
FRICTION_VELOCITY_LIMITS = (1e-6, 10.0)     # m/s
LIMITS = {
    **dict.fromkeys(('l', 'l1', 'l2', 'l3'), LENGTH_LIMITS),
    **dict.fromkeys(('m1', 'm2', 'm3', 'm4', 'm5', 'm6'), MASS_LIMITS),
    'gravity': GRAVITY_LIMITS,
    'friction_viscous': VISCOUS_LIMITS,
    'friction_coulomb': COULOMB_LIMITS,
    'friction_velocity': FRICTION_VELOCITY_LIMITS,
}

DESCRIPTIONS = {
    'l': 'side of the cubic platform (body 5)',
    'l1': 'length of the slider rod A1A2 (body 1)',
    'l2': 'length of the rods A3A6 (body 2) and A4A7 (body 4)',
    'l3': 'length of the parallelogram bars A3A4 (body 3) and A6A7 (body 6)',
    'alpha': 'orientation angle of the slider rod about its guide-way',
    'm1': 'mass of each slider (body 1)',
    'm2': 'mass of each rod A3A6 (body 2)',
    'm3': 'mass of each bar A3A4 (body 3)',
    'm4': 'mass of each rod A4A7 (body 4); defaults to m2',
    'm5': 'mass of the platform (body 5, counted once)',
    'm6': 'mass of each bar A6A7 (body 6); defaults to m3',
    'gravity': 'gravity vector in the base frame 0',
    'friction_viscous': 'viscous friction of the sliders A, B, C: a force '
                        'c lambdadot against the motion',
    'friction_coulomb': 'Coulomb friction of the sliders A, B, C: a force '
                        'F tanh(lambdadot / friction_velocity) against the '
                        'motion',
    'friction_velocity': 'slider speed that smooths the Coulomb friction '
                         '(tanh(1) = 76 % of it at this speed)',
}


class RobotParameterError(ValueError):
    """A robot parameter breaks a rule; the message names both."""

    def __init__(self, name, rule):
        super().__init__(f'robot.{name}: {rule}')
        self.name = name
        self.rule = rule


@dataclass(frozen=True)
class Robot:
    """
    Geometry (m, rad), masses (kg), gravity (m/s^2, frame 0), friction.

    ``m4`` and ``m6`` default to ``m2`` and ``m3`` (the paper's
    ``m4 = m2``, ``m6 = m3``). Every value must be finite, lengths and
    masses positive and within :data:`LIMITS`, ``alpha`` in (0, pi/2) and
    ``gravity`` a 3-vector within :data:`GRAVITY_LIMITS`; otherwise
    :class:`RobotParameterError` names the parameter.

    Friction on each slider (actuators A, B, C), which the paper neglects:
    ``friction_viscous`` ``c_j`` (N s/m) and ``friction_coulomb`` ``F_j``
    (N), 3-vectors of values >= 0, and ``friction_velocity`` ``v_s`` (m/s,
    > 0): the actuator must add ``c_j lambdadot_j + F_j tanh(lambdadot_j /
    v_s)`` to its force (see :func:`mechanics.friction_force`). None by
    default: the paper's robot.

    >>> Robot().l3
    0.85
    >>> Robot(m5=18.0).m4 == Robot().m2
    True
    """

    l: float = PAPER_VALUES['l']
    l1: float = PAPER_VALUES['l1']
    l2: float = PAPER_VALUES['l2']
    l3: float = PAPER_VALUES['l3']
    alpha: float = PAPER_VALUES['alpha']
    m1: float = PAPER_VALUES['m1']
    m2: float = PAPER_VALUES['m2']
    m3: float = PAPER_VALUES['m3']
    m4: float = None
    m5: float = PAPER_VALUES['m5']
    m6: float = None
    gravity: tuple = field(default=DEFAULT_GRAVITY)
    friction_viscous: tuple = field(default=NO_FRICTION)
    friction_coulomb: tuple = field(default=NO_FRICTION)
    friction_velocity: float = DEFAULT_FRICTION_VELOCITY

    def __post_init__(self):
        if self.m4 is None:
            object.__setattr__(self, 'm4', self.m2)
        if self.m6 is None:
            object.__setattr__(self, 'm6', self.m3)
        for name in ('l', 'l1', 'l2', 'l3', 'alpha', 'm1', 'm2', 'm3', 'm4',
                     'm5', 'm6'):
            _check_positive(name, getattr(self, name))
        if not self.alpha < math.pi / 2:
            raise RobotParameterError('alpha', 'must lie in (0, pi/2) rad')
        for name in ('gravity', 'friction_viscous', 'friction_coulomb'):
            object.__setattr__(self, name, _check_vector(
                name, getattr(self, name)))
        _check_positive('friction_velocity', self.friction_velocity)
        # Derived once (not fields: no part of eq or repr): the kernel's
        # constants, and whether the sliders have friction at all.
        object.__setattr__(self, 'constants', kernel_constants(self))
        object.__setattr__(self, 'has_friction', any(
            self.friction_viscous + self.friction_coulomb))

    @classmethod
    def parameter_names(cls):
        """Names of the parameters, in declaration order (``robot.`` less)."""
        return tuple(f.name for f in fields(cls))

    def as_parameters(self):
        """
        Return the description as a ``{name: value}`` dict.

        Scalars as floats, vectors (gravity, friction) as lists of floats:
        the ``robot.*`` parameters' types.
        """
        return {name: list(value) if isinstance(value, tuple)
                else float(value)
                for name, value in ((name, getattr(self, name))
                                    for name in self.parameter_names())}

    def replace(self, **changes):
        """Return a validated copy with some parameters changed."""
        values = self.as_parameters()
        values.update(changes)
        return Robot(**values)


def _check_positive(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RobotParameterError(name, f'must be a number, got {value!r}')
    if not math.isfinite(value):
        raise RobotParameterError(name, f'must be finite, got {value!r}')
    if not value > 0.0:
        raise RobotParameterError(name, f'must be positive, got {value!r}')
    low, high = LIMITS.get(name, (0.0, math.inf))
    if not low <= value <= high:
        raise RobotParameterError(name, (
            f'must lie in [{low:g}, {high:g}] {UNITS[name]}, got {value!r}'))


def _check_vector(name, value):
    """Return a finite 3-vector within LIMITS[name] as floats."""
    try:
        vector = tuple(value)
    except TypeError:
        raise RobotParameterError(
            name, f'must be a 3-vector, got {value!r}') from None
    if len(vector) != 3 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool)
            for v in vector):
        raise RobotParameterError(
            name, f'must be a 3-vector of numbers, got {value!r}')
    if not all(math.isfinite(v) for v in vector):
        raise RobotParameterError(name, f'must be finite, got {value!r}')
    low, high = LIMITS[name]
    if not all(low <= v <= high for v in vector):
        raise RobotParameterError(name, (
            f'each component must lie in [{low:g}, {high:g}] '
            f'{UNITS[name]}, got {value!r}'))
    return tuple(float(v) for v in vector)
