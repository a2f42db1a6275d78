"""
The positions worth measuring: the best conditioned calibration.

:func:`design` picks N of CANDIDATES random positions of the workspace
cube (|x|, |y|, |z| <= CUBE, within the singularity margin of the nominal
robot) whose readings give the identified parameters' Jacobian
(:func:`geometry.jacobian`, unit-norm columns) the smallest condition
number: a greedy start (each position the one that most raises the
information's determinant) then exchanges (a chosen position swapped for
the candidate that most lowers the condition number) until none helps or
the evaluations are spent, as ``excitation --optimize`` searches the
dynamics' (doc/calibration.md#the-positions-to-measure).
"""

from __future__ import annotations

from collections import namedtuple
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.types import Array
from orthoglide_ros.tools.calibration import geometry
from orthoglide_ros.tools.calibration.identifiability import (
    BLUNDER_REDUNDANCY, identifiable, MIN_REDUNDANCY)

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# Half side of the paper's tested workspace cube (m), where positions are
# drawn.
CUBE = 0.3
# Positions drawn as candidates.
CANDIDATES = 2000
# Condition numbers an exchange search may compute (about 20 us each:
# 2 s by default, 3 min at most; doc/measurements.md#calibration).
DEFAULT_EVALUATIONS = 100_000
MAX_EVALUATIONS = 10_000_000
# Most positions asked: a campaign of a thousand measurements or readings.
MAX_COUNT = 1000
# Types of measurement: x, y and z at each position, or one coordinate
# (a dial gauge's) per reading.
TYPES = ('xyz', 'gauge')

Design = namedtuple('Design', ('lambdas', 'positions', 'coordinates',
                               'condition', 'random_condition',
                               'identified', 'evaluations', 'notes'))
Design.__doc__ = """The positions :func:`design` chose.

``lambdas`` (N, 3): the joint readings (m) to drive to; ``positions``
(N, 3): where the nominal robot puts the platform there (m); ``coordinates``
(N,): the coordinate each reading measures (0, 1, 2 for x, y, z; None for
``xyz``); ``condition``: the identified Jacobian's condition number
(unit-norm columns); ``random_condition``: the median of as many random
candidates' (for comparison); ``identified``: the parameters
(:data:`geometry.LEG_PARAMETERS` indices); ``evaluations``: condition
numbers computed; ``notes``: what the count does not allow, as sentences.
"""


class DesignError(ValueError):
    """
    Positions that cannot be designed; the message says why.

    ``option``: the argument at fault (``count``, ``type``), or None
    where the robot is (it reaches too little of the cube).
    """

    def __init__(self, message: str, option: str | None = None) -> None:
        """Keep ``message`` and the ``option`` at fault."""
        super().__init__(message)
        self.option = option


def minimum_count(kind: str, parameters: int,
                  spare: int = MIN_REDUNDANCY) -> int:
    """
    Return the fewest positions of ``kind`` for ``parameters`` values.

    Positions in x, y, z (``xyz``) or gauge readings whose readings
    leave ``spare`` more than the values.
    """
    per = 3 if kind == 'xyz' else 1
    return math.ceil((parameters + spare) / per)


def design(robot: Robot, count: int, kind: str = 'xyz', seed: int = 0,
           evaluations: int = DEFAULT_EVALUATIONS,
           candidates: int = CANDIDATES) -> 'Design':
    """
    Choose ``count`` positions whose readings best condition the calibration.

    ``robot``: the nominal robot; ``kind``: ``xyz`` or ``gauge`` (a
    candidate is then a position and a coordinate); ``seed``: of the
    candidates. Raises :class:`DesignError` for a count below
    :func:`minimum_count` or above MAX_COUNT, or a robot that reaches too
    little of the cube.
    """
    if kind not in TYPES:
        raise DesignError(f'{kind!r}: one of {", ".join(TYPES)}', 'type')
    rng = np.random.default_rng(seed)
    positions = _workspace(robot, rng, candidates)
    lambdas = mechanics.solve_batch(robot, positions).lambda_
    params = geometry.LEG_PARAMETERS
    columns = geometry.jacobian(robot.legs, lambdas, np.zeros(30))
    found = identifiable(columns.reshape(-1, len(params)), params)
    low = minimum_count(kind, len(found.identified))
    if not low <= count <= MAX_COUNT:
        raise DesignError(
            f'{count}: {"below" if count < low else "above"} '
            f'{low if count < low else MAX_COUNT}, the '
            + ('fewest whose readings identify the '
               f'{len(found.identified)} separable values with '
               f'{MIN_REDUNDANCY} readings to spare'
               if count < low else 'most this command designs'), 'count')
    blocks = columns[:, :, list(found.identified)]
    if kind == 'gauge':     # a candidate per position and coordinate
        blocks = blocks.reshape(-1, 1, blocks.shape[2])
    gram = np.einsum('nki,nkj->nij', blocks, blocks)
    chosen, spent = _exchange(blocks, gram, count, evaluations)
    rows = chosen // 3 if kind == 'gauge' else chosen
    random_condition = float(np.median([
        condition(gram[rng.choice(len(gram), count, replace=False)].sum(0))
        for _ in range(15)]))
    sure = minimum_count(kind, len(found.identified), BLUNDER_REDUNDANCY)
    notes = () if count >= sure else (
        f'{count} {"positions" if kind == "xyz" else "readings"} leave '
        f'{count * (3 if kind == "xyz" else 1) - len(found.identified)} '
        'readings to spare: too few to find a blunder reliably; '
        f'{sure} or more do',)
    return Design(lambdas[rows], positions[rows],
                  chosen % 3 if kind == 'gauge' else None,
                  condition(gram[chosen].sum(0)), random_condition,
                  found.identified, spent, notes)


def condition(information: Array) -> Any:
    """
    Return the condition number of ``J`` from ``J^T J`` (k, k).

    Columns scaled to unit norm first; inf where a column is zero or the
    matrix singular. A float, or an array of them for (M, k, k).
    """
    d = np.sqrt(np.diagonal(information, axis1=-2, axis2=-1))
    with np.errstate(divide='ignore', invalid='ignore'):
        scaled = information / (d[..., :, None] * d[..., None, :])
        values = np.linalg.eigvalsh(scaled)
        out = np.sqrt(values[..., -1] / values[..., 0])
    return np.where(np.isfinite(out) & (values[..., 0] > 0.0), out,
                    math.inf)[()]


def _workspace(robot, rng, count):
    """Draw ``count`` positions of the cube within the robot's margin."""
    out = np.empty((0, 3))
    for _ in range(100):
        draw = rng.uniform(-CUBE, CUBE, (2 * count, 3))
        out = np.vstack((out, draw[mechanics.workspace_status(robot,
                                                              draw).ok]))
        if len(out) >= count:
            return out[:count]
    raise DesignError('the robot reaches too little of the workspace cube '
                      f'|x|, |y|, |z| <= {CUBE:g} m within its singularity '
                      'margin')


def _exchange(blocks, gram, count, evaluations):
    """
    Return the indices of ``count`` candidates and the evaluations spent.

    ``blocks``: each candidate's readings' Jacobian ``J_c`` (M, r, k),
    ``gram`` its ``J_c^T J_c`` (M, k, k). Greedy on the determinant of
    the information ``A`` (regularised until it has full rank): the
    candidate of the largest ``det(A + J_c^T J_c) = det(A) det(I + J_c
    A^-1 J_c^T)`` (the matrix determinant lemma: an r x r determinant
    per candidate, so that the greedy's ``count`` steps over M candidates
    take about a second at the limits); then exchanges that lower the
    condition number, best first, at most ``evaluations`` of them.
    """
    size = gram.shape[1]
    ridge = 1e-9 * np.trace(gram.mean(0)) * np.eye(size)
    information = ridge.copy()
    chosen = []
    free = np.ones(len(gram), dtype=bool)
    eye = np.eye(blocks.shape[1])
    for _ in range(count):
        seen = blocks @ np.linalg.inv(information)
        gain = np.linalg.slogdet(eye + seen @ blocks.transpose(0, 2, 1))[1]
        gain[~free] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        free[best] = False
        information = information + gram[best]
    information -= ridge
    spent = 0
    current = float(condition(information))
    improved = True
    while improved and spent < evaluations:
        improved = False
        for slot in range(count):
            if spent >= evaluations:
                break
            base = information - gram[chosen[slot]]
            tried = np.flatnonzero(free)[:evaluations - spent]
            values = condition(base + gram[tried])
            spent += len(tried)
            best = int(np.argmin(values))
            if values[best] < current * (1.0 - 1e-6):
                free[chosen[slot]] = True
                chosen[slot] = int(tried[best])
                free[chosen[slot]] = False
                information = base + gram[chosen[slot]]
                current = float(values[best])
                improved = True
    return np.array(sorted(chosen)), spent
