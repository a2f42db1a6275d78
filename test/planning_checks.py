"""
Independent checks of planned motions, shared by the planning tests.

- :func:`toppra_duration`: the time-optimal duration along a path by the
  ``toppra`` library (TOPP-RA, Pham and Pham 2018) on its own fine grid,
  for a robot without speed-dependent friction: the optimum the planner
  must come near.
- :func:`lagrange_check`: samples re-solved with the independent Lagrange
  model (``mechanics_reference``) and the friction law written from
  doc/model.md: the worst share of every limit.
- :func:`path_distance`: each sample's distance to a path given as dense
  points; :func:`distance_to_path`: each point's distance to a Path, exact
  (dense samples, then a golden-section search on the path itself);
- :class:`CurvePath`: a smooth curve given by a formula as a one-piece
  path, for toppra and the distances (a curve the planner never saw).
"""

import logging
import math
from types import SimpleNamespace

import numpy as np

import mechanics_reference as reference
from orthoglide_ros.model import mechanics

logging.getLogger('toppra').setLevel(logging.ERROR)


def toppra_duration(robot, path, limits, intervals=4000, max_speed=math.inf):
    """
    Duration (s) of TOPP-RA's optimum along ``path`` within ``limits``.

    Effort, velocity and acceleration limits and G's feed; ``robot``
    without friction that depends on the speed (its viscous and Coulomb
    terms must be zero). The grid is toppra's own, uniform in ``s``; where
    two pieces meet, both pieces' coefficients constrain the junction
    gridpoint, and a junction where the planner stops is held at rest.
    """
    import warnings
    with warnings.catch_warnings():     # its docstrings' escape sequences
        warnings.simplefilter('ignore', DeprecationWarning)
        import toppra.algorithm

    assert not robot.has_friction
    starts = np.concatenate(([0.0], np.cumsum([p.length for p in path.pieces])))
    s = np.unique(np.concatenate((np.linspace(0.0, starts[-1], intervals + 1),
                                  starts)))
    right = np.clip(np.searchsorted(starts, s, side='right') - 1, 0,
                    len(path.pieces) - 1)
    left = np.clip(np.searchsorted(starts, s, side='left') - 1, 0,
                   len(path.pieces) - 1)
    constraints = []
    xbound = np.tile([0.0, 1e12], (len(s), 1))
    for index in (left, right):
        w = np.clip(s - starts[index], 0.0,
                    [path.pieces[k].length for k in index])
        p, d1, d2 = path.evaluate(index, w)
        inertia = robot.replace(gravity=(0.0, 0.0, 0.0))
        a = mechanics.solve_batch(inertia, p, None, d1).force
        curving = mechanics.solve_batch(inertia, p, d1, d2)
        c = mechanics.solve_batch(robot, p).force
        rows_a, rows_b, rows_c, bound = [], [], [], []
        for j in range(3):
            if math.isfinite(limits.effort[j]):
                rows_a.append(a[:, j])
                rows_b.append(curving.force[:, j])
                rows_c.append(c[:, j])
                bound.append(limits.effort[j])
            if math.isfinite(limits.acceleration[j]):
                rows_a.append(curving.lambdadot[:, j])
                rows_b.append(curving.lambdaddot[:, j])
                rows_c.append(np.zeros(len(s)))
                bound.append(limits.acceleration[j])
        speed_cap = np.full(len(s), 1e12)
        with np.errstate(divide='ignore'):
            for j in range(3):
                speed_cap = np.minimum(speed_cap, (
                    limits.velocity[j] / np.abs(curving.lambdadot[:, j])) ** 2)
            feed = np.minimum([path.pieces[k].feed for k in index], max_speed)
            speed_cap = np.minimum(speed_cap, (feed / np.linalg.norm(
                d1, axis=1)) ** 2)
        xbound[:, 1] = np.minimum(xbound[:, 1], speed_cap)
        if rows_a:
            constraints.append(_Rows(np.array(rows_a).T, np.array(rows_b).T,
                                     np.array(rows_c).T, np.array(bound)))
    stops = starts[np.nonzero(path.stops)[0]]
    xbound[np.isin(s, stops), 1] = 0.0
    constraints.append(_Caps(xbound))
    instance = toppra.algorithm.TOPPRA(constraints, _Line(s[-1]),
                                       gridpoints=s, solver_wrapper='seidel')
    sdd, sd, _ = instance.compute_parameterization(0.0, 0.0)
    assert sd is not None, 'toppra found no parametrization'
    pace = sd[1:] + sd[:-1]
    return float(np.sum(2.0 * np.diff(s) / pace))


class _Line:
    """The minimal geometric path toppra needs: its interval."""

    def __init__(self, length):
        self.path_interval = np.array([0.0, length])
        self.dof = 1


def _rows_class():
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', DeprecationWarning)
        import toppra.constraint as constraint

    class Rows(constraint.LinearConstraint):
        """``|a u + b x + c| <= bound`` per row, interpolation scheme."""

        def __init__(self, a, b, c, bound):
            super().__init__()
            self.values = (a, b, c, bound)
            self.identical = True
            self.discretization_type = \
                constraint.DiscretizationType.Interpolation

        def compute_constraint_params(self, path, gridpoints, *args, **kw):
            a, b, c, bound = self.values
            k = len(bound)
            f = np.vstack((np.eye(k), -np.eye(k)))
            return a, b, c, f, np.r_[bound, bound], None, None

    class Caps(constraint.LinearConstraint):
        """Bounds on ``x`` alone."""

        def __init__(self, xbound):
            super().__init__()
            self.xbound = xbound
            self.discretization_type = \
                constraint.DiscretizationType.Collocation

        def compute_constraint_params(self, path, gridpoints, *args, **kw):
            return None, None, None, None, None, None, self.xbound

    return Rows, Caps


def _Rows(*args):
    return _rows_class()[0](*args)


def _Caps(*args):
    return _rows_class()[1](*args)


def friction_reference(robot, rates):
    """Return the sliders' friction (N) by doc/model.md's law, written anew."""
    rates = np.asarray(rates, dtype=float)
    out = np.empty_like(rates)
    for j in range(3):
        v = rates[..., j]
        coulomb = np.where(v > 0.0, robot.friction_coulomb[j],
                           robot.friction_coulomb_negative[j])
        stribeck = robot.friction_stribeck[j] * np.exp(
            -(v / robot.friction_stribeck_velocity) ** 2)
        out[..., j] = robot.friction_viscous[j] * v + (coulomb + stribeck) \
            * np.tanh(v / robot.friction_velocity)
    return out


def lagrange_check(robot, motion, limits, samples):
    """
    Return the worst share of each limit over ``samples``, re-solved.

    Forces by Lagrange's equations (``mechanics_reference``) plus the
    friction law; actuator rates and accelerations by the reference's
    ``J_lambda`` and the derivative of ``lambda`` along the motion.
    Returns ``{'effort': share, 'velocity': ..., 'acceleration': ...}``:
    the largest ``|value| / limit`` over the samples.
    """
    worst = {'effort': 0.0, 'velocity': 0.0, 'acceleration': 0.0}
    for k in samples:
        p = motion.position[k]
        v = motion.velocity[k]
        a = motion.acceleration[k]
        jac = reference.lambda_jacobian(robot, p)
        rates = jac @ v
        # lambdaddot = J a + (dJ/dt) v, dJ/dt by a central difference.
        h = 1e-6
        djac = (reference.lambda_jacobian(robot, p + h * v)
                - reference.lambda_jacobian(robot, p - h * v)) / (2 * h)
        accelerations = jac @ a + djac @ v
        force = reference.lagrange_forces(robot, p, v, a).force + \
            friction_reference(robot, rates)
        for name, value, bound in (
                ('effort', force, limits.effort),
                ('velocity', rates, limits.velocity),
                ('acceleration', accelerations, limits.acceleration)):
            with np.errstate(divide='ignore'):
                share = np.abs(value) / bound
            worst[name] = max(worst[name], float(share.max()))
    return worst


def path_distance(points, dense, neighbours=8):
    """
    Distance (m) of each of ``points`` (n, 3) to the polyline ``dense``.

    The nearest ``neighbours`` vertices by a k-d tree (a junction's vertex
    comes twice, once per piece), then the segments beside each.
    """
    from scipy.spatial import cKDTree
    _, nearest = cKDTree(dense).query(points, k=neighbours)
    best = np.full(len(points), np.inf)
    for column in nearest.T:
        for first in (column - 1, column):
            k = np.clip(first, 0, len(dense) - 2)
            a, b = dense[k], dense[k + 1]
            ab = b - a
            t = np.clip(((points - a) * ab).sum(1) / np.maximum(
                (ab * ab).sum(1), 1e-300), 0.0, 1.0)
            best = np.minimum(best, np.linalg.norm(
                points - a - t[:, None] * ab, axis=1))
    return best


def distance_to_path(path, points, spacing=1e-5, candidates=4):
    """
    Return the distance (m) of each of ``points`` (n, 3) to ``path``.

    ``path``: anything with ``pieces`` (their ``length``) and
    ``evaluate(index, w)``. The ``candidates`` nearest of samples
    ``spacing`` (m) apart at most (16 a piece at least), then a
    golden-section search of ``|p(w) - x|`` over the sample's
    neighbourhood on its piece: the distance to the path itself, not to a
    polyline through it.
    """
    from scipy.spatial import cKDTree
    index, w, width = [], [], []
    for k, piece in enumerate(path.pieces):
        count = max(16, math.ceil(piece.length / spacing)) + 1
        ws = np.linspace(0.0, piece.length, count)
        index.append(np.full(count, k))
        w.append(ws)
        width.append(np.full(count, ws[1] - ws[0]))
    index, w, width = map(np.concatenate, (index, w, width))
    dense = path.evaluate(index, w)[0]
    _, nearest = cKDTree(dense).query(points, k=candidates)
    best = np.full(len(points), np.inf)
    lengths = np.array([piece.length for piece in path.pieces])
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    for column in np.atleast_2d(nearest.T):
        k = index[column]
        low = np.clip(w[column] - width[column], 0.0, lengths[k])
        high = np.clip(w[column] + width[column], 0.0, lengths[k])

        def far(at):
            return np.linalg.norm(path.evaluate(k, at)[0] - points, axis=1)
        for _ in range(40):
            a = high - golden * (high - low)
            b = low + golden * (high - low)
            closer = far(a) < far(b)
            high = np.where(closer, b, high)
            low = np.where(closer, low, a)
        best = np.minimum(best, far(0.5 * (low + high)))
    return best


class CurvePath:
    """
    A smooth curve ``p(phi)``, ``phi`` in [``start``, ``stop``], as a path.

    ``curve(phi)`` returns ``p``, ``dp/dphi``, ``d2p/dphi2`` ((n, 3));
    one piece, ``w = (phi - start) scale`` (about its length: the
    parameter need not be the arc length, toppra's problem is the same),
    at rest at both ends, G's speed within ``feed`` (m/s).
    """

    def __init__(self, curve, start, stop, scale, feed=math.inf):
        """Keep the curve and its parameter's range."""
        self.curve, self.first, self.scale = curve, start, scale
        self.pieces = (SimpleNamespace(length=(stop - start) * scale,
                                       feed=feed),)
        self.stops = np.array([True, True])

    def evaluate(self, index, w):
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` (the one piece)."""
        p, d1, d2 = self.curve(self.first + np.asarray(w) / self.scale)
        return p, d1 / self.scale, d2 / self.scale ** 2
