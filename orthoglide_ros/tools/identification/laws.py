"""
The parameters identification finds: masses, drives and friction, by law.

A :class:`Law` is a choice of the terms of :mod:`model.terms`; the forces
are linear in its standard parameters (the masses of eq. 20-24, then each
term's coefficient per slider): ``f = W theta``
(doc/identification.md#friction-laws-chosen-by-the-data).
"""

from __future__ import annotations

from typing import Any, Optional, TYPE_CHECKING
from itertools import combinations

import numpy as np

from orthoglide_ros.model import terms
from orthoglide_ros.model.robot import LEGS, ROW
from orthoglide_ros.model.terms import ARRAYS, COULOMB, VISCOUS
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot
    from orthoglide_ros.model.terms import Term

MASSES = ('m1', 'm2', 'm3', 'm4', 'm5', 'm6')


class Law(tuple):
    """
    The terms a law identifies, in :data:`terms.TERMS`' order.

    Named by :attr:`name` (``coulomb+direction+stribeck+armature``: the
    plain law, then the other terms'), read by :func:`parse_law`. A term
    comes with those that are ``part_of`` it (the ripple's cosine part
    with its sine part), which its name stands for.
    """

    def __new__(cls, members):
        """Hold ``members`` (terms) and their parts, in TERMS' order."""
        names = {t.name for t in members}
        return super().__new__(cls, (t for t in terms.TERMS
                                     if t.name in names or t.part_of in names))

    @property
    def name(self) -> str:
        """Return ``coulomb``, ``coulomb+direction``, ..."""
        return '+'.join(['coulomb'] + [
            term.name for term in self
            if term not in PLAIN and term.part_of is None])

    def __repr__(self) -> str:
        """Show the law by its name."""
        return f'Law({self.name!r})'

    def columns_order(self) -> tuple[Term, ...]:
        """Return the terms in the order of ``theta``: drives, friction."""
        return tuple(sorted(self, key=lambda term: term.friction))


# Viscous and Coulomb friction, every law's; the terms a law may add
# (each with its parts).
PLAIN = Law((VISCOUS, COULOMB))
OPTIONAL = tuple(t for t in terms.FORCES if t.identified and t not in PLAIN
                 and t.part_of is None)
# Every law identify chooses from: the fewest terms first, and among as
# many, the later terms of OPTIONAL last.
LAWS = tuple(sorted(
    (Law(PLAIN + chosen) for count in range(len(OPTIONAL) + 1)
     for chosen in combinations(OPTIONAL, count)),
    key=lambda law: (len(law), [t in law for t in reversed(OPTIONAL)])))


def law_name(law: Law) -> str:
    """Name a :class:`Law`: ``coulomb``, ``coulomb+direction``, ..."""
    return law.name


def parse_law(text: str) -> Law:
    """Return the :class:`Law` named ``text`` (ValueError if none is)."""
    for law in LAWS:
        if law.name == text:
            return law
    raise ValueError(f'unknown law {text!r}: one of '
                     + ', '.join(law.name for law in LAWS))


def parameter(term: Term, leg: str) -> str:
    """Return a standard parameter's name: ``coulomb_negative_a``."""
    return f'{terms.coefficient_name(term).removeprefix("friction_")}_{leg}'


def standard_names(law: Law = PLAIN) -> tuple[str, ...]:
    """Return the standard parameters' names of ``law`` (``m1``, ...)."""
    return MASSES + tuple(parameter(term, leg)
                          for term in law.columns_order() for leg in LEGS)


# The standard parameters of the plain law.
STANDARD = standard_names(PLAIN)
# Each standard parameter's unit, meaning in words and lowest value: its
# robot.* row's (the masses' meaning from the row's description).
_IDENTIFIED = tuple(t for t in terms.FORCES if t.identified)
_ROWS = {m: ROW[m] for m in MASSES} | {
    parameter(term, leg): term.rows[0]
    for term in _IDENTIFIED for leg in LEGS}
UNITS = {name: row.unit for name, row in _ROWS.items()}
MEANINGS = {m: ROW[m].description.split(';')[0] for m in MASSES} | {
    parameter(term, leg): term.meaning.format(f'slider {leg.upper()}')
    for term in _IDENTIFIED for leg in LEGS}
LOWER = {name: row.limits[0] for name, row in _ROWS.items()}


def standard_parameters(robot: Robot, law: Law = PLAIN) -> Array:
    """
    Return ``theta`` of ``robot``: its values of :func:`standard_names`.

    Each term's coefficient as a model of ``law`` has it
    (:func:`terms.coefficient`: without ``direction``, the mean of the
    robot's two Coulomb levels); terms outside ``law`` are left out.
    """
    values = [getattr(robot, m) for m in MASSES]
    for term in law.columns_order():
        values += terms.coefficient(robot, term, law)
    return np.array(values, dtype=float)


def with_parameters(robot: Robot, theta: Array, law: Law = PLAIN,
                    stribeck_velocity: Optional[float] = None) -> Robot:
    """
    Return ``robot`` with the standard parameters ``theta`` of ``law``.

    Validated. Outside ``law``, as :func:`terms.reduced` says: both
    Coulomb levels take the Coulomb coefficient, no other friction, the
    drives keep ``robot``'s; ``stribeck_velocity`` (m/s), if given, sets
    the Stribeck term's speed.
    """
    values = dict(zip(standard_names(law), (float(v) for v in theta)))
    changes: dict[str, Any] = {m: values[m] for m in MASSES}
    if stribeck_velocity is not None:
        changes['friction_stribeck_velocity'] = float(stribeck_velocity)
    given = {term: tuple(values[parameter(term, leg)] for leg in LEGS)
             for term in law}
    return terms.reduced(robot.replace(**changes), law, given)


def acting(term: Term, law: tuple[Term, ...]) -> tuple[Term, ...]:
    """
    Return the terms of ``law`` that ``term``'s coefficient acts through.

    ``term`` and those whose coefficient follows it (``direction``, the
    excess over ``coulomb``'s level, acts with it: -1 times).
    """
    return tuple(t for t in law if t is term or terms.leader(t) is term)


def columns(robot: Robot, term: Term, law: tuple[Term, ...], lambda_: Array,
            lambdadot: Array, lambdaddot: Array) -> Array:
    """
    Return ``term``'s own columns of ``W`` in ``law`` (N, 3): per actuator.

    The forces of ``law``'s terms with ``term``'s coefficient 1 and the
    others' 0 (a follower's excess over it then -1: :func:`acting`), at
    the sliders' positions ``lambda_`` (m), rates ``lambdadot`` (m/s) and
    accelerations ``lambdaddot`` (m/s^2), (N, 3) arrays; the column of
    slider j's coefficient is zero on the other actuators (and where the
    term cannot act: the ripple without a lead).
    """
    out = np.zeros(lambdadot.shape)
    for t in acting(term, law):
        for j in range(3):
            out[:, j] += (1.0 if t is term else -1.0) * t.force(
                1.0, terms.Slider(j, lambda_[:, j], lambdadot[:, j],
                                  lambdaddot[:, j]), robot, ARRAYS)
    return out


def term_columns(robot: Robot, lambda_: Array, lambdadot: Array,
                 lambdaddot: Array, law: Law = PLAIN) -> Array:
    """
    Return the terms' part of ``W`` (N, 3, k) at the slider motion.

    One column per coefficient of ``law`` (:func:`standard_names` less the
    masses), the force of its term with that coefficient 1 and the others
    0 (:func:`columns`; ``friction_velocity``,
    ``friction_stribeck_velocity`` and ``screw_lead`` are ``robot``'s).
    """
    return np.concatenate([diagonal(columns(robot, term, law, lambda_,
                                            lambdadot, lambdaddot))
                           for term in law.columns_order()], axis=2)


def diagonal(own: Array) -> Array:
    """Return (N, 3, 3) columns from each actuator's own (N, 3)."""
    out = np.zeros(own.shape + (3,))
    for j in range(3):
        out[:, j, j] = own[:, j]
    return out
