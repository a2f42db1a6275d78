"""
A log on uniform grids, filtered as the least squares need it.

:class:`Motion` cuts a log at its gaps onto uniform grids and filters,
trims and decimates alike everything computed from it (eq. 14 from the
measured ``lambda``); :func:`prepare` gives the :class:`Samples` of one
law, :func:`estimate_lag` the forces' delay
(doc/identification.md#the-filter).
"""

from __future__ import annotations

from typing import Callable, Optional, Sequence, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.formats.logs import check_log, LogError
from orthoglide_ros.model import mechanics
from orthoglide_ros.tools.identification.laws import (
    acting, columns as own_columns, diagonal, PLAIN)
from orthoglide_ros.tools.identification.regressor import rigid_columns
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.formats.logs import Log
    from orthoglide_ros.model.robot import Robot
    from orthoglide_ros.model.terms import Term
    from orthoglide_ros.tools.identification.laws import Law

# The filter and the grid (doc/identification.md#the-filter): a
# Butterworth low-pass of FILTER_ORDER at DEFAULT_CUTOFF (Hz), zero phase,
# on the forces and W's columns; the motion through the same design at
# STATE_CUTOFF_FACTOR times the cutoff, at most STATE_CUTOFF_SHARE of the
# rate; a gap longer than GAP_FACTOR median periods and GAP_SHARE / cutoff
# splits the log.
DEFAULT_CUTOFF = 10.0
FILTER_ORDER = 4
STATE_CUTOFF_FACTOR = 5.0
STATE_CUTOFF_SHARE = 0.4
GAP_FACTOR = 3.0
GAP_SHARE = 0.1
# A step between two samples longer than this many median periods is a
# missing sample (interpolated inside a segment; counted in the report).
MISSING_FACTOR = 1.5
# The drive's lag (the forces' delay on the states' stamps), when it is
# not given: searched within +-LAG_SEARCH s, first on the log's period,
# then on a quarter of it around the best, and refined by a parabola
# through the three best (doc/identification.md).
LAG_SEARCH = 0.01
LAG_STEPS = 4
# The largest speed (m/s) and acceleration (m/s^2) of the platform a log
# may show, per axis: the largest max_speed and max_acceleration the
# feedforward accepts. Beyond them the stamps are not in seconds or the
# log is not a robot's, and the forces computed from such a motion would
# leave the finite numbers.
MOTION_LIMITS = (('speed', 1e3, 'm/s'), ('acceleration', 1e5, 'm/s^2'))
Samples = namedtuple('Samples', (
    'times', 'regressor', 'forces', 'segments', 'rate', 'law', 'lambdas',
    'lambdadots', 'coverage'), defaults=(PLAIN, None, None, None))
Samples.__doc__ = """A log prepared for identification (:func:`prepare`).

(N,) times (s), the regressor ``W`` (N, 3, n) of the standard parameters
of ``law`` and the forces (N, 3) (N), both through the same low-pass;
``segments``: how many pieces of the log they come from; ``rate``: their
sampling rate after the decimation (Hz); ``lambdas`` (m) and
``lambdadots`` (m/s): (N, 3), the motion at those samples (through the
motion's low-pass); ``coverage``: what of the log was used
(:class:`Coverage`).
"""

Coverage = namedtuple('Coverage', (
    'log_s', 'used_s', 'segments', 'gaps', 'longest_gap_s', 'short_pieces',
    'missing'))
Coverage.__doc__ = """What of a log :func:`prepare` used.

``log_s``: the log's span (s); ``used_s``: the span of the samples used,
segment by segment (s); ``segments``: how many; ``gaps``: the gaps that
split the log, the longest ``longest_gap_s`` (s); ``short_pieces``: pieces
between gaps too short to filter (dropped); ``missing``: samples missing
inside the segments (steps longer than MISSING_FACTOR periods,
interpolated).
"""

Piece = namedtuple('Piece', ('grid', 'stamps', 'forces', 'position',
                             'velocity', 'acceleration', 'lambdas',
                             'lambdadot', 'lambdaddot', 'rigid'))


class Motion:
    """
    A log on uniform grids, piece by piece between its gaps (:func:`prepare`).

    Holds each piece's motion and the masses' columns of ``W`` at the
    log's rate, and filters, trims and decimates whatever is computed from
    them alike (:meth:`filtered`): the forces at any lag (:meth:`forces`),
    a term's columns at any Stribeck speed (:meth:`own_columns`), a law's
    whole ``W`` (:meth:`columns`), a robot's forces
    (:meth:`model_forces`).
    """

    def __init__(self, robot: Robot, log: Log,
                 cutoff: float = DEFAULT_CUTOFF) -> None:
        """Check and cut ``log``; raises :class:`LogError` (see prepare)."""
        import scipy.signal
        self._signal = scipy.signal
        check_log(log)
        self.robot = robot
        self.source = log.source
        times = np.asarray(log.times, dtype=float)
        lambdas = np.asarray(log.lambdas, dtype=float)
        forces = np.asarray(log.forces, dtype=float)
        measured = None if log.lambdadots is None else np.asarray(
            log.lambdadots, dtype=float)
        self.period = period = float(np.median(np.diff(times)))
        rate = 1.0 / period
        if not 0.0 < cutoff < 0.5 * rate:
            raise LogError(f'{log.source}: the cutoff {cutoff:g} Hz must lie '
                           f'in (0, {0.5 * rate:g}) Hz, half the sampling '
                           f'rate {rate:g} Hz')
        span = float(times[-1] - times[0])
        if not 4.0 / cutoff < span:
            raise LogError(f'{log.source}: no piece of the log lasts more '
                           f'than {4.0 / cutoff:.3g} s (4 / cutoff, the '
                           f'cutoff {cutoff:g} Hz): it lasts {span:.3g} s')
        self.cutoff = cutoff
        self.sos = scipy.signal.butter(FILTER_ORDER, cutoff, fs=rate,
                                       output='sos')
        state_sos = scipy.signal.butter(
            FILTER_ORDER, min(STATE_CUTOFF_FACTOR * cutoff,
                              STATE_CUTOFF_SHARE * rate), fs=rate,
            output='sos')
        # (1e-9: a median period rounded up must not change these counts.)
        trim = int(math.ceil(2.0 * rate / cutoff * (1.0 - 1e-9)))
        self.step = max(1, int(rate / (2.0 * cutoff) * (1.0 + 1e-9)))
        self.rate = rate / self.step
        steps = np.diff(times)
        breaks = np.flatnonzero(steps > max(GAP_FACTOR * period,
                                            GAP_SHARE / cutoff)) + 1
        self.pieces, self.inner, short = [], [], 0
        for start, end in zip(np.r_[0, breaks], np.r_[breaks, len(times)]):
            t = times[start:end]
            grid = t[0] + period * np.arange(
                int(math.floor((t[-1] - t[0]) / period + 1e-9)) + 1)
            if len(grid) < 2 * trim + 3 * (2 * len(self.sos) + 1):
                short += 1
                continue

            def on_grid(values):
                return np.column_stack([np.interp(grid, t, values[:, j])
                                        for j in range(3)])
            try:
                position = scipy.signal.sosfiltfilt(
                    state_sos, mechanics.forward_kinematics(
                        robot, on_grid(lambdas[start:end])), axis=0)
                if measured is None:
                    velocity = np.gradient(position, period, axis=0)
                else:
                    j1, j2 = mechanics.jacobians(robot, position)
                    velocity = np.linalg.solve(
                        j2, j1 @ scipy.signal.sosfiltfilt(
                            state_sos, on_grid(measured[start:end]),
                            axis=0)[:, :, None])[:, :, 0]
                acceleration = np.gradient(velocity, period, axis=0)
                _check_motion(log.source, grid, velocity, acceleration)
                rigid, reference = rigid_columns(robot, position, velocity,
                                                 acceleration)
            except mechanics.WorkspaceError as error:
                raise LogError(f'{log.source}: the motion at t = '
                               f'{grid[error.row]:.6g} s: {error}') from None
            self.pieces.append(Piece(
                grid, t, forces[start:end], position, velocity, acceleration,
                reference.lambda_, reference.lambdadot,
                reference.lambdaddot, rigid))
            self.inner.append(slice(trim, len(grid) - trim, self.step))
        if not self.pieces:
            raise LogError(f'{log.source}: no piece of the log lasts more '
                           f'than {2 * trim * period:.3g} s (4 / cutoff) '
                           'between gaps')
        inside = np.ones(len(steps), dtype=bool)
        inside[breaks - 1] = False
        self.coverage = Coverage(
            float(times[-1] - times[0]),
            float(sum(p.grid[i][-1] - p.grid[i][0]
                      for p, i in zip(self.pieces, self.inner))),
            len(self.pieces), len(breaks),
            float(steps[breaks - 1].max()) if len(breaks) else 0.0, short,
            int(np.round(steps[inside & (steps > MISSING_FACTOR * period)]
                         / period - 1.0).sum()))
        self.times = self.kept([p.grid for p in self.pieces])
        self.rigid = self.filtered([p.rigid for p in self.pieces])
        self._own = {}

    def kept(self, arrays: Sequence[Array]) -> Array:
        """Return the samples kept of per-piece arrays, joined."""
        return np.concatenate([a[i] for a, i in zip(arrays, self.inner)])

    def filtered(self, arrays: Sequence[Array]) -> Array:
        """Return per-piece arrays (n, ...) low-passed, trimmed, decimated."""
        return self.kept([self._signal.sosfiltfilt(
            self.sos, a.reshape(len(a), -1), axis=0).reshape(a.shape)
            for a in arrays])

    def forces(self, lag: float = 0.0) -> Array:
        """Return the forces taken as applied ``lag`` s before their stamps."""
        return self.filtered([np.column_stack([
            np.interp(p.grid, p.stamps - lag, p.forces[:, j])
            for j in range(3)]) for p in self.pieces])

    def columns(self, law: Law,
                stribeck_velocity: Optional[float] = None) -> Array:
        """Return ``W`` (M, 3, n) of ``law`` along the motion (kept)."""
        robot = self.robot if stribeck_velocity is None else \
            self.robot.replace(friction_stribeck_velocity=stribeck_velocity)
        return np.concatenate([self.rigid] + [
            diagonal(self.own_columns(term, law, robot))
            for term in law.columns_order()], axis=2)

    def own_columns(self, term: Term, law: Law,
                    robot: Optional[Robot] = None) -> Array:
        """
        Return ``term``'s filtered columns (M, 3) in ``law`` (kept).

        Each actuator's own (:func:`laws.columns`) along the piece's
        ``lambda`` (the screw ripple's phase), ``lambdadot`` and
        ``lambdaddot``: that one series is filtered. ``robot`` (default
        the motion's) gives the parameters of the term's other rows (the
        Stribeck speed searched, the screw's lead).
        """
        robot = robot or self.robot
        members = acting(term, law)
        key = (term.name, tuple(t.name for t in members), tuple(
            getattr(robot, row.name) for t in members for row in t.rows[1:]))
        if key not in self._own:
            self._own[key] = self.filtered([
                own_columns(robot, term, law, p.lambdas, p.lambdadot,
                            p.lambdaddot) for p in self.pieces])
        return self._own[key]

    def model_forces(self, robot: Robot) -> Array:
        """
        Return ``robot``'s forces along the motion (the full model).

        Raises :class:`LogError` where the model cannot give them.
        """
        forces = []
        for p in self.pieces:
            try:
                forces.append(mechanics.solve_batch(
                    robot, p.position, p.velocity, p.acceleration).force)
            except mechanics.WorkspaceError as error:
                raise LogError(f'{self.source}: the motion at t = '
                               f'{p.grid[error.row]:.6g} s: {error}') \
                    from None
        return self.filtered(forces)

    def samples(self, regressor: Optional[Array], forces: Array,
                law: Law = PLAIN) -> 'Samples':
        """Return the :class:`Samples` of a regressor and forces."""
        return Samples(self.times, regressor, forces, len(self.pieces),
                       self.rate, law,
                       self.kept([p.lambdas for p in self.pieces]),
                       self.kept([p.lambdadot for p in self.pieces]),
                       self.coverage)


def prepare(robot: Robot, log: Log, cutoff: float = DEFAULT_CUTOFF,
            force_lag: float = 0.0, law: Law = PLAIN) -> 'Samples':
    """
    Turn a :class:`Log` into :class:`Samples` for the least squares.

    The log is checked (:func:`check_log`), split at gaps longer than
    GAP_FACTOR median periods and GAP_SHARE / cutoff, each segment put on a
    uniform grid, the forces taken ``force_lag`` s before their stamps; then
    the motion through ``H_s`` (STATE_CUTOFF_FACTOR x ``cutoff``, at most
    STATE_CUTOFF_SHARE of the rate), ``W`` of ``law`` at every sample, the
    forces and ``W`` through ``H`` (``cutoff``, order FILTER_ORDER), edges
    dropped and decimated (doc/identification.md#the-filter).

    Raises :class:`LogError`.
    """
    motion = Motion(robot, log, cutoff)
    check_lag(log.source, force_lag, cutoff)
    return motion.samples(motion.columns(law), motion.forces(force_lag), law)


def _check_motion(source, grid, velocity, acceleration):
    """Refuse a motion beyond MOTION_LIMITS, naming when (LogError)."""
    for (name, limit, unit), values in zip(MOTION_LIMITS,
                                           (velocity, acceleration)):
        k, j = np.unravel_index(np.argmax(np.abs(values)), values.shape)
        if not abs(values[k, j]) <= limit:
            raise LogError(
                f'{source}: the platform\'s {name} along {"xyz"[j]} reaches '
                f'{values[k, j]:.4g} {unit} at t = {grid[k]:.6g} s, beyond '
                f'the {limit:g} {unit} a robot may have: are the times in '
                'seconds and lambda in metres?')


def check_lag(source: str, force_lag: float, cutoff: float) -> None:
    """Refuse a force lag (s) not shorter than 1 / cutoff (LogError)."""
    if not (math.isfinite(force_lag) and abs(force_lag) < 1.0 / cutoff):
        raise LogError(f'{source}: the force lag {force_lag:g} s must be '
                       f'shorter than 1 / cutoff = {1.0 / cutoff:g} s')


def estimate_lag(motion: Motion, residual: Callable[[Array], float]) -> float:
    """
    Return the lag (s) of the forces that minimizes ``residual(forces)``.

    ``motion``: a :class:`Motion`; ``residual``: the sum of squares left
    by filtered forces (N, 3). Searched within +-LAG_SEARCH (less than 1 /
    cutoff), on the log's period, then on a quarter of it around the best,
    then the vertex of a parabola through the three best.
    """
    period = motion.period
    reach = min(LAG_SEARCH, 0.5 / motion.cutoff)
    cache = {}

    def cost(lag):
        key = round(lag / period * LAG_STEPS)
        if key not in cache:
            cache[key] = residual(motion.forces(key * period / LAG_STEPS))
        return cache[key]
    coarse = int(reach / period)
    best = min(range(-coarse, coarse + 1), key=lambda k: cost(k * period))
    fine = min(range(best * LAG_STEPS - LAG_STEPS + 1,
                     best * LAG_STEPS + LAG_STEPS),
               key=lambda k: cost(k * period / LAG_STEPS))
    h = period / LAG_STEPS
    left, middle, right = (cost((fine + d) * h) for d in (-1, 0, 1))
    curvature = left - 2.0 * middle + right
    shift = 0.5 * (left - right) / curvature if curvature > 0.0 else 0.0
    return (fine + max(-1.0, min(1.0, shift))) * h
