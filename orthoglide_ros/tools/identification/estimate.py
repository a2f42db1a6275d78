"""
The estimate: the lag, the law, the least squares, the identified robot.

:func:`identify` takes a log and the nominal robot; what the nominal robot
knows and the law leaves out (the payload, the drives) is known force,
taken off the measured forces
(doc/identification.md#least-squares-and-statistics).
"""

from __future__ import annotations

from typing import Optional, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.tools.identification.laws import (
    Law, LAWS, law_name, LOWER, MASSES, standard_names, standard_parameters,
    UNITS, with_parameters)
from orthoglide_ros.tools.identification.motion import (
    check_lag, DEFAULT_CUTOFF, estimate_lag, Motion)
from orthoglide_ros.tools.identification.regressor import base_of
from orthoglide_ros.formats.logs import LogError
from orthoglide_ros.model import terms
from orthoglide_ros.model.robot import ROW
from orthoglide_ros.model.terms import STRIBECK
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.formats.logs import Log
    from orthoglide_ros.model.robot import Robot
    from orthoglide_ros.tools.identification.regressor import Base

# Fewest samples the least squares may use, per base parameter.
MIN_SAMPLES_PER_PARAMETER = 10
# A base parameter whose relative standard deviation (%) exceeds this is
# not excited by the log: it is held at its nominal value unless the log
# needs it (see identify). Well excited parameters come out at a few % at
# most (doc/identification.md).
MAX_RELATIVE_STD = 10.0
# The relative standard deviation of a base parameter is taken against the
# larger of its estimate and this resolution (by the unit of its carrier),
# so that a parameter that is zero (a robot without friction) is judged by
# its deviation: a slider friction below 1 N (or 1 N s/m, 0.4 N at the
# excitation's 0.4 m/s) or a mass below 10 g hardly matters to forces of
# tens to hundreds of N.
RESOLUTION = {'kg': 0.01, 'N s/m': 1.0, 'N': 1.0}
# The Stribeck speeds v_b searched (m/s): log-spaced STRIBECK_STEP apart (the
# spacing of 12 speeds from 2 to 100 mm/s), from the nominal robot's Coulomb
# smoothing speed friction_velocity (below it a Stribeck excess is one more
# Coulomb switch) to the log's largest slider speed (above it the excess is a
# Coulomb level less a term in v^2 that the log cannot tell from a larger
# v_b); the best is refined between its neighbours (stribeck_velocities).
STRIBECK_STEP = 50.0 ** (1.0 / 11.0)
# The law is chosen by the RMS error on held-out parts of the log (FOLDS
# contiguous blocks, each predicted from the others): a law with more
# terms is chosen only when it lowers that error by more than
# SELECTION_MARGIN of it. The same margin decides whether parameters the
# log does not excite are held at their nominal values.
FOLDS = 5
SELECTION_MARGIN = 0.02
# An unexcited base parameter is held at its nominal value only where the
# log is consistent with it: within this many standard deviations.
NOMINAL_SIGMAS = 3.0
# A payload is refused when the platform's own mass comes out this many
# standard deviations below its bound (see _check_payload).
PAYLOAD_SIGMAS = 3.0
# A refusal of a log whose gaps left less than this share usable names the
# gaps first.
GAP_LOSS = 0.8
# The index of the platform's mass among the rigid columns.
_PLATFORM = MASSES.index('m5')

Candidate = namedtuple('Candidate', ('law', 'stribeck_velocity',
                                     'held_out_rms'))
Candidate.__doc__ = """A law tried by :func:`identify`: its Stribeck speed
(m/s, the best searched; None without the term) and its RMS error (N) on
held-out parts of the log."""

Identification = namedtuple('Identification', (
    'base', 'values', 'nominal', 'std', 'relative_std', 'condition',
    'residual_rms', 'force_rms', 'samples', 'predicted', 'robot', 'notes',
    'law', 'stribeck_velocity', 'force_lag', 'lag_estimated', 'candidates',
    'law_chosen', 'bounded', 'held', 'payload'))
Identification.__doc__ = """What :func:`identify` found.

Per base parameter: ``values`` (identified, or nominal where held),
``nominal`` (of the nominal robot), ``std`` and ``relative_std`` (%,
``100 std / max(|value|, resolution)``, RESOLUTION, of the fit with every
parameter free); ``condition``: of the base regressor with unit-norm
columns; ``residual_rms`` and ``force_rms``: per actuator (N), of the
residual and of the filtered forces; ``samples``: the :class:`Samples`
used; ``predicted``: the forces (N, 3) the identified parameters give for
them (the known forces included); ``robot``: the identified
:class:`Robot` (:func:`split`); ``notes``: what the split rule had to do
beyond the plain rule, as sentences; ``law``: the :class:`laws.Law` and
``stribeck_velocity`` its Stribeck speed (m/s, None without the term);
``force_lag`` (s) and ``lag_estimated`` (False: given); ``candidates``:
every law tried (:class:`Candidate`); ``law_chosen``: why ``law`` (a
sentence); ``bounded``: the base parameters the bounded least squares held
at a bound, as sentences; ``held``: what the log did not excite and what
was done with it, as sentences (a tuple of the indices held at nominal is
``held.indices``); ``payload``: the payload (kg) the log was recorded with.
"""


class IdentificationError(ValueError):
    """An identification that cannot give a robot; the message says why."""


class Held(tuple):
    """Sentences about the parameters a log did not excite; ``indices``."""

    def __new__(cls, sentences=(), indices=()):
        """Keep the sentences; ``indices``: the base parameters held."""
        held = super().__new__(cls, sentences)
        held.indices = tuple(indices)
        return held


def identify(robot: Robot, log: Log, cutoff: float = DEFAULT_CUTOFF,
             base: Optional[Base] = None, force_lag: Optional[float] = None,
             max_relative_std: float = MAX_RELATIVE_STD,
             friction: Optional[Law] = None,
             stribeck_velocity: Optional[float] = None,
             payload: Optional[float] = None) -> 'Identification':
    """
    Identify the base parameters from a :class:`Log` (an Identification).

    ``robot``: the nominal robot (its geometry, gravity and
    ``friction_velocity`` are taken as known; its masses, drives and
    friction are the nominal values); ``cutoff`` (Hz): of the low-pass;
    ``force_lag`` (s): None to estimate it; ``friction``: the
    :class:`laws.Law`, None to choose it (see the module docstring);
    ``stribeck_velocity`` (m/s): given, or None to search it; ``base``: a
    :class:`regressor.Base` (its law is then the one used);
    ``max_relative_std`` (%): above it a base parameter is not excited;
    ``payload`` (kg): what the log was recorded with (None: the nominal
    robot's ``payload``), whose forces are taken off: the identified
    platform is the robot's own, and the robot returned keeps the nominal
    robot's payload.

    Raises :class:`LogError` for a log it cannot use (too short, no piece
    between gaps long enough) and :class:`IdentificationError` for one
    that shows no motion (no slider's friction is excited).
    """
    motion = Motion(robot, log, cutoff)
    payload = robot.payload if payload is None else float(payload)
    laws = (base.law,) if base is not None else (
        tuple(law for law in LAWS if _possible(robot, law))
        if friction is None else (friction,))
    _check_possible(robot, laws[0])
    # The laws the log has samples enough for (the simplest needs them).

    def parameters(law):
        return len((base or base_of(robot, law)).independent)
    fitting = [law for law in laws if len(motion.times)
               >= MIN_SAMPLES_PER_PARAMETER * parameters(law)]
    if not fitting:
        count = parameters(laws[0])
        raise LogError(f'{log.source}: {_gaps_prefix(motion)}'
                       f'{len(motion.times)} usable '
                       f'samples, at least {MIN_SAMPLES_PER_PARAMETER * count}'
                       f' needed ({MIN_SAMPLES_PER_PARAMETER} per base '
                       f'parameter, at {motion.rate:.4g} Hz after the '
                       'decimation)')
    laws = tuple(fitting)

    def known(law):
        """Return the forces the nominal robot knows and ``law`` leaves out."""
        forces = payload * motion.rigid[:, :, _PLATFORM]
        for term in terms.FORCES:
            if not term.friction and term not in law:
                forces = forces + motion.own_columns(term, (term,)) * np.array(
                    getattr(robot, terms.coefficient_name(term)))
        return forces

    grid = stribeck_velocities(robot, motion)
    if force_lag is None:
        richest = laws[-1]
        speeds = _speeds(richest, stribeck_velocity, grid)
        grams = [_residual_of(_base_columns(motion, richest, v))
                 for v in speeds]
        offset = known(richest)
        force_lag = estimate_lag(motion, lambda f: min(
            r(f - offset) for r in grams))
        lag_estimated = True
    else:
        check_lag(log.source, force_lag, cutoff)
        lag_estimated = False
    forces = motion.forces(force_lag)
    force_rms = np.sqrt(np.mean(forces ** 2, axis=0))
    candidates = [_candidate(motion, law, forces - known(law),
                             _speeds(law, stribeck_velocity, grid))
                  for law in laws]
    if len(laws) > 1:
        chosen, why = _chosen(candidates)
    else:
        chosen, why = candidates[0], f'{law_name(laws[0])}: as asked'
    law, speed = chosen.law, chosen.stribeck_velocity
    target = forces - known(law)
    if STRIBECK in law and stribeck_velocity is None:
        speed = _refined_speed(motion, law, target, speed, grid)
    base = base or base_of(robot, law)
    count = len(base.independent)
    w = motion.columns(law, speed)

    a = w[:, :, list(base.independent)].reshape(-1, count)
    y = target.reshape(-1)
    names = standard_names(law)
    nominal = base.matrix @ standard_parameters(robot, law)
    lower = bounds(base)
    units = [UNITS[names[j]] for j in base.independent]
    values, std, singular, bounded, found = _least_squares(
        a, y, lower, base.names, units)
    _check_payload(log.source, base, payload, found, std, lower)
    resolution = [RESOLUTION[unit] for unit in units]
    relative = 100.0 * std / np.maximum(np.abs(values), resolution)
    unexcited = np.flatnonzero(~(relative <= max_relative_std))
    moving = [i for i, j in enumerate(base.independent)
              if names[j].startswith('viscous_')]
    if moving and all(i in unexcited for i in moving):
        raise IdentificationError(
            f'{log.source}: {_gaps_prefix(motion)}the log shows no motion '
            'to identify from: no '
            'slider\'s friction is excited (relative standard deviations '
            + ', '.join(f'{base.names[i]} {relative[i]:.3g} %'
                        for i in moving)
            + '); record the robot following an excitation (orthoglide '
            'excitation)')
    held = Held()
    if len(unexcited):
        values, bounded, held = _held(a, y, lower, base, values, bounded,
                                      nominal, unexcited, std, relative,
                                      max_relative_std, names)
    held = Held(held + _left_out(robot, laws, law), held.indices)
    residual = y - a @ values
    robot_out, notes = split(robot, base, values, speed)
    return Identification(
        base, values, nominal, std, relative,
        float(singular[0] / singular[-1]),
        np.sqrt(np.mean(residual.reshape(-1, 3) ** 2, axis=0)), force_rms,
        motion.samples(w, forces, law),
        (a @ values).reshape(-1, 3) + known(law), robot_out, notes, law,
        speed, float(force_lag), lag_estimated, tuple(candidates), why,
        bounded, held, payload)


def _possible(robot, law):
    """Whether every term of ``law`` can act on some actuator of ``robot``."""
    return all(any(terms.acts(robot, term)) for term in law)


def _check_possible(robot, law):
    """Refuse a law with a term ``robot`` cannot have (IdentificationError)."""
    for term in law:
        if not any(terms.acts(robot, term)):
            needs = term.rows[0].needs
            raise IdentificationError(
                f'the law {law_name(law)} identifies the '
                f'{term.meaning.format("the sliders")}, which needs '
                f'robot.{needs}: the nominal robot (--params) has none on '
                'any actuator')


def _left_out(robot, laws, law):
    """
    Say which terms the nominal robot enabled the chosen law leaves out.

    A term whose coefficient ``needs`` a row of the nominal robot (the
    screw ripple its lead) was asked for: tried and not chosen, it keeps
    the nominal robot's values (the known forces), in one sentence each.
    """
    tried = {term for candidate in laws for term in candidate}
    return tuple(
        f'not in the law chosen, kept at the nominal robot\'s values: '
        f'{term.meaning.format("the sliders")} (robot.'
        f'{terms.coefficient_name(term)} '
        + ', '.join(f'{v:.4g}' for v in getattr(
            robot, terms.coefficient_name(term)))
        + f' {term.rows[0].unit})'
        for term in terms.FORCES if term in tried and term not in law
        and term.rows[0].needs)


def _held(a, y, lower, base, values, bounded, nominal, unexcited, std,
          relative, max_relative_std, names):
    """
    Hold the unexcited base parameters at nominal, unless the log needs them.

    A parameter the log places more than NOMINAL_SIGMAS of its standard
    deviations from its nominal value is not held: the log does not pin
    it down, but it does say that the nominal value is not the robot's
    (a viscous friction of 28 +- 6 N s/m on a robot whose nominal has
    none). The others one at a time, the least excited first (the
    essential-parameters method's order): a parameter is held when the
    held-out error with it (and those held before it) at the nominal value
    stays within SELECTION_MARGIN of the error so far; else it is kept as
    found. Returns ``(values, bounded, held)``.
    """
    def error(fixed):
        free = np.setdiff1d(np.arange(len(values)), fixed)
        return _held_out_rms(a[:, free], y - a[:, fixed] @ nominal[fixed],
                             lower[free])
    away = [i for i in unexcited
            if abs(values[i] - nominal[i]) > NOMINAL_SIGMAS * std[i]]
    held, current = [], error([])
    for i in sorted(unexcited, key=lambda i: -relative[i]):
        if i in away:
            continue
        trial = error(held + [i])
        if trial <= current * (1.0 + SELECTION_MARGIN):
            held, current = held + [i], min(current, trial)
    kept = [i for i in unexcited if i not in held and i not in away]

    def words(indices):
        return '; '.join(
            f'{base.names[i]} ({relative[i]:.3g} % relative deviation, '
            f'nominal {nominal[i]:.4g} {UNITS[names[base.independent[i]]]})'
            for i in indices)
    sentences = []
    if held:
        held = sorted(held)
        free = np.setdiff1d(np.arange(len(values)), held)
        some, _, _, bounded, _ = _least_squares(
            a[:, free], y - a[:, held] @ nominal[held], lower[free],
            [base.names[i] for i in free],
            [UNITS[names[base.independent[i]]] for i in free])
        values = nominal.copy()
        values[free] = some
        sentences.append(
            f'not excited by the log (above {max_relative_std:g} %), held '
            f'at the nominal value: {words(held)} (held-out error '
            f'{current:.4g} N)')
    if kept:
        sentences.append(
            f'poorly excited by the log (above {max_relative_std:g} %), '
            'kept as found since the held-out error needs it (more than '
            f'{100 * SELECTION_MARGIN:g} % higher at the nominal value): '
            + words(kept))
    if away:
        sentences.append(
            f'poorly excited by the log (above {max_relative_std:g} %), '
            f'kept as found since the log puts it more than '
            f'{NOMINAL_SIGMAS:g} standard deviations from its nominal value: '
            + words(away))
    return values, bounded, Held(sentences, held)


def stribeck_velocities(robot: Robot, motion: Motion) -> tuple[float, ...]:
    """
    Return the Stribeck speeds (m/s) searched along ``motion``.

    Log-spaced about STRIBECK_STEP apart from ``robot``'s
    ``friction_velocity`` to the largest slider speed of the samples used
    (at least one step above; within the speed's limits,
    ``robot.friction_stribeck_velocity``).
    """
    low = robot.friction_velocity
    speed = float(np.abs(motion.kept([p.lambdadot
                                      for p in motion.pieces])).max())
    high = min(max(speed, low * STRIBECK_STEP),
               ROW['friction_stribeck_velocity'].limits[1])
    count = int(math.ceil(math.log(high / low) / math.log(STRIBECK_STEP)
                          - 1e-9)) + 1
    return tuple(np.geomspace(low, high, max(count, 2)).tolist())


def _speeds(law, stribeck_velocity, grid):
    """Return the Stribeck speeds to try for ``law`` (None: no term)."""
    if STRIBECK not in law:
        return (None,)
    return (stribeck_velocity,) if stribeck_velocity is not None else grid


def _candidate(motion, law, target, speeds):
    """Return ``law``'s :class:`Candidate`: held-out RMS, best ``speeds``."""
    y = target.reshape(-1)
    lower = bounds(base_of(motion.robot, law))
    rms, speed = min((_held_out_rms(_base_columns(motion, law, v), y,
                                    lower), v) for v in speeds)
    return Candidate(law, speed, rms)


def _base_columns(motion, law, stribeck_velocity):
    """Return the base regressor (3N, n_base) of ``law`` along ``motion``."""
    base = base_of(motion.robot, law)
    w = motion.columns(law, stribeck_velocity)
    return w[:, :, list(base.independent)].reshape(-1, len(base.independent))


def _refined_speed(motion, law, target, speed, speeds):
    """
    Return the Stribeck speed of the least held-out error near ``speed``.

    Between the neighbours of ``speed`` in ``speeds`` (the grid searched),
    by Brent's bounded search on its logarithm (the grid is log-spaced).
    """
    from scipy.optimize import minimize_scalar
    grid = np.log(speeds)
    k = int(np.argmin(np.abs(grid - math.log(speed))))
    low, high = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    y = target.reshape(-1)
    lower = bounds(base_of(motion.robot, law))

    def error(log_speed):
        return _held_out_rms(_base_columns(motion, law,
                                           math.exp(log_speed)), y, lower)
    found = minimize_scalar(error, bounds=(low, high), method='bounded',
                            options={'xatol': 1e-3})
    return float(math.exp(found.x)) if found.fun < error(math.log(speed)) \
        else speed


def _chosen(candidates):
    """Return the simplest candidate within the selection margin, why."""
    best = min(candidates, key=lambda c: c.held_out_rms)
    for candidate in sorted(candidates, key=lambda c: (len(c.law),
                                                       c.held_out_rms)):
        if candidate.held_out_rms <= best.held_out_rms * (
                1.0 + SELECTION_MARGIN):
            if candidate is best:
                return candidate, (f'{law_name(candidate.law)}: the least '
                                   'held-out error')
            return candidate, (
                f'{law_name(candidate.law)}: within '
                f'{100 * SELECTION_MARGIN:g} % of the least held-out error '
                f'({law_name(best.law)}, {best.held_out_rms:.4g} N) with '
                'fewer terms')
    return best, law_name(best.law)


# The searches (lag, law, Stribeck speed) solve many least squares on the
# same columns: by the normal equations of the unit-norm columns, whose
# Gram matrix is small (n_base^2), solved by lstsq (no failure on a column
# a log does not excite). The final estimate is the SVD's (_least_squares).

def _scaled(a):
    """Return ``a`` with unit-norm columns and the norms (zero: kept 0)."""
    norms = np.linalg.norm(a, axis=0)
    return a / np.where(norms > 0.0, norms, 1.0), norms


def _residual_of(a):
    """Return ``forces -> |y - a x|^2`` for the least squares on ``a``."""
    scaled, _ = _scaled(a)
    gram = scaled.T @ scaled

    def residual(forces):
        y = forces.reshape(-1)
        b = scaled.T @ y
        return float(y @ y - b @ np.linalg.lstsq(gram, b, rcond=None)[0])
    return residual


def _held_out_rms(a, y, lower=None, folds=FOLDS):
    """
    RMS error (N) of each of ``folds`` blocks predicted from the others.

    Each prediction by the estimate identify would give from the other
    blocks: within the bounds ``lower`` of the parameters (None: none),
    so that no law scores by a robot no robot can be (a negative
    armature or friction fitting what the law does not hold).
    """
    rows = len(y) // 3
    edges = np.linspace(0, rows, folds + 1).astype(int) * 3
    scaled, norms = _scaled(a)
    low = None if lower is None else np.where(
        norms > 0.0, lower * norms, -np.inf)
    blocks = [(scaled[i:j], y[i:j]) for i, j in zip(edges[:-1], edges[1:])]
    grams = [(m.T @ m, m.T @ v) for m, v in blocks]
    gram, b = sum(g for g, _ in grams), sum(c for _, c in grams)
    squares = 0.0
    for (m, v), (g, c) in zip(blocks, grams):
        x = _bounded_normal(gram - g, b - c, low)
        squares += float(np.sum((v - m @ x) ** 2))
    return math.sqrt(squares / len(y))


def _bounded_normal(gram, b, lower=None):
    """
    Solve the normal equations ``gram x = b``, ``x >= lower`` where given.

    Least squares on the small system first (lstsq: no failure on a
    direction the data do not excite); where that breaks a bound, the
    bounded least squares (BVLS) of the same problem written with the
    square root of ``gram`` (its eigendecomposition), n_base rows.
    """
    x = np.linalg.lstsq(gram, b, rcond=None)[0]
    if lower is None or (x >= lower).all():
        return x
    from scipy.optimize import lsq_linear
    values, vectors = np.linalg.eigh(gram)
    keep = values > values[-1] * np.finfo(float).eps * len(values)
    if not keep.any():      # nothing excited: no fit, the bounds
        return np.maximum(x, lower)
    root = np.sqrt(values[keep])
    return lsq_linear((vectors[:, keep] * root).T,
                      (vectors[:, keep].T @ b) / root,
                      bounds=(lower, np.inf), method='bvls').x


def _least_squares(a, y, lower, names=None, units=None):
    """
    Solve ``a beta = y``: values, std, singular values, notes, ordinary.

    Returned in that order: the values, their standard deviations, the
    singular values, the bounded notes and the ordinary values.

    By the SVD of ``a`` with unit-norm columns; a direction the log does
    not excite (a singular value below numpy's rank tolerance) adds
    nothing to ``beta`` and a huge deviation, rather than a division by
    zero. Where the solution breaks a bound of ``lower``, the bounded
    least squares' instead, and a note per parameter (``names``, their
    ``units``) held at a bound.
    """
    count = a.shape[1]
    scaled, norms = _scaled(a)
    excited = norms > 0.0
    u, singular, vt = np.linalg.svd(scaled[:, excited], full_matrices=False)
    floor = singular[0] * np.finfo(float).eps * max(scaled.shape)
    values = np.zeros(count)
    values[excited] = vt.T @ (np.divide(
        u.T @ y, singular, out=np.zeros_like(singular),
        where=singular > floor)) / norms[excited]
    residual = y - a @ values
    variance = residual @ residual / max(len(y) - count, 1)
    std = np.full(count, np.inf)
    std[excited] = np.sqrt(variance * ((vt.T / np.maximum(singular, floor))
                                       ** 2).sum(axis=1)) / norms[excited]
    bounded, found = [], values
    if (values < lower).any():
        from scipy.optimize import lsq_linear
        found = values
        solution = lsq_linear(scaled[:, excited], y, bounds=(
            np.where(np.isfinite(lower), lower * norms, -np.inf)[excited],
            np.inf), method='bvls')
        values = np.zeros(count)
        values[excited] = solution.x / norms[excited]
        for i in np.flatnonzero(np.isclose(values, lower, rtol=1e-9,
                                           atol=1e-12)):
            name = names[i] if names else f'parameter {i}'
            unit = units[i] if units else ''
            bounded.append(
                f'{name} was found {found[i]:.4g} {unit} by ordinary least '
                f'squares, below its bound: held at {lower[i]:.4g} {unit} '
                '(bounded least squares)' if found[i] < lower[i] else
                f'{name} was found {found[i]:.4g} {unit} by ordinary least '
                f'squares; with the parameters below their bounds held '
                f'there, it comes to its bound {lower[i]:.4g} {unit} too '
                '(bounded least squares)')
    return values, std, singular, bounded, found


def _check_payload(source, base, payload, found, std, lower):
    """
    Refuse a payload the log's forces do not carry (IdentificationError).

    With its forces taken off, the platform's own mass (the base parameter
    ``m5`` is in) must not come out below what any robot has by more
    than PAYLOAD_SIGMAS of its standard deviations: a payload larger than
    the one the log was recorded with (or in another unit) leaves a
    platform of negative mass, and every other parameter bent to make up
    for it.
    """
    rows = np.flatnonzero(base.matrix[:, _PLATFORM])
    if payload <= 0.0 or len(rows) != 1:
        return
    i = int(rows[0])
    if found[i] + PAYLOAD_SIGMAS * std[i] < lower[i]:
        raise IdentificationError(
            f'{source}: with a payload of {payload:g} kg the platform\'s '
            f'own mass ({base.names[i]}) comes out at {found[i]:.4g} kg '
            f'(standard deviation {std[i]:.2g} kg), which no robot has: '
            'the log\'s forces do not carry that payload; give the one it '
            'was recorded with (kg)')


def bounds(base: Base) -> Array:
    """
    Return the lowest value (n_base,) each base parameter of a robot has.

    ``row @ LOWER`` of a combination of members with coefficients >= 0
    (each member at its bound), else -inf (no bound).
    """
    lower = np.array([LOWER[n] for n in standard_names(base.law)])
    return np.array([row @ lower if (row >= 0.0).all() else -np.inf
                     for row in base.matrix])


def split(robot: Robot, base: Base, values: Array,
          stribeck_velocity: Optional[float] = None
          ) -> tuple[Robot, list[str]]:
    """
    Return ``(robot, notes)``: a complete robot with base parameters ``values``.

    Each base parameter ``beta_i = theta_j + sum_k P_ik theta_k`` is split by
    the rule of doc/identification.md#the-split-rule; each departure from its
    first case is a note. The law is ``base.law`` (with
    ``stribeck_velocity``, m/s). Raises :class:`IdentificationError` only when
    the robot so made is refused (a value beyond a bound of
    :data:`robot.ROWS`).
    """
    names = standard_names(base.law)
    nominal = standard_parameters(robot, base.law)
    lower = np.array([LOWER[n] for n in names])
    theta = nominal.copy()
    notes = []
    for i, (name, carrier) in enumerate(zip(base.names, base.independent)):
        row = base.matrix[i]
        others = [k for k in np.flatnonzero(row) if k != carrier]
        value = values[i] - row[others] @ nominal[others]
        if value >= lower[carrier]:
            theta[carrier] = value
            continue
        unit = UNITS[names[carrier]]
        if carrier >= len(MASSES) and not others:
            theta[carrier] = lower[carrier]
            notes.append(f'{name} was found {values[i]:.4g} {unit}, below '
                         f'its bound: set to {lower[carrier]:g} {unit}')
            continue
        nominal_value = row @ nominal
        shared = any(base.matrix[m, others].any()
                     for m in range(len(base.names)) if m != i)
        members = [carrier] + others
        ratio = values[i] / nominal_value if nominal_value > 0.0 else 0.0
        if ratio > 0.0 and (row >= 0.0).all() and not shared and (
                nominal[members] * ratio >= lower[members]).all():
            theta[members] = nominal[members] * ratio
            notes.append(f'{name} = {values[i]:.6g} {unit} is below its '
                         'other members\' nominal share: the combination '
                         f'is scaled by {ratio:.6g} from its nominal '
                         'values')
            continue
        # (The bounded least squares hold a combination at its bound to
        # the rounding of its scaled solution.)
        rest = values[i] - row[others] @ lower[others]
        if (row >= 0.0).all() and not shared and rest >= lower[carrier] - (
                1e-9 * abs(lower[carrier])):
            theta[others] = lower[others]
            theta[carrier] = rest = max(rest, lower[carrier])
            notes.append(f'{name} = {values[i]:.6g} {unit} is below what '
                         'its members\' nominal values or their scaling '
                         'allow: the other members are set to their bounds '
                         f'and {names[carrier]} takes the rest, {rest:.6g} '
                         f'{unit}')
            continue
        notes.append(f'{name} was found {values[i]:.4g} {unit}, which no '
                     'robot within the bounds has: its nominal value '
                     f'{nominal_value:.4g} {unit} is kept (the log may not '
                     'excite it enough: see its standard deviation)')
    try:
        return with_parameters(robot, theta, base.law,
                               stribeck_velocity), notes
    except ValueError as error:
        raise IdentificationError(f'the identified robot is refused: '
                                  f'{error}') from None


def _gaps_prefix(motion):
    """
    Name the log's gaps when they lost much of it, to lead a refusal.

    A log the recording split (a stalled recorder, lost messages) is the
    cause to fix before its motion: the refusal says so first.
    """
    coverage = motion.coverage
    if not coverage.gaps or coverage.used_s >= GAP_LOSS * coverage.log_s:
        return ''
    return (f'{coverage.gaps} gap(s) split the log (the longest '
            f'{coverage.longest_gap_s:.3g} s) and '
            f'{100.0 * coverage.used_s / coverage.log_s:.3g} % of it is '
            'usable: record it again without gaps (another load on the '
            'machine?); ')
