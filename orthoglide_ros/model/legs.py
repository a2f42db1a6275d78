"""
Each leg as built: its actuator axis, joint offset, bar length, attachment.

Leg i (A, B, C) holds the platform centre G on a sphere, eq. (14)
generalised (doc/model.md#the-machine-as-built):

    | G + r_i - a_i - (lambda_i + e_i - L_i) u_i | = L_i

with ``a_i`` the axis point, ``u_i`` the axis direction, ``e_i`` the joint
offset, ``L_i`` the bar length and ``r_i`` the attachment, the rows
``robot.axis_point_a`` ... of :mod:`robot`. :func:`build` derives every
:class:`Leg` once from them (``Robot.legs``), with the leg's frame ``R_i``
in which the kernel's one-leg recursion runs; :func:`intersect` is the
forward kinematics in closed form and :func:`status` each leg's reach and
``J_lambda``, both for legs as built (:mod:`mechanics` takes the drawing's
own closed forms for a robot as drawn).
"""

from __future__ import annotations

from collections import namedtuple
import math
from typing import Any, Sequence

import numpy as np

from orthoglide_ros.model import kernel
from orthoglide_ros.model.types import Array, Rows, Triple

# The drawing's axes n_i: actuator A moves along +x0, B along +y0, C +z0.
DRAWING_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
# The drawing's leg frames P_i, row by row, its columns the leg's own x, y,
# z in frame 0: leg B sees G as (y, z, x), leg C as (z, x, y), the kernel's
# cyclic permutation (b10 = a1 P_B^T, c10 = a1 P_C^T).
DRAWING_FRAMES = (
    ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
)

Matrix = tuple[Triple, ...]

# Smallest accepted singularity distance by default (the mechanics' margin,
# mechanics.workspace_status): legs whose home stands nearer a singularity
# do not assemble (robot.py).
DEFAULT_SINGULARITY_MARGIN = 0.2

Leg = namedtuple('Leg', ('name', 'point', 'direction', 'offset', 'length',
                         'attachment', 'frame'))
Leg.__doc__ = """One leg's geometry, as built (doc/model.md#the-machine-as-built).

``name`` (``'a'``, ``'b'``, ``'c'``); ``point`` ``a_i`` (m, frame 0), the
point of the actuator's axis where the leg holds its platform point when
the slider's true position is 0 and the bars lie along the axis;
``direction`` ``u_i``, the unit vector of +lambda_i; ``offset`` ``e_i``
(m), the slider's true position less its reading; ``length`` ``L_i`` (m),
the parallelogram's bars; ``attachment`` ``r_i`` (m, frame 0), the leg's
platform point relative to G; ``frame`` ``R_i`` (3x3, row by row): its
columns are the leg's own axes in frame 0, the first ``u_i``.
"""


def smallest_rotation(axis: Sequence[float],
                      direction: Sequence[float]) -> Matrix:
    """
    Return the smallest rotation taking the unit ``axis`` onto ``direction``.

    Rodrigues' formula about ``k = axis x direction``: ``I + k~ + k~ k~ /
    (1 + axis . direction)``, no roll about the axis; exactly the identity
    for ``direction == axis``. Both unit 3-vectors, less than 90 deg apart.
    """
    n1, n2, n3 = axis
    u1, u2, u3 = direction
    k1, k2, k3 = n2 * u3 - n3 * u2, n3 * u1 - n1 * u3, n1 * u2 - n2 * u1
    w = 1.0 / (1.0 + n1 * u1 + n2 * u2 + n3 * u3)
    # k~ = [[0, -k3, k2], [k3, 0, -k1], [-k2, k1, 0]]; k~ k~ = k k^T - |k|^2 I.
    kk = k1 * k1 + k2 * k2 + k3 * k3
    return ((1.0 + w * (k1 * k1 - kk), w * k1 * k2 - k3, w * k1 * k3 + k2),
            (w * k2 * k1 + k3, 1.0 + w * (k2 * k2 - kk), w * k2 * k3 - k1),
            (w * k3 * k1 - k2, w * k3 * k2 + k1, 1.0 + w * (k3 * k3 - kk)))


def multiply(a: Matrix, b: Matrix) -> Matrix:
    """Return the 3x3 product ``a b`` (tuples of rows)."""
    return tuple(tuple(a[i][0] * b[0][j] + a[i][1] * b[1][j]
                       + a[i][2] * b[2][j] for j in range(3))
                 for i in range(3))


def unit(vector: Sequence[float]) -> Triple:
    """Return ``vector / |vector|`` (exactly itself for a drawing axis)."""
    norm = math.sqrt(sum(v * v for v in vector))
    return tuple(v / norm for v in vector)


def build(points: Sequence[Triple], directions: Sequence[Triple],
          offsets: Triple, lengths: Triple,
          attachments: Sequence[Triple]) -> tuple[Leg, ...]:
    """
    Return the three legs (A, B, C) of the rows' values.

    ``directions`` are normalised (the robot checks that they are unit
    vectors to 1e-3); each leg's frame is ``R_i = Rot(n_i -> u_i) P_i``,
    :func:`smallest_rotation` after the drawing's frame. The drawing's
    values give the drawing's frames exactly.
    """
    out = []
    for i, name in enumerate(('a', 'b', 'c')):
        u = unit(directions[i])
        out.append(Leg(name, tuple(points[i]), u, offsets[i], lengths[i],
                       tuple(attachments[i]), multiply(smallest_rotation(
                           DRAWING_AXES[i], u), DRAWING_FRAMES[i])))
    return tuple(out)


def angle(a: Sequence[float], b: Sequence[float]) -> float:
    """Return the angle between two unit vectors (rad), robust near 0."""
    cross = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
             a[0] * b[1] - a[1] * b[0])
    return math.atan2(math.sqrt(sum(c * c for c in cross)),
                      sum(x * y for x, y in zip(a, b)))


def intersect(legs: Sequence[Leg], lam: Rows) -> tuple[Array, Array]:
    """
    Forward kinematics of legs as built: ``(positions, found)``.

    Trilateration: G lies on leg i's sphere of centre ``c_i = a_i - r_i +
    (lambda_i + e_i - L_i) u_i`` and radius ``L_i``. In the frame ``(ex,
    ey, ez)`` of the three centres (``ex`` from ``c_1`` to ``c_2``, ``ey``
    towards ``c_3``), ``G = c_1 + X ex + Y ey + Z ez`` with ``X``, ``Y``
    from the spheres' differences and ``Z = +sqrt(L_1^2 - X^2 - Y^2)``:
    the side where ``det[G - c_i] > 0``, as at home, the home branch (the
    other root is its mirror across the centres' plane, where ``J2`` is
    singular). ``lam``: (3,) or (N, 3) (m). ``found`` (bool, () or (N,))
    says where that point exists with every ``alpha_i = u_i . (G - c_i) >
    0``; ``positions`` (m) is meaningless elsewhere.
    """
    lam = np.asarray(lam, dtype=float)
    centres = [np.subtract(leg.point, leg.attachment) + (
        lam[..., i, None] + (leg.offset - leg.length)) * np.asarray(
            leg.direction) for i, leg in enumerate(legs)]
    l1, l2, l3 = (leg.length for leg in legs)
    c1, c2, c3 = centres
    with np.errstate(all='ignore'):     # judged by found, row by row
        side = c2 - c1
        d = np.sqrt((side * side).sum(-1))
        ex = side / d[..., None]
        to3 = c3 - c1
        i = (ex * to3).sum(-1)
        across = to3 - i[..., None] * ex
        j = np.sqrt((across * across).sum(-1))
        ey = across / j[..., None]
        x = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d)
        y = (l1 * l1 - l3 * l3 + i * i + j * j - 2.0 * i * x) / (2.0 * j)
        zz = l1 * l1 - x * x - y * y
        position = c1 + x[..., None] * ex + y[..., None] * ey + np.sqrt(
            zz)[..., None] * np.cross(ex, ey)
        alpha = np.stack([((position - c) * leg.direction).sum(-1)
                          for c, leg in zip(centres, legs)], -1)
        found = (zz >= 0.0) & np.isfinite(position).all(-1) & (
            alpha > 0.0).all(-1)
    return position, found


def status(legs: Sequence[Leg], constants: Sequence[Any],
           position: Rows) -> tuple[Any, Any, Any, Any]:
    """
    Reach, ``alpha_i / L_i`` and ``J_lambda`` of legs as built.

    ``position``: (3,) or (N, 3) (m, frame 0); ``constants``: the legs'
    :data:`kernel.LegConstants`. Leg i reaches G where its point ``(x',
    y', z')`` (:func:`kernel.leg_point`) has ``y'^2 + z'^2 < L_i^2``; then
    ``alpha_i / L_i = sqrt(1 - (y'^2 + z'^2) / L_i^2)`` (eq. 17) and
    ``J_lambda``'s row i is ``R_i (1, y'/alpha_i, z'/alpha_i)``. Returns
    ``(reachable, alpha_ratio, conditioning, j_lambda)``: ``() or (N,)``,
    ``(3,) or (N, 3)`` (0 where unreachable), ``() or (N,)`` (``1 /
    kappa_F(J_lambda)``, 0 where unreachable or singular) and ``(3, 3)``
    or ``(N, 3, 3)``.
    """
    p = np.asarray(position, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    reach, rows = [], []
    for leg, c in zip(legs, constants):
        _, yq, zq = kernel.leg_point(c, x, y, z)
        reach.append(1.0 - (yq * yq + zq * zq) / (leg.length * leg.length))
        rows.append((yq, zq))
    q = np.stack(reach, -1)
    with np.errstate(invalid='ignore'):
        reachable = (q > 0.0).all(-1)
    ratio = np.sqrt(np.where(reachable[..., None], q, 1.0))
    entries = []
    for i, (leg, (yq, zq)) in enumerate(zip(legs, rows)):
        alpha = leg.length * ratio[..., i]
        ty, tz = yq / alpha, zq / alpha
        entries.extend(r[0] + r[1] * ty + r[2] * tz for r in leg.frame)
    with np.errstate(divide='ignore', invalid='ignore'):
        conditioning = kernel.cofactors(entries, np.sqrt)[2]
    conditioning = np.where(reachable, np.nan_to_num(conditioning, nan=0.0),
                            0.0)
    j_lambda = np.stack(entries, -1).reshape(p.shape[:-1] + (3, 3))
    return (reachable, np.where(reachable[..., None], ratio, 0.0),
            conditioning, j_lambda)
