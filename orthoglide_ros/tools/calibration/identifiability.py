"""
Which geometric parameters the measurements separate, found from the data.

The Jacobian of the readings with respect to every parameter
(:func:`geometry.jacobian`: the legs' 30, the instrument's 6), each column
scaled by a built robot's error of it and its priority, through a QR
decomposition with column pivoting (as identification's base parameters,
doc/identification.md#base-parameters): pivots above RANK_TOLERANCE of the
first are separable, every other column the least-squares combination of
those that it moves the readings as. Nothing is listed in the code
(doc/calibration.md#identifiability).
"""

from __future__ import annotations

from collections import namedtuple
from typing import Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.tools.calibration.geometry import Parameter

# A pivot below this fraction of the first is a column the others already
# make (exact dependencies give about 1e-16 of the first; the weakest
# separable parameter of 6 positions measured in x, y, z, 1e-4).
RANK_TOLERANCE = 1e-8
# Readings a fit keeps beyond the values it identifies: the noise's
# estimate and the search for blunders need them.
MIN_REDUNDANCY = 6
# Readings to spare from which a blunder is found reliably: a 5 mm one
# in one reading of 12 random positions in x, y, z (18 to spare) was
# named on 90 machines of 90; with fewer, the fit absorbs it more often
# (then refused for the noise it leaves) and, with a gauge, may miss it
# harmfully (doc/measurements.md#calibration).
BLUNDER_REDUNDANCY = 18
# A combination's coefficient nearer zero than this is zero.
COMBINATION_TOLERANCE = 1e-9

Identifiability = namedtuple('Identifiability', (
    'identified', 'held', 'combinations', 'explained', 'separable',
    'readings'))
Identifiability.__doc__ = """What :func:`identifiable` found.

``identified`` and ``held``: indices of the parameters (sorted);
``combinations`` (len(held), len(identified)): a held parameter moves the
readings as this combination of the identified ones (the Jacobian's
columns, m per m or rad), ``explained`` (bool each) where it does so
exactly (to COMBINATION_TOLERANCE of its column), not where it was held
for want of readings; ``separable``: how many the data separate
(the pivots above RANK_TOLERANCE); ``readings``: the readings (measured
coordinates) they were found from. ``identified`` holds ``separable`` of
them, or fewer where the readings do not leave MIN_REDUNDANCY.
"""


def identifiable(columns: Array, params: Sequence[Parameter],
                 redundancy: int = MIN_REDUNDANCY) -> Identifiability:
    """
    Find what the readings' Jacobian ``columns`` (n, p) can separate.

    ``params``: the p parameters (their ``scale`` and ``priority`` weight
    the columns). The first ``min(rank, n - redundancy)`` pivoted columns
    are identified (none where ``n <= redundancy``).
    """
    import scipy.linalg
    weights = np.array([p.scale * p.priority for p in params])
    _, r, pivots = scipy.linalg.qr(columns * weights, mode='economic',
                                   pivoting=True)
    diagonal = np.abs(np.diag(r))
    relative = diagonal / diagonal[0] if diagonal[0] > 0.0 else diagonal
    separable = int(np.sum(relative > RANK_TOLERANCE))
    count = max(0, min(separable, len(columns) - redundancy))
    identified = np.sort(pivots[:count])
    held = np.sort(pivots[count:])
    combinations = np.zeros((len(held), count))
    explained = np.zeros(len(held), dtype=bool)
    if len(held) and count:
        combinations[:] = np.linalg.lstsq(columns[:, identified],
                                          columns[:, held], rcond=None)[0].T
        left = columns[:, held] - columns[:, identified] @ combinations.T
        explained = np.linalg.norm(left, axis=0) <= COMBINATION_TOLERANCE \
            * np.linalg.norm(columns[:, held], axis=0)
        combinations[np.abs(combinations) < COMBINATION_TOLERANCE] = 0.0
    return Identifiability(tuple(int(j) for j in identified),
                           tuple(int(j) for j in held), combinations,
                           tuple(bool(e) for e in explained), separable,
                           len(columns))


def combination_text(params: Sequence[Parameter], found: Identifiability,
                     k: int) -> str:
    """
    Describe held parameter ``found.held[k]`` by what it moves the readings as.

    ``'-joint_offset[a]'``, ``'0.5 a + 2 b'``; ``'not separated: too few readings'`` where
    it is not a combination of the identified ones.
    """
    row = found.combinations[k]
    terms = [(c, params[j].name) for c, j in zip(row, found.identified)
             if c != 0.0]
    if not terms or not found.explained[k]:
        return 'not separated: too few readings'
    out = ''
    for c, name in sorted(terms, key=lambda t: -abs(t[0])):
        size = f'{abs(c):.4g}'
        factor = '' if size == '1' else size + ' '
        out += (('-' if c < 0 else '') if not out else
                (' - ' if c < 0 else ' + ')) + factor + name
    return out
