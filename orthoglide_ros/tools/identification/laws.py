"""
The parameters identification finds: masses, drives and friction, by law.

A :class:`Law` says which terms the forces hold beyond the rigid masses,
viscous and Coulomb friction: a Coulomb level per direction, a Stribeck
excess, the drives' armature. Its standard parameters ``theta``
(:func:`standard_names`: ``m1`` ... ``m6``, ``armature_a`` ...,
``viscous_a`` ..., ``coulomb_a`` ...) are what the forces are linear in;
:func:`standard_parameters` reads them off a :class:`Robot`,
:func:`with_parameters` writes them back, and :func:`friction_columns`
gives their friction columns (the law of
:func:`mechanics.friction_force` with one coefficient 1).
"""

from __future__ import annotations

from typing import Any, Optional, TYPE_CHECKING
from collections import namedtuple

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import LEGS, ROW
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

MASSES = ('m1', 'm2', 'm3', 'm4', 'm5', 'm6')
# The drives' reflected inertia (kg), one per actuator: robot.armature.
ARMATURES = tuple(f'armature_{leg}' for leg in LEGS)
# The friction coefficients by kind: the Robot field each sets, its meaning.
FRICTION_KINDS = {
    'viscous': ('friction_viscous', 'viscous friction'),
    'coulomb': ('friction_coulomb', 'Coulomb friction'),
    'coulomb_negative': ('friction_coulomb_negative',
                         'Coulomb friction moving -lambda'),
    'stribeck': ('friction_stribeck', 'Stribeck excess'),
}

Law = namedtuple('Law', ('direction', 'stribeck', 'armature'),
                 defaults=(False,))
Law.__doc__ = """The terms to identify beyond masses, viscous and Coulomb
friction: a Coulomb level per direction (``direction``), a Stribeck excess
(``stribeck``), the drives' armature (``armature``). Named by
:func:`law_name`, read by :func:`parse_law`."""
PLAIN = Law(False, False, False)
# Every law identify chooses from, the simplest first.
LAWS = tuple(sorted((Law(d, s, a) for d in (False, True)
                     for s in (False, True) for a in (False, True)),
                    key=lambda law: (sum(law), law.armature, law.stribeck)))


def law_name(law: 'Law') -> str:
    """Name a :class:`Law`: ``coulomb``, ``coulomb+direction``, ..."""
    return 'coulomb' + '+direction' * law.direction \
        + '+stribeck' * law.stribeck + '+armature' * law.armature


def parse_law(text: str) -> 'Law':
    """Return the :class:`Law` named ``text`` (ValueError if none is)."""
    for law in LAWS:
        if law_name(law) == text:
            return law
    raise ValueError(f'unknown law {text!r}: one of '
                     + ', '.join(law_name(law) for law in LAWS))


def friction_kinds(law: 'Law') -> tuple[str, ...]:
    """Return the friction coefficients' kinds of ``law``, in order."""
    return ('viscous', 'coulomb') + ('coulomb_negative',) * law.direction \
        + ('stribeck',) * law.stribeck


def standard_names(law: 'Law' = PLAIN) -> tuple[str, ...]:
    """Return the standard parameters' names of ``law`` (``m1``, ...)."""
    return MASSES + ARMATURES * law.armature + tuple(
        f'{kind}_{leg}' for kind in friction_kinds(law) for leg in LEGS)


# The standard parameters of the plain law.
STANDARD = standard_names(PLAIN)
# Each standard parameter's unit, its Robot field's.
UNITS = {m: ROW[m].unit for m in MASSES} | dict.fromkeys(
    ARMATURES, ROW['armature'].unit) | {
    f'{kind}_{leg}': ROW[field].unit
    for kind, (field, _) in FRICTION_KINDS.items() for leg in LEGS}
# What each standard parameter is, in words (the masses' from the robot's
# parameter descriptions).
MEANINGS = {m: ROW[m].description.split(';')[0] for m in MASSES} | {
    f'armature_{leg}': f'drive inertia reflected onto slider {leg.upper()}'
    for leg in LEGS} | {
    f'{kind}_{leg}': f'{words} of slider {leg.upper()}'
    for kind, (_, words) in FRICTION_KINDS.items() for leg in LEGS}
# Lowest value of each standard parameter (a Robot's bound).
LOWER = dict.fromkeys(MASSES, ROW['m1'].limits[0]) | dict.fromkeys(
    ARMATURES, ROW['armature'].limits[0]) | {
    f'{kind}_{leg}': ROW[field].limits[0]
    for kind, (field, _) in FRICTION_KINDS.items() for leg in LEGS}


def standard_parameters(robot: Robot, law: 'Law' = PLAIN) -> Array:
    """
    Return ``theta`` of ``robot``: its values of :func:`standard_names`.

    Without the ``direction`` term, the Coulomb coefficient is the mean of
    the robot's two levels; without ``stribeck`` or ``armature`` those
    terms are left out.
    """
    coulomb = robot.friction_coulomb if law.direction else tuple(
        0.5 * (f + g) for f, g in zip(robot.friction_coulomb,
                                      robot.friction_coulomb_negative))
    values = [getattr(robot, m) for m in MASSES]
    if law.armature:
        values += robot.armature
    values += list(robot.friction_viscous) + list(coulomb)
    if law.direction:
        values += robot.friction_coulomb_negative
    if law.stribeck:
        values += robot.friction_stribeck
    return np.array(values, dtype=float)


def with_parameters(robot: Robot, theta: Array, law: 'Law' = PLAIN,
                    stribeck_velocity: Optional[float] = None) -> Robot:
    """
    Return ``robot`` with the standard parameters ``theta`` of ``law``.

    Validated. Without the ``direction`` term both Coulomb levels take the
    Coulomb coefficient; without ``stribeck`` there is no Stribeck term;
    without ``armature`` the drives keep ``robot``'s; ``stribeck_velocity``
    (m/s), if given, sets its speed.
    """
    values = dict(zip(standard_names(law), (float(v) for v in theta)))
    changes: dict[str, Any] = {m: values[m] for m in MASSES}
    if law.armature:
        changes['armature'] = tuple(values[a] for a in ARMATURES)
    for kind in ('viscous', 'coulomb', 'coulomb_negative', 'stribeck'):
        source = kind if kind in friction_kinds(law) else (
            'coulomb' if kind == 'coulomb_negative' else None)
        changes[FRICTION_KINDS[kind][0]] = tuple(
            values[f'{source}_{leg}'] if source else 0.0 for leg in LEGS)
    if stribeck_velocity is not None:
        changes['friction_stribeck_velocity'] = float(stribeck_velocity)
    return robot.replace(**changes)


def friction_columns(robot: Robot, lambdadot: Array,
                     law: 'Law' = PLAIN) -> Array:
    """
    Return the friction part of ``W`` (N, 3, k) at slider speeds (m/s).

    One column per friction coefficient of ``law``: the force of
    :func:`mechanics.friction_force` for ``robot`` without friction but
    that coefficient 1 (``friction_velocity`` and
    ``friction_stribeck_velocity`` are ``robot``'s). Without the
    ``direction`` term a Coulomb coefficient acts both ways.
    """
    return np.concatenate([kind_columns(robot, lambdadot, kind,
                                        law.direction)
                           for kind in friction_kinds(law)], axis=2)


def kind_columns(robot: Robot, lambdadot: Array, kind: str,
                 direction: bool) -> Array:
    """Return the columns (N, 3, 3) of ``kind``'s three coefficients."""
    bare = robot.frictionless()
    out = np.empty(lambdadot.shape + (3,))
    for j in range(3):
        one = tuple(float(j == i) for i in range(3))
        unit = {FRICTION_KINDS[kind][0]: one}
        if kind == 'coulomb' and not direction:
            unit['friction_coulomb_negative'] = one
        out[:, :, j] = mechanics.friction_force(bare.replace(**unit),
                                                lambdadot)
    return out
