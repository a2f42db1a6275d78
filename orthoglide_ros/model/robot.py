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
# Coulomb term: tanh(1) = 76 % of the Coulomb force at 1 mm/s. The Stribeck
# excess falls to exp(-1) = 37 % of itself at its velocity.
NO_FRICTION = (0.0, 0.0, 0.0)
DEFAULT_FRICTION_VELOCITY = 0.001   # m/s
DEFAULT_STRIBECK_VELOCITY = 0.01    # m/s
# No drive inertia reflected onto the sliders, nothing on the platform:
# the paper's robot.
NO_ARMATURE = (0.0, 0.0, 0.0)
NO_PAYLOAD = 0.0
# Parameters that take another's value when not given (the paper's m4 = m2,
# m6 = m3; a Coulomb friction the same in both directions).
FOLLOWS = {'m4': 'm2', 'm6': 'm3',
           'friction_coulomb_negative': 'friction_coulomb'}
# The friction parameters that are forces (zero: a frictionless robot).
FRICTION_FORCES = ('friction_viscous', 'friction_coulomb',
                   'friction_coulomb_negative', 'friction_stribeck')

# Units of every parameter, for messages, descriptions and the docs.
UNITS = {
    'l': 'm', 'l1': 'm', 'l2': 'm', 'l3': 'm', 'alpha': 'rad',
    'm1': 'kg', 'm2': 'kg', 'm3': 'kg', 'm4': 'kg', 'm5': 'kg', 'm6': 'kg',
    'gravity': 'm/s^2', 'friction_viscous': 'N s/m',
    'friction_coulomb': 'N', 'friction_coulomb_negative': 'N',
    'friction_stribeck': 'N', 'friction_velocity': 'm/s',
    'friction_stribeck_velocity': 'm/s', 'armature': 'kg', 'payload': 'kg',
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
ARMATURE_LIMITS = (0.0, 1e6)        # kg, each actuator
PAYLOAD_LIMITS = (0.0, 1e6)         # kg
LIMITS = {
    **dict.fromkeys(('l', 'l1', 'l2', 'l3'), LENGTH_LIMITS),
    **dict.fromkeys(('m1', 'm2', 'm3', 'm4', 'm5', 'm6'), MASS_LIMITS),
    'gravity': GRAVITY_LIMITS,
    'friction_viscous': VISCOUS_LIMITS,
    'friction_coulomb': COULOMB_LIMITS,
    'friction_coulomb_negative': COULOMB_LIMITS,
    'friction_stribeck': COULOMB_LIMITS,
    'friction_velocity': FRICTION_VELOCITY_LIMITS,
    'friction_stribeck_velocity': FRICTION_VELOCITY_LIMITS,
    'armature': ARMATURE_LIMITS,
    'payload': PAYLOAD_LIMITS,
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
                        'motion (moving +lambda, and both ways unless '
                        'friction_coulomb_negative is set)',
    'friction_coulomb_negative': 'Coulomb friction of the sliders A, B, C '
                                 'moving -lambda; defaults to '
                                 'friction_coulomb',
    'friction_stribeck': 'Stribeck friction of the sliders A, B, C: the '
                         'breakaway excess S, a force S exp(-(lambdadot / '
                         'friction_stribeck_velocity)^2) tanh(lambdadot / '
                         'friction_velocity) against the motion',
    'friction_velocity': 'slider speed that smooths the Coulomb friction '
                         '(tanh(1) = 76 % of it at this speed)',
    'friction_stribeck_velocity': 'slider speed at which the Stribeck '
                                  'excess has fallen to exp(-1) = 37 % of '
                                  'itself',
    'armature': 'inertia of the drives of A, B, C reflected onto their '
                'sliders, J (2 pi / lead)^2 for a ball screw: a force '
                'armature lambdaddot on each actuator',
    'payload': 'mass carried rigidly on the platform (a tool, a part): '
               'exactly a heavier platform',
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
    friction_coulomb_negative: tuple = None
    friction_stribeck: tuple = field(default=NO_FRICTION)
    friction_stribeck_velocity: float = DEFAULT_STRIBECK_VELOCITY
    armature: tuple = field(default=NO_ARMATURE)
    payload: float = NO_PAYLOAD

    def __post_init__(self):
        # (Not a field: no part of eq or repr.)
        object.__setattr__(self, 'following', frozenset(
            name for name in FOLLOWS if getattr(self, name) is None))
        for name in self.following:
            object.__setattr__(self, name, getattr(self, FOLLOWS[name]))
        for name in ('l', 'l1', 'l2', 'l3', 'alpha', 'm1', 'm2', 'm3', 'm4',
                     'm5', 'm6'):
            _check_positive(name, getattr(self, name))
        if not self.alpha < math.pi / 2:
            raise RobotParameterError('alpha', 'must lie in (0, pi/2) rad')
        for name in ('gravity', 'armature') + FRICTION_FORCES:
            object.__setattr__(self, name, _check_vector(
                name, getattr(self, name)))
        object.__setattr__(self, 'payload', _check_nonnegative(
            'payload', self.payload))
        _check_positive('friction_velocity', self.friction_velocity)
        _check_positive('friction_stribeck_velocity',
                        self.friction_stribeck_velocity)
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
        """
        Return a validated copy with some parameters changed.

        A parameter of :data:`FOLLOWS` that was not given (``following``)
        keeps following: ``Robot().replace(friction_coulomb=(5.0, 3.0,
        4.0))`` has the same Coulomb friction both ways,
        ``Robot().replace(m2=0.3).m4`` is 0.3.
        """
        values = self.as_parameters()
        for name in self.following:
            del values[name]
        values.update(changes)
        return Robot(**values)

    def frictionless(self):
        """Return a copy with no friction (every FRICTION_FORCES zero)."""
        return self.replace(**dict.fromkeys(FRICTION_FORCES, NO_FRICTION))


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


def _check_nonnegative(name, value):
    """Return a finite number within LIMITS[name] (>= 0) as a float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RobotParameterError(name, f'must be a number, got {value!r}')
    low, high = LIMITS[name]
    if not (math.isfinite(value) and low <= value <= high):
        raise RobotParameterError(name, (
            f'must lie in [{low:g}, {high:g}] {UNITS[name]}, got {value!r}'))
    return float(value)


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
