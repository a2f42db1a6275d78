"""
Forces beyond the paper's rigid bodies: friction, the drives, a payload.

Each :class:`Term` is the one home of its law and its ``robot.*``
parameters (:class:`Row`), read by the robot, :mod:`mechanics` (``f =
f_rigid(eq. 25) + sum of the terms``), the MJCF, identification and the
docs' tables. A term's force is a function of its slider's state
(:class:`Slider`). Adding a term is one entry in :data:`TERMS`
(doc/model.md#terms).
"""

from __future__ import annotations

from typing import Any, Optional
from collections import namedtuple
import math
from types import SimpleNamespace

import numpy as np

from orthoglide_ros.model.types import Triple

# Bounds of every value (inclusive unless said): far beyond any
# Orthoglide, they keep every derived quantity of the kernel finite (a
# length of 1e200 m would overflow its l3^2).
LENGTH_LIMITS = (1e-4, 100.0)       # m
MASS_LIMITS = (1e-6, 1e6)           # kg
FORCE_LIMITS = (0.0, 1e6)           # N, N s/m: friction, each actuator
SPEED_LIMITS = (1e-6, 10.0)         # m/s
AMPLITUDE_LIMITS = (-1e6, 1e6)      # N: a sine or cosine coefficient
LEAD_LIMITS = (1e-4, 1.0)           # m: a screw's lead (0.0: no screw)
# No term by default: the paper's robot, whose figures stand.
NO_FRICTION = (0.0, 0.0, 0.0)

Row = namedtuple('Row', ('name', 'default', 'unit', 'limits', 'description',
                         'follows', 'open', 'none', 'needs'),
                 defaults=(None, False, None, None))
Row.__doc__ = """One robot parameter: the one home of its rules.

``name`` (the ``robot.*`` parameter less ``robot.``, the paper's);
``default`` (a float, or a 3-tuple for a vector; None when it
``follows`` another parameter until given); ``unit``; ``limits``
``(low, high)`` of the value or of each component, inclusive unless
``open``; ``description``, in words; ``none``: a value outside the
limits that means "none" (a screw's lead 0.0), or None; ``needs``: the
vector row that must not be ``none`` on an actuator where this one is
not zero (an amplitude needs its lead). The :class:`Robot`'s fields and
checks, the nodes' ``robot.*`` parameters and the docs' table
(doc/model.md#parameters) all come from :data:`robot.ROWS`."""

Slider = namedtuple('Slider', ('leg', 'lambda_', 'lambdadot', 'lambdaddot'))
Slider.__doc__ = """One slider's state, the argument of a term's force.

``leg``: its index (0, 1, 2 for A, B, C: its component of a vector
row); ``lambda_`` (m), ``lambdadot`` (m/s) and ``lambdaddot`` (m/s^2):
floats, or (N,) arrays of as many samples."""

Term = namedtuple('Term', ('name', 'rows', 'force', 'formula', 'mujoco',
                           'friction', 'identified', 'meaning', 'inertial',
                           'part_of'), defaults=(False, None))
Term.__doc__ = """One force beyond the rigid bodies (doc/model.md#terms).

``rows``: its ``robot.*`` parameters, the first its coefficient, one per
actuator, in which the force is linear; ``force(c, slider, robot,
ops)``: the force (N) on one actuator of coefficient ``c`` (for a term
whose coefficient follows another's, the excess over it) in the state
``slider`` (:class:`Slider`), on floats or arrays (``ops``:
:data:`FLOATS` or :data:`ARRAYS`): linear in ``lambdaddot`` and nothing
else (``inertial``: the mass matrix), or a function of ``lambda_`` and
``lambdadot`` (the forward dynamics' bias); None for a term the rigid
bodies hold (the payload, a mass); ``formula``: the docs' expression;
``mujoco``: the slide joint's MJCF attribute that holds it, or None (the
MuJoCo plant applies it as a force); ``friction``: dissipative, a
function of ``lambdadot``, none unless set (``Robot.frictionless``);
``identified``: a choice of ``orthoglide identify --friction``;
``meaning``: a coefficient's, with ``{}`` for the slider; ``part_of``:
the name of the term this one is identified with (a law holds both or
neither), or None."""

# The functions a term's force may use, on floats and on arrays.
FLOATS = SimpleNamespace(tanh=math.tanh, exp=math.exp, minimum=min,
                         sin=math.sin, cos=math.cos)
ARRAYS = SimpleNamespace(tanh=np.tanh, exp=np.exp, minimum=np.minimum,
                         sin=np.sin, cos=np.cos)

VISCOUS = Term(
    'viscous',
    (Row('friction_viscous', NO_FRICTION, 'N s/m', FORCE_LIMITS,
         'viscous friction of the sliders A, B, C: a force c lambdadot '
         'against the motion'),),
    lambda c, s, robot, ops: c * s.lambdadot,
    'c_j v', 'damping', True, True, 'viscous friction of {}')
COULOMB = Term(
    'coulomb',
    (Row('friction_coulomb', NO_FRICTION, 'N', FORCE_LIMITS,
         'Coulomb friction of the sliders A, B, C: a force F tanh(lambdadot '
         '/ friction_velocity) against the motion (moving +lambda, and both '
         'ways unless friction_coulomb_negative is set)'),
     Row('friction_velocity', 0.001, 'm/s', SPEED_LIMITS,
         'slider speed that smooths the Coulomb friction (tanh(1) = 76 % of '
         'it at this speed)')),
    lambda c, s, robot, ops: c * ops.tanh(
        s.lambdadot / robot.friction_velocity),
    'F_j tanh(v / v_s)', 'frictionloss', True, True,
    'Coulomb friction of {}')
DIRECTION = Term(
    'direction',
    (Row('friction_coulomb_negative', None, 'N', FORCE_LIMITS,
         'Coulomb friction of the sliders A, B, C moving -lambda; defaults '
         'to friction_coulomb', 'friction_coulomb'),),
    lambda c, s, robot, ops: c * ops.tanh(
        ops.minimum(s.lambdadot, 0.0) / robot.friction_velocity),
    '(F_j^- - F_j) tanh(min(v, 0) / v_s)', None, True, True,
    'Coulomb friction moving -lambda of {}')


def _stribeck(c, s, robot, ops):
    """Return the Stribeck excess on one actuator (see STRIBECK)."""
    v = s.lambdadot
    x = v / robot.friction_stribeck_velocity
    return c * ops.exp(-x * x) * ops.tanh(v / robot.friction_velocity)


STRIBECK = Term(
    'stribeck',
    (Row('friction_stribeck', NO_FRICTION, 'N', FORCE_LIMITS,
         'Stribeck friction of the sliders A, B, C: the breakaway excess S, '
         'a force S exp(-(lambdadot / friction_stribeck_velocity)^2) '
         'tanh(lambdadot / friction_velocity) against the motion'),
     Row('friction_stribeck_velocity', 0.01, 'm/s', SPEED_LIMITS,
         'slider speed at which the Stribeck excess has fallen to exp(-1) '
         '= 37 % of itself')),
    _stribeck, 'S_j exp(-(v / v_b)^2) tanh(v / v_s)', None, True, True,
    'Stribeck excess of {}')
ARMATURE = Term(
    'armature',
    (Row('armature', (0.0, 0.0, 0.0), 'kg', (0.0, 1e6),
         'inertia of the drives of A, B, C reflected onto their sliders, J '
         '(2 pi / lead)^2 for a ball screw: a force armature lambdaddot on '
         'each actuator'),),
    lambda c, s, robot, ops: c * s.lambdaddot,
    'J_j lambdaddot', 'armature', False, True,
    'drive inertia reflected onto {}', True)


def _phase(s, robot):
    """Return the screw's angle ``2 pi lambda / p`` (rad), None without one."""
    lead = robot.screw_lead[s.leg]
    return 2.0 * math.pi / lead * s.lambda_ if lead else None


def _ripple_sine(c, s, robot, ops):
    """Return the ripple's sine part on one actuator (see RIPPLE)."""
    phase = _phase(s, robot)
    return 0.0 * s.lambda_ if phase is None else c * ops.sin(phase)


def _ripple_cosine(c, s, robot, ops):
    """Return the ripple's cosine part on one actuator (see RIPPLE)."""
    phase = _phase(s, robot)
    return 0.0 * s.lambda_ if phase is None else c * ops.cos(phase)


# A ball screw's force ripple: one harmonic of its lead p, in the angle
# of the screw, which turns with the slider's position lambda (the joint
# reading, 0 at home; doc/model.md#drives-and-payload).
RIPPLE = Term(
    'ripple',
    (Row('ripple_sine', (0.0, 0.0, 0.0), 'N', AMPLITUDE_LIMITS,
         'sine coefficient of the screw ripple of the drives of A, B, C: '
         'a force s sin(2 pi lambda / screw_lead) on each actuator',
         needs='screw_lead'),
     Row('screw_lead', (0.0, 0.0, 0.0), 'm', LEAD_LIMITS,
         'lead of the ball screw driving each slider A, B, C, from the '
         'drive\'s datasheet (slider travel per screw turn); 0.0: no '
         'screw, no ripple', none=0.0)),
    _ripple_sine, 's_j sin(2 pi lambda_j / p_j)', None, False, True,
    'sine part of the screw ripple of {}')
RIPPLE_COSINE = Term(
    'ripple_cosine',
    (Row('ripple_cosine', (0.0, 0.0, 0.0), 'N', AMPLITUDE_LIMITS,
         'cosine coefficient of the screw ripple of the drives of A, B, C: '
         'a force c cos(2 pi lambda / screw_lead) on each actuator',
         needs='screw_lead'),),
    _ripple_cosine, 'c_j cos(2 pi lambda_j / p_j)', None, False, True,
    'cosine part of the screw ripple of {}', part_of='ripple')
PAYLOAD = Term(
    'payload',
    (Row('payload', 0.0, 'kg', (0.0, 1e6),
         'mass carried rigidly on the platform (a tool, a part): exactly a '
         'heavier platform'),),
    None, 'platform mass m5 + payload', None, False, False,
    'mass carried on the platform')

TERMS = (VISCOUS, COULOMB, DIRECTION, STRIBECK, ARMATURE, RIPPLE,
         RIPPLE_COSINE, PAYLOAD)
# The terms with a force of their own, and the friction among them.
FORCES = tuple(term for term in TERMS if term.force)
FRICTION = tuple(term for term in FORCES if term.friction)
# Every term's rows, by name.
_ROWS = {row.name: row for term in TERMS for row in term.rows}
# Each term whose coefficient follows another's, by name: that term.
_LEADERS = {term.name: lead for term in FORCES for lead in FORCES
            if term.rows[0].follows == lead.rows[0].name}


def acts(robot: Any, term: Term) -> tuple[bool, bool, bool]:
    """
    Return on which actuators ``term``'s force can be other than zero.

    Everywhere, but for a coefficient that ``needs`` another row (the
    ripple its lead): where that row is set (not its ``none``).
    """
    needs = term.rows[0].needs
    if needs is None:
        return (True, True, True)
    none = _ROWS[needs].none
    return tuple(value != none for value in getattr(robot, needs))


def coefficient_name(term: Term) -> str:
    """Return the ``robot.*`` name (less ``robot.``) of ``term``'s coefficient."""
    return term.rows[0].name


def leader(term: Term) -> Optional[Term]:
    """Return the term whose coefficient ``term``'s follows (None)."""
    return _LEADERS.get(term.name)


def coefficients(robot: Any, term: Term) -> Triple:
    """
    Return the coefficients ``term``'s force takes, per actuator.

    Its row's values; for a term that follows another's (``direction``),
    their excess over the leader's: zero while it follows.
    """
    values = getattr(robot, term.rows[0].name)
    lead = leader(term)
    if lead is None:
        return values
    return tuple(v - w for v, w in zip(values, getattr(
        robot, lead.rows[0].name)))


def active(robot: Any) -> tuple[Term, ...]:
    """Return the terms with a force whose coefficients ``robot`` sets."""
    return tuple(term for term in FORCES if any(coefficients(robot, term)))


def platform_mass(robot: Any) -> float:
    """Return the platform's mass with its payload, ``m5 + payload`` (kg)."""
    return robot.m5 + robot.payload


def rigid(robot: Any) -> Any:
    """Return ``robot`` without any term: the paper's rigid bodies."""
    return robot.replace(**{term.rows[0].name: term.rows[0].default
                            for term in TERMS})


def forces(robot: Any, terms: tuple[Term, ...], lambda_: Any, lambdadot: Any,
           lambdaddot: Any, ops: SimpleNamespace) -> Triple:
    """
    Sum the force (N) of each of ``terms`` on the actuators A, B, C.

    ``lambda_`` (m), ``lambdadot`` (m/s) and ``lambdaddot`` (m/s^2):
    3-sequences of floats (``ops`` :data:`FLOATS`) or of (N,) arrays
    (:data:`ARRAYS`), the sliders' states (:class:`Slider`).
    """
    pa, pb, pc = lambda_
    va, vb, vc = lambdadot
    aa, ab, ac = lambdaddot
    # (Slider(...) through tuple.__new__: half the cost, the hot path.)
    new = tuple.__new__
    sa, sb, sc = (new(Slider, (0, pa, va, aa)), new(Slider, (1, pb, vb, ab)),
                  new(Slider, (2, pc, vc, ac)))
    fa = fb = fc = 0.0
    for term in terms:
        ca, cb, cc = getattr(robot, term.rows[0].name)
        lead = _LEADERS.get(term.name)
        if lead is not None:     # (coefficients(), inline: the hot path)
            la, lb, lc = getattr(robot, lead.rows[0].name)
            ca, cb, cc = ca - la, cb - lb, cc - lc
        force = term.force
        fa = fa + force(ca, sa, robot, ops)
        fb = fb + force(cb, sb, robot, ops)
        fc = fc + force(cc, sc, robot, ops)
    return fa, fb, fc


def inertial(robot: Any) -> Any:
    """
    Return ``robot`` as its mass matrix sees it: no gravity, no bias term.

    Only the :attr:`Term.inertial` terms (the drives) keep their
    coefficients: the inverse dynamics of this robot at zero velocity is
    ``M`` applied to the acceleration (the forward dynamics' columns).
    """
    return robot.replace(gravity=(0.0, 0.0, 0.0), **{
        coefficient_name(term): (0.0, 0.0, 0.0)
        for term in FORCES if not term.inertial})


def coefficient(robot: Any, term: Term, held: tuple[Term, ...]) -> Triple:
    """
    Return ``term``'s coefficient in a model that holds only ``held``.

    Its own; with the terms that follow it left out, the mean of theirs
    and its own: one Coulomb level, the mean of both directions'.
    """
    values = [getattr(robot, coefficient_name(t)) for t in FORCES
              if t is term or (leader(t) is term and t not in held)]
    return tuple(sum(v) / len(values) for v in zip(*values))


def reduced(robot: Any, held: tuple[Term, ...],
            given: Optional[dict[Term, Triple]] = None) -> Any:
    """
    Return ``robot`` as a model that holds only the terms ``held``.

    Each held term takes its coefficient of ``given`` (default
    :func:`coefficient`), a follower left out its leader's, friction left
    out none; other terms (the drives) keep ``robot``'s.
    """
    given = given or {term: coefficient(robot, term, held)
                      for term in held if term.force}
    changes = {}
    for term in FORCES:
        source = term if term in held else leader(term)
        if source in held:
            changes[coefficient_name(term)] = given[source]
        elif term.friction:
            changes[coefficient_name(term)] = NO_FRICTION
    return robot.replace(**changes)
