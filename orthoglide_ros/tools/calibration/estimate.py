"""
The calibration: nonlinear least squares of the legs' geometry, robustly.

:func:`calibrate` starts from the nominal robot and fits the parameters the
readings separate (:func:`identifiability.identifiable`) by scipy's
``least_squares``. Blunders (a beam break, a mistyped reading) are found
by robust statistics: a fit with a robust loss (soft L1, its scale the
median absolute studentized residual) names the rows beyond
BLUNDER_SIGMAS as candidates, each left out only if the fit without them
all predicts it that badly; then plain least squares leaves out, one at
a time, a row whose externally studentized residual still lies beyond
BLUNDER_SIGMAS. The standard errors follow from the noise the residuals
imply (doc/calibration.md#the-least-squares).
"""

from __future__ import annotations

from collections import namedtuple
import functools
import math
from typing import TYPE_CHECKING

import numpy as np

from orthoglide_ros.model.robot import ParameterError
from orthoglide_ros.tools.calibration import geometry
from orthoglide_ros.tools.calibration.identifiability import (
    BLUNDER_REDUNDANCY, identifiable, MIN_REDUNDANCY)
from orthoglide_ros.tools.calibration.measurements import (
    COORDINATES, Measurements, repeats, where)

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# A reading farther than this from where the nominal robot puts the
# platform (m, each coordinate) is no geometric error: the robot as built
# to 1 cm and 3 deg (robots_as_built.FAR) is at most 60 mm off in the
# workspace cube, a built Orthoglide about 7 mm.
MAX_DEVIATION = 0.1
# A row is a blunder where noise alone would give its residual with the
# probability of BLUNDER_SIGMAS standard deviations of a normal variable
# (2e-9): its studentized residual's F statistic beyond that quantile of
# F(readings of the row, readings to spare) (36 for one reading among
# many, 2068 for three against six to spare: few readings hide a blunder
# rather than name the noise one). The robust fits name candidates beyond
# BLUNDER_SIGMAS of their scale.
BLUNDER_SIGMAS = 6.0
# At most this share of the rows may be left out as blunders: more is no
# blunder but measurements of another robot, setup or frame.
MAX_LEFT_OUT = 0.2
# Robust fits, each with the scale of the last one's residuals.
ROBUST_ROUNDS = 3
# Evaluations of the residuals one least squares may make (a fit takes
# 5 to 20).
MAX_EVALUATIONS = 200
# Plain fits after the robust ones that may each leave out one blunder
# (one more fits what is left).
MAX_REFITS = 5
# The MAD's factor to the standard deviation of normal noise.
MAD_TO_SIGMA = 1.4826
# The least noise a reading is taken to have (m): 1 nm, a thousand times
# below a dial gauge's, a CMM's or a laser tracker's resolution (1-10 um)
# and above what the least squares leaves of exact readings (1e-12 m).
# The implied noise and the robust scale are at least this, so that
# exact readings name no row a blunder for residuals of rounding.
SIGMA_FLOOR = 1e-9
# The most noise a calibration's instrument has (m): ten times a laser
# tracker's or a dial gauge's (1-10 um). A fit that leaves more per
# reading is no calibration (a blunder the readings to spare could not
# find, the robot moved, another robot or frame): refused.
MAX_NOISE = 100e-6
# A reading whose leverage exceeds this is checked by no other: not judged.
MAX_LEVERAGE = 0.99
# How far off a reading is modelled where the legs tried do not assemble
# (m): far, finite.
_NOT_FOUND = 1.0

Calibration = namedtuple('Calibration', (
    'robot', 'params', 'identifiability', 'deviation', 'std', 'frame',
    'kept', 'left_out', 'before', 'after', 'rms_before', 'rms_after',
    'sigma', 'readings', 'notes'))
Calibration.__doc__ = """What :func:`calibrate` found.

``robot``: the calibrated :class:`Robot` (the nominal one's other rows
kept); ``params``: the :class:`geometry.Parameter` s (30, or 36 with an
instrument); ``identifiability``: what the readings separate; per
parameter ``deviation`` (m, rad; 0 where held) and ``std`` (its standard
error, NaN where held); ``frame``: the map into the instrument's frame
(:class:`geometry.Frame`, the identity without an instrument); ``kept``
(bool per row) and ``left_out``: ``(row, largest residual (m), column)``
per blunder; ``before`` and ``after`` (N, 3): each reading's residual
(measured less modelled, m, NaN where not measured) of the nominal robot
(with the instrument's frame fitted to it) and of the calibrated one;
``rms_before`` and ``rms_after`` (m) over the kept readings; ``sigma``:
the noise the residuals imply, ``sqrt(RSS / (n - k))``, at least
SIGMA_FLOOR (m); ``readings``:
the kept readings ``n``; ``notes``: what the data did not allow, as
sentences.
"""


class CalibrationError(ValueError):
    """Measurements that give no calibration; the message says why."""


def calibrate(nominal: Robot, data: Measurements,
              instrument: bool = False) -> 'Calibration':
    """
    Calibrate the legs of ``nominal`` to the measurements ``data``.

    ``instrument``: the readings are in the instrument's own frame, whose
    pose is identified with the geometry (it starts from the rigid fit of
    the nominal robot's positions to the rows measured in x, y, z, three
    at least). Raises :class:`CalibrationError`.
    """
    params = geometry.parameters(instrument)
    problem = _Problem(nominal, data, _start(nominal, data, instrument))
    _check_deviations(problem, data)
    kept = np.ones(len(data.lines), dtype=bool)
    problem.identify(kept)
    deviation, candidates = _robust_candidates(problem, kept)
    if candidates:      # left out where the rows without them confirm it
        trial = kept.copy()
        trial[candidates] = False
        try:
            problem.identify(trial)
        except CalibrationError:    # too few without them to judge
            candidates = []
    if candidates:
        fitted = _fit(problem, deviation, trial)
        confirmed = [row for row, score in zip(candidates, _predicted(
            problem, fitted, trial, candidates)) if score > 1.0]
        if confirmed:
            kept[confirmed] = False
            _check_left_out(data, kept)
            deviation = fitted
    for refit in range(MAX_REFITS + 1):     # the last one leaves none out
        found = problem.identify(kept)
        deviation = _fit(problem, deviation, kept)
        row = _worst_row(problem, deviation, kept) \
            if refit < MAX_REFITS else None
        if row is None:
            break
        kept[row] = False
        _check_left_out(data, kept)
    residual = problem.residuals(deviation, kept)
    dof = len(residual) - len(problem.free)
    sigma = max(math.sqrt(float(residual @ residual) / dof), SIGMA_FLOOR)
    after = problem.residual_table(deviation)
    if sigma > MAX_NOISE:
        raise CalibrationError(_too_noisy(data, after, kept, sigma, dof))
    std = np.full(len(params), math.nan)
    std[problem.free] = sigma * np.sqrt(np.diag(np.linalg.inv(
        _normal(problem, deviation, kept))))
    try:
        robot = geometry.calibrated_robot(nominal, deviation)
    except ParameterError as error:
        raise CalibrationError(f'{data.source}: the calibrated legs are no '
                               f'robot ({error})') from None
    before = problem.residual_table(np.zeros(len(params)))
    left_out = tuple(
        (int(row), float(after[row, column]), column)
        for row in np.flatnonzero(~kept)
        for column in [int(np.nanargmax(np.abs(after[row])))])
    notes = [f'line {data.lines[row]} repeats line {data.lines[earlier]} '
             'exactly: counted as two measurements (a quantised instrument '
             'reads a position again alike; a row pasted twice would count '
             'twice too)' for row, earlier in repeats(data)]
    if len(found.identified) < found.separable:
        notes.append(
            f'{found.readings} readings: {len(found.identified)} of the '
            f'{found.separable} values these positions separate identified '
            f'(a fit keeps {MIN_REDUNDANCY} readings more than it '
            f'identifies); measure {found.separable - len(found.identified)}'
            ' more coordinates to identify all')
    if dof < BLUNDER_REDUNDANCY:
        notes.append(f'{dof} readings to spare: too few to find a blunder '
                     f'reliably ({BLUNDER_REDUNDANCY} or more do); '
                     f'{_more(dof)}')
    frame = geometry.instrument_map(problem.start, deviation[30:]) \
        if instrument else geometry.IDENTITY
    return Calibration(
        robot, params, found, deviation, std, frame, kept, left_out,
        before, after, _rms(before[kept]), _rms(after[kept]), sigma,
        len(residual), tuple(notes))


class _Problem:
    """The measurements and the model: residuals and Jacobians by subset."""

    def __init__(self, nominal, data, start):
        self.data = data
        self.legs = nominal.legs
        self.lam = data.lambdas
        self.values = data.readings
        self.mask = ~np.isnan(data.readings)
        self.start = start
        self.scale = np.array([p.scale for p in geometry.parameters(
            start is not None)])
        self.free = None
        self.size = len(self.scale)
        self.nominal_columns = None

    def identify(self, kept):
        """
        Find what the kept rows separate: the free values from now on.

        At the nominal robot (the parameters' Jacobian there); refuses
        readings too few to identify anything. Returns the
        :class:`identifiability.Identifiability`.
        """
        if self.nominal_columns is None:
            self.nominal_columns = self.columns(np.zeros(self.size))
        found = identifiable(self.nominal_columns[self.mask & kept[:, None]],
                             geometry.parameters(self.start is not None))
        if not found.identified:
            raise CalibrationError(
                f'{self.data.source}: {found.readings} readings: too few to '
                f'identify anything (at least {MIN_REDUNDANCY + 1}: one '
                f'value and {MIN_REDUNDANCY} more to estimate the noise)')
        self.free = np.array(found.identified)
        return found

    def model(self, deviation):
        """Return the modelled readings (N, 3), _NOT_FOUND off where none."""
        readings, found = geometry.measured(self.legs, self.lam, deviation,
                                            self.start)
        return np.where(found[:, None], readings, self.values + _NOT_FOUND)

    def residual_table(self, deviation):
        """Return measured less modelled (N, 3), NaN where not measured."""
        return np.where(self.mask, self.values - self.model(deviation),
                        math.nan)

    def residuals(self, deviation, kept):
        """Return the kept readings' modelled less measured values (m)."""
        return (self.model(deviation) - np.nan_to_num(self.values))[
            self.mask & kept[:, None]]

    def columns(self, deviation):
        """Return the readings' Jacobian (N, 3, p), m per m or rad."""
        return geometry.jacobian(self.legs, self.lam, deviation, self.start)

    def free_columns(self, deviation, kept):
        """Return the kept readings' Jacobian (n, k) of the free values."""
        return self.columns(deviation)[self.mask & kept[:, None]][
            :, self.free]


def _start(nominal, data, instrument):
    """Return the instrument's frame fitted to the nominal robot, or None."""
    if not instrument:
        return None
    full = ~np.isnan(data.readings).any(1)
    position, _ = geometry.measured(nominal.legs, data.lambdas[full],
                                    np.zeros(30))
    if full.sum() < 3 or np.linalg.matrix_rank(
            position - position.mean(0), tol=1e-3) < 2:
        raise CalibrationError(
            f'{data.source}: --frame instrument needs three rows at least '
            'measured in x, y and z at positions not on a line, to find '
            f'the instrument\'s frame; {int(full.sum())} row(s) are')
    return geometry.rigid_fit(position, data.readings[full])


def _check_deviations(problem, data):
    """Refuse a reading farther than MAX_DEVIATION from the nominal robot's."""
    residual = problem.residual_table(np.zeros(problem.size))
    far = np.nan_to_num(np.abs(residual)) > MAX_DEVIATION
    if far.any():
        row, column = np.unravel_index(int(np.argmax(np.where(
            far, np.abs(residual), 0.0))), far.shape)
        frame = ('the instrument\'s frame fitted to the rows' if
                 problem.start is not None else 'the base frame; '
                 'an instrument in its own frame needs --frame instrument')
        # In m from 1 m on: a reading near the largest double (1e308)
        # has no value in mm.
        distance = abs(float(residual[row, column]))
        raise CalibrationError(
            f'{where(data, row, COORDINATES[column])}: '
            f'{data.readings[row, column]:.6g} m is '
            + (f'{1e3 * distance:.4g} mm' if distance < 1.0
               else f'{distance:.4g} m') + ' from where the '
            f'nominal robot puts the platform, beyond the '
            f'{1e3 * MAX_DEVIATION:g} mm geometric errors can explain '
            f'(units m; {frame})')


def _fit(problem, deviation, kept, loss='linear', f_scale=1.0):
    """
    Return the least squares' deviation from ``deviation`` on the kept rows.

    Its free values only, solved in units of their scale (1 mm, 1 mrad);
    the others as in ``deviation``.
    """
    from scipy.optimize import least_squares
    free, scale = problem.free, problem.scale[problem.free]

    def full(x):
        out = deviation.copy()
        out[free] = x * scale
        return out
    result = least_squares(
        lambda x: problem.residuals(full(x), kept), deviation[free] / scale,
        jac=lambda x: problem.free_columns(full(x), kept) * scale,
        method='trf', loss=loss, f_scale=f_scale, xtol=1e-12, ftol=1e-12,
        gtol=1e-12, max_nfev=MAX_EVALUATIONS)
    if result.status == 0:
        raise CalibrationError(
            f'{problem.data.source}: the least squares did not converge in '
            f'{MAX_EVALUATIONS} evaluations: are the measurements of this '
            'robot (--params), in its base frame (or --frame instrument)?')
    return full(result.x)


def _normal(problem, deviation, kept):
    """Return ``J^T J`` of the free values on the kept rows."""
    jac = problem.free_columns(deviation, kept)
    return jac.T @ jac


def _robust_candidates(problem, kept):
    """
    Return a robust fit's deviation and the rows it calls blunders.

    Least squares, then ROBUST_ROUNDS soft-L1 fits, each with the robust
    standard deviation of the last one's studentized residuals as the
    loss's scale; a candidate is a row with a studentized residual beyond
    BLUNDER_SIGMAS of it, the largest first, MAX_LEFT_OUT of the rows at
    most. None where the readings leave fewer than MIN_REDUNDANCY to
    judge by. With few readings to spare the scale comes out small and
    names rows the noise explains: a candidate is only that.
    """
    deviation = _fit(problem, np.zeros(problem.size), kept)
    rows = np.nonzero(problem.mask & kept[:, None])[0]
    if len(rows) - len(problem.free) < MIN_REDUNDANCY:
        return deviation, []
    for robust_round in range(ROBUST_ROUNDS + 1):
        jac = problem.free_columns(deviation, kept)
        leverage = np.einsum('ij,ij->i', jac @ np.linalg.inv(jac.T @ jac),
                             jac)
        judged = leverage < MAX_LEVERAGE
        studentized = np.abs(problem.residuals(deviation, kept))[judged] \
            / np.sqrt(1.0 - leverage[judged])
        scale = max(MAD_TO_SIGMA * float(np.median(studentized)),
                    SIGMA_FLOOR)
        if robust_round == ROBUST_ROUNDS:
            break
        deviation = _fit(problem, deviation, kept, 'soft_l1', scale)
    order = np.argsort(-studentized)
    beyond = rows[judged][order][studentized[order] > BLUNDER_SIGMAS * scale]
    return deviation, list(dict.fromkeys(int(row) for row in beyond))[
        :int(MAX_LEFT_OUT * len(kept))]


def _beyond(statistic, readings, spare):
    """Return an F statistic over its blunder quantile (above 1: a blunder)."""
    return statistic / _quantile(readings, spare)


@functools.lru_cache(maxsize=256)
def _quantile(readings, spare):
    """
    Return the blunder quantile of F(``readings``, ``spare``).

    What noise exceeds with the probability of BLUNDER_SIGMAS standard
    deviations of a normal variable, ``alarm = erfc(6 / sqrt(2))``: with
    ``P(F > x) = I_z(spare / 2, readings / 2)``, ``z = spare / (spare +
    readings x)`` (the regularized incomplete beta function, inverted by
    scipy's ``betaincinv``).
    """
    from scipy.special import betaincinv
    alarm = math.erfc(BLUNDER_SIGMAS / math.sqrt(2.0))
    z = float(betaincinv(0.5 * spare, 0.5 * readings, alarm))
    return spare * (1.0 - z) / (readings * z)


def _predicted(problem, deviation, kept, rows):
    """
    Return how badly a fit without ``rows`` predicts each (:func:`_beyond`).

    ``F = e^T C^-1 e / (m sigma^2)``: ``e`` the row's m residuals, ``C =
    I + J_B (J^T J)^-1 J_B^T`` their prediction's covariance over
    ``sigma^2``, ``sigma`` the fit's noise of ``n - k`` readings to spare.
    """
    residual = problem.residuals(deviation, kept)
    spare = len(residual) - len(problem.free)
    if spare < 1:
        return [0.0] * len(rows)
    sigma2 = max(float(residual @ residual) / spare, SIGMA_FLOOR ** 2)
    inverse = np.linalg.inv(_normal(problem, deviation, kept))
    table = problem.residual_table(deviation)
    columns = problem.columns(deviation)
    out = []
    for row in rows:
        measured = problem.mask[row]
        e = table[row, measured]
        jac = columns[row][measured][:, problem.free]
        cov = np.eye(len(e)) + jac @ inverse @ jac.T
        out.append(_beyond(float(e @ np.linalg.solve(cov, e)) / len(e)
                           / sigma2, len(e), spare))
    return out


def _worst_row(problem, deviation, kept):
    """
    Return the row of the largest externally studentized residual, if a blunder.

    Row B's ``q = e_B^T (I - H_BB)^-1 e_B`` (H the hat matrix), ``sigma_B^2
    = (RSS - q) / (dof - m_B)`` (the fit without the row), the statistic
    ``F = q / (m_B sigma_B^2)`` against its quantile (:func:`_beyond`);
    None where none exceeds it or the readings leave fewer than
    MIN_REDUNDANCY to judge by. A row no other reading checks (leverage
    near 1) is not judged.
    """
    rows = np.nonzero(problem.mask & kept[:, None])[0]
    residual = problem.residuals(deviation, kept)
    dof = len(residual) - len(problem.free)
    if dof < MIN_REDUNDANCY:
        return None
    jac = problem.free_columns(deviation, kept)
    projected = jac @ np.linalg.inv(jac.T @ jac)
    total = float(residual @ residual)
    worst, score = None, 1.0
    for row in np.unique(rows):
        at = rows == row
        m = int(at.sum())
        e = residual[at]
        rest = np.eye(m) - projected[at] @ jac[at].T
        if np.linalg.eigvalsh(rest)[0] < 1.0 - MAX_LEVERAGE or dof <= m:
            continue
        q = float(e @ np.linalg.solve(rest, e))
        spread = max((total - q) / (dof - m), SIGMA_FLOOR ** 2)
        value = _beyond(q / m / spread, m, dof - m)
        if value > score:
            worst, score = int(row), value
    return worst


def _more(dof):
    """Say how many more readings give BLUNDER_REDUNDANCY to spare."""
    more = BLUNDER_REDUNDANCY - dof
    return (f'measure {more} more coordinates ({math.ceil(more / 3)} more '
            'positions in x, y and z)')


def _too_noisy(data, after, kept, sigma, dof):
    """
    Say why a fit that leaves more than MAX_NOISE is refused.

    With few readings to spare, a blunder the fit absorbed (its row's
    residual no longer the largest); else the largest residual's row.
    """
    if dof < BLUNDER_REDUNDANCY:
        why = f'with {dof} readings to spare a blunder may hide: {_more(dof)}'
    else:
        table = np.where(kept[:, None], np.abs(np.nan_to_num(after)), 0.0)
        row, column = np.unravel_index(int(np.argmax(table)), table.shape)
        why = ('measurements of another robot (--params), setup or frame '
               '(--frame instrument), or a robot that moved; the largest '
               f'residual: line {data.lines[row]}, column '
               f'{COORDINATES[column]!r} ({1e3 * after[row, column]:+.4g} '
               'mm)')
    return (f'{data.source}: the calibrated robot leaves '
            f'{1e6 * sigma:.4g} um of noise per reading (sqrt(RSS / (n - '
            f'k))), beyond any instrument a calibration uses '
            f'({1e6 * MAX_NOISE:g} um): {why}')


def _check_left_out(data, kept):
    """Refuse when more than MAX_LEFT_OUT of the rows disagree."""
    out = int((~kept).sum())
    if out > MAX_LEFT_OUT * len(kept):
        raise CalibrationError(
            f'{data.source}: {out} of {len(kept)} rows disagree with the '
            f'others beyond {BLUNDER_SIGMAS:g} standard deviations: more '
            f'than {100 * MAX_LEFT_OUT:g} % are no blunders but '
            'measurements of another robot (--params), setup or frame '
            '(--frame instrument)')


def _rms(table):
    """Return the RMS of a residual table's measured readings (m)."""
    values = table[~np.isnan(table)]
    return float(np.sqrt(np.mean(values * values))) if len(values) else 0.0
