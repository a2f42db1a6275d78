"""
The regressor ``W`` of the forces, and the base parameters a log can find.

:func:`regressor` builds ``W`` from the package's own inverse dynamics
(eq. 25; a mass's column a difference of two robots' forces, a term's its
force at coefficient 1), not from a second model
(doc/identification.md#base-parameters).
"""

from __future__ import annotations

from typing import Optional, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.model import mechanics, terms
from orthoglide_ros.tools.identification.laws import (
    Law, MASSES, MEANINGS, OPTIONAL, PLAIN, standard_names,
    standard_parameters, term_columns)
from orthoglide_ros.model.types import Array, Rows

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# States at which the base parameters are found: random, uniform in a
# cube of half side BASE_BOX (m) inside the workspace, with speeds up to
# BASE_SPEED (m/s) and accelerations up to BASE_ACCELERATION (m/s^2) per
# axis: far richer than any log, so only structural dependencies remain.
BASE_SAMPLES = 400
BASE_BOX = 0.25
BASE_SPEED = 1.0
BASE_ACCELERATION = 10.0
# A pivot of the QR decomposition below this fraction of the first is a
# dependent column (exact dependencies give about 1e-16; the weakest
# independent one of the paper's robot, 5e-3).
RANK_TOLERANCE = 1e-8
# Coefficients of a base combination closer to zero than this are zero.
COMBINATION_TOLERANCE = 1e-9

Base = namedtuple('Base', ('names', 'independent', 'matrix', 'meanings',
                           'law'), defaults=(PLAIN,))
Base.__doc__ = """The base parameters (:func:`base_parameters`) of a law.

``matrix`` ``P`` (n_base, n): ``beta = P theta`` and ``W theta = W[:,
independent] beta`` for every state, ``theta`` the standard parameters
of ``law`` (:func:`laws.standard_names`); ``independent``: the standard
parameter carrying each base parameter (its column of ``P`` is a unit
one); ``names``: each as a combination, e.g. ``'m5 + 3 m4'``;
``meanings``: the same in words (:data:`laws.MEANINGS`).
"""


def regressor(robot: Robot, positions: Rows, velocities: Rows,
              accelerations: Rows, law: Law = PLAIN,
              margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN) -> Array:
    """
    Return ``W`` (N, 3, n): ``force = W @ theta`` per sample and actuator.

    ``positions`` (m), ``velocities`` (m/s), ``accelerations`` (m/s^2):
    (N, 3) arrays of the platform centre in frame 0. Built from
    :func:`mechanics.solve_batch` on ``robot``'s geometry and gravity (its
    masses, drives and friction do not matter): the masses' columns of
    :func:`rigid_columns`, then the terms' of ``law``
    (:func:`laws.term_columns`) at the samples' ``lambda``, ``lambdadot``
    and ``lambdaddot``. Raises :class:`mechanics.WorkspaceError` as
    ``solve_batch`` does.
    """
    rigid, reference = rigid_columns(robot, positions, velocities,
                                     accelerations, margin)
    return np.concatenate((rigid, term_columns(
        robot, reference.lambda_, reference.lambdadot, reference.lambdaddot,
        law)), axis=2)


def rigid_columns(robot: Robot, positions: Rows, velocities: Rows,
                  accelerations: Rows,
                  margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN
                  ) -> tuple[Array, mechanics.Solution]:
    """
    Return the masses' columns (N, 3, 6) and the kinematics.

    Column ``m_i`` is the force of a robot whose masses are all 1 kg but
    ``m_i``, 2 kg, less that of the robot whose masses are all 1 kg (no
    term: no payload, drive or friction). The kinematics: a
    :class:`mechanics.Solution` along the motion.
    """
    unit = terms.rigid(robot).replace(**dict.fromkeys(MASSES, 1.0))
    reference = mechanics.solve_batch(unit, positions, velocities,
                                      accelerations, margin)
    out = np.empty(reference.force.shape + (len(MASSES),))
    for i, name in enumerate(MASSES):
        out[:, :, i] = mechanics.solve_batch(
            unit.replace(**{name: 2.0}), positions, velocities,
            accelerations, margin).force - reference.force
    return out, reference


def base_parameters(robot: Robot, law: Law = PLAIN,
                    samples: int = BASE_SAMPLES, seed: int = 0) -> 'Base':
    """
    Find the base parameters of ``robot``'s regressor (a :class:`Base`).

    ``W`` of ``law`` at ``samples`` random states (BASE_BOX and its
    neighbours; ``seed``), each column weighted by its nominal value in
    ``robot`` (scaled to unit RMS where that is zero; a column that is zero
    everywhere, a ripple without a lead, is no parameter), through a QR
    decomposition with column pivoting: pivots above RANK_TOLERANCE of the
    first are independent, the other columns their least-squares
    combinations (``P``). The weighting makes the largest nominal
    contribution carry each combination (doc/identification.md#base-parameters).
    """
    import scipy.linalg
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-BASE_BOX, BASE_BOX, (samples, 3))
    velocities = rng.uniform(-BASE_SPEED, BASE_SPEED, (samples, 3))
    accelerations = rng.uniform(-BASE_ACCELERATION, BASE_ACCELERATION,
                                (samples, 3))
    ok = mechanics.workspace_status(robot, positions).ok
    names = standard_names(law)
    w = regressor(robot, positions[ok], velocities[ok], accelerations[ok],
                  law).reshape(-1, len(names))
    nominal = standard_parameters(robot, law)
    rms = np.sqrt(np.mean(w * w, axis=0))
    weights = np.where(nominal > 0.0, nominal, 1.0 / np.where(
        rms > 0.0, rms, np.inf))
    _, r, pivots = scipy.linalg.qr(w * weights, mode='economic',
                                   pivoting=True)
    diagonal = np.abs(np.diag(r))
    rank = int(np.sum(diagonal > RANK_TOLERANCE * diagonal[0]))
    independent = np.sort(pivots[:rank])
    dependent = np.sort(pivots[rank:])
    matrix = np.zeros((rank, len(names)))
    matrix[np.arange(rank), independent] = 1.0
    if len(dependent):
        combination = np.linalg.lstsq(w[:, independent], w[:, dependent],
                                      rcond=None)[0]
        combination[np.abs(combination) < COMBINATION_TOLERANCE] = 0.0
        matrix[:, dependent] = combination
    texts, meanings = ([_combination(row, j, names, words, times)
                        for row, j in zip(matrix, independent)]
                       for words, times in ((dict(zip(names, names)), ' '),
                                            (MEANINGS, ' x ')))
    return Base(tuple(texts), tuple(int(j) for j in independent), matrix,
                tuple(meanings), law)


def _combination(row, carrier, names, words, times):
    """
    Write ``sum_k row_k theta_k``, the carrier first, in ``words``.

    ``'m5 + 3 m4'`` with the names and ``times`` ``' '``.
    """
    order = [carrier] + [k for k in range(len(row))
                         if k != carrier and row[k] != 0.0]
    text = ''
    for k in order:
        c = row[k]
        rounded = round(c)
        size = abs(c)
        if abs(c - rounded) <= COMBINATION_TOLERANCE * max(1.0, size):
            size = abs(rounded)
        factor = '' if size == 1 else f'{size:.6g}{times}'
        sign = '-' if c < 0 else '+'
        text += (f'{"-" if c < 0 else ""}' if not text else f' {sign} ') \
            + factor + words[names[k]]
    return text


_BASES = {}


def base_of(robot: Robot, law: Law) -> 'Base':
    """Return :func:`base_parameters` of ``robot`` and ``law`` (kept)."""
    key = (robot, law)
    if key not in _BASES:
        if len(_BASES) >= 16:
            _BASES.clear()
        _BASES[key] = base_parameters(robot, law)
    return _BASES[key]


def design_law(robot: Robot) -> Law:
    """
    Return the law an excitation for ``robot`` is designed for.

    The plain law, with the inertial terms (the drives) that ``robot``
    has: a motion that tells each drive's inertia from the masses (which
    gravity alone does for ``m1 + m2``).
    """
    return Law(PLAIN + tuple(term for term in OPTIONAL if term.inertial
                             and term in robot.active_terms))


def condition_number(robot: Robot, positions: Rows, velocities: Rows,
                     accelerations: Rows,
                     base: Optional['Base'] = None) -> float:
    """
    Condition number of the base regressor along a motion (no noise).

    (N, 3) arrays (m, m/s, m/s^2); ``base`` default the base parameters
    of ``robot`` and :func:`design_law`. Columns scaled to unit norm, as
    identify solves them: 1 is ideal, and the larger it is the more the
    noise of the log is amplified into the parameters.
    """
    base = base or base_of(robot, design_law(robot))
    w = regressor(robot, positions, velocities, accelerations, base.law)
    a = w[:, :, list(base.independent)].reshape(-1, len(base.independent))
    norms = np.linalg.norm(a, axis=0)
    if not (np.isfinite(norms).all() and norms.min() > 0.0):
        return math.inf     # a column the motion does not excite at all
    # The singular values' ratio, from the eigenvalues of the small Gram
    # matrix (exact to about 1e-16 times the condition number squared).
    scaled = a / norms
    eigenvalues = np.linalg.eigvalsh(scaled.T @ scaled)
    return float(math.sqrt(eigenvalues[-1] / max(eigenvalues[0], 0.0))) \
        if eigenvalues[0] > 0.0 else math.inf
