"""
Forces beyond the paper's rigid bodies: friction, the drives, a payload.

Each :class:`Term` is the one home of its law and its ``robot.*``
parameters (:class:`Row`), read by the robot, :mod:`mechanics` (``f =
f_rigid(eq. 25) + sum of the terms``), the MJCF, identification and the
docs' tables. Adding a term is one entry in :data:`TERMS`
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
# No term by default: the paper's robot, whose figures stand.
NO_FRICTION = (0.0, 0.0, 0.0)

Row = namedtuple('Row', ('name', 'default', 'unit', 'limits', 'description',
                         'follows', 'open'), defaults=(None, False))
Row.__doc__ = """One robot parameter: the one home of its rules.

``name`` (the ``robot.*`` parameter less ``robot.``, the paper's);
``default`` (a float, or a 3-tuple for a vector; None when it
``follows`` another parameter until given); ``unit``; ``limits``
``(low, high)`` of the value or of each component, inclusive unless
``open``; ``description``, in words. The :class:`Robot`'s fields and
checks, the nodes' ``robot.*`` parameters and the docs' table
(doc/model.md#parameters) all come from :data:`robot.ROWS`."""

Term = namedtuple('Term', ('name', 'rows', 'force', 'formula', 'mujoco',
                           'friction', 'identified', 'meaning'))
Term.__doc__ = """One force beyond the rigid bodies (doc/model.md#terms).

``rows``: its ``robot.*`` parameters, the first its coefficient, one per
actuator, in which the force is linear; ``force(c, v, a, robot, ops)``:
the force (N) on one actuator of coefficient ``c`` (for a term whose
coefficient follows another's, the excess over it) at its slider's rate
``v`` (m/s) and acceleration ``a`` (m/s^2), on floats or arrays (``ops``:
:data:`FLOATS` or :data:`ARRAYS`), a function of ``v`` (friction: the
forward dynamics' bias) or linear in ``a`` (the mass matrix); None for a
term the rigid bodies hold (the payload, a mass); ``formula``: the docs'
expression; ``mujoco``: the slide joint's MJCF attribute that holds it, or
None (the MuJoCo plant applies it as a force); ``friction``: dissipative,
none unless set (``Robot.frictionless``); ``identified``: a choice of
``orthoglide identify --friction``; ``meaning``: a coefficient's, with
``{}`` for the slider."""

# The functions a term's force may use, on floats and on arrays.
FLOATS = SimpleNamespace(tanh=math.tanh, exp=math.exp, minimum=min)
ARRAYS = SimpleNamespace(tanh=np.tanh, exp=np.exp, minimum=np.minimum)

VISCOUS = Term(
    'viscous',
    (Row('friction_viscous', NO_FRICTION, 'N s/m', FORCE_LIMITS,
         'viscous friction of the sliders A, B, C: a force c lambdadot '
         'against the motion'),),
    lambda c, v, a, robot, ops: c * v,
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
    lambda c, v, a, robot, ops: c * ops.tanh(v / robot.friction_velocity),
    'F_j tanh(v / v_s)', 'frictionloss', True, True,
    'Coulomb friction of {}')
DIRECTION = Term(
    'direction',
    (Row('friction_coulomb_negative', None, 'N', FORCE_LIMITS,
         'Coulomb friction of the sliders A, B, C moving -lambda; defaults '
         'to friction_coulomb', 'friction_coulomb'),),
    lambda c, v, a, robot, ops: c * ops.tanh(
        ops.minimum(v, 0.0) / robot.friction_velocity),
    '(F_j^- - F_j) tanh(min(v, 0) / v_s)', None, True, True,
    'Coulomb friction moving -lambda of {}')


def _stribeck(c, v, a, robot, ops):
    """Return the Stribeck excess on one actuator (see STRIBECK)."""
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
    lambda c, v, a, robot, ops: c * a,
    'J_j lambdaddot', 'armature', False, True,
    'drive inertia reflected onto {}')
PAYLOAD = Term(
    'payload',
    (Row('payload', 0.0, 'kg', (0.0, 1e6),
         'mass carried rigidly on the platform (a tool, a part): exactly a '
         'heavier platform'),),
    None, 'platform mass m5 + payload', None, False, False,
    'mass carried on the platform')

TERMS = (VISCOUS, COULOMB, DIRECTION, STRIBECK, ARMATURE, PAYLOAD)
# The terms with a force of their own, and the friction among them.
FORCES = tuple(term for term in TERMS if term.force)
FRICTION = tuple(term for term in FORCES if term.friction)
# Each term whose coefficient follows another's, by name: that term.
_LEADERS = {term.name: lead for term in FORCES for lead in FORCES
            if term.rows[0].follows == lead.rows[0].name}


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


def forces(robot: Any, terms: tuple[Term, ...], lambdadot: Any,
           lambdaddot: Any, ops: SimpleNamespace) -> Triple:
    """
    Sum the force (N) of each of ``terms`` on the actuators A, B, C.

    ``lambdadot`` (m/s) and ``lambdaddot`` (m/s^2): 3-sequences of floats
    (``ops`` :data:`FLOATS`) or of (N,) arrays (:data:`ARRAYS`).
    """
    va, vb, vc = lambdadot
    aa, ab, ac = lambdaddot
    fa = fb = fc = 0.0
    for term in terms:
        ca, cb, cc = getattr(robot, term.rows[0].name)
        lead = _LEADERS.get(term.name)
        if lead is not None:     # (coefficients(), inline: the hot path)
            la, lb, lc = getattr(robot, lead.rows[0].name)
            ca, cb, cc = ca - la, cb - lb, cc - lc
        force = term.force
        fa = fa + force(ca, va, aa, robot, ops)
        fb = fb + force(cb, vb, ab, robot, ops)
        fc = fc + force(cc, vc, ac, robot, ops)
    return fa, fb, fc


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
