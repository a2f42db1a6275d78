"""
Identify the Orthoglide's masses and slider friction from a log, without ROS.

The actuator forces are linear in the masses and the friction coefficients:
``f = W(r_G, rdot_G, rddot_G) theta`` with the standard parameters
``theta = (m1 ... m6, c_A, c_B, c_C, F_A, F_B, F_C)`` (kg, N s/m, N:
:data:`STANDARD`). The geometry, gravity and the Coulomb smoothing speed
are known (the nominal robot's). The steps, each a function here:

- :func:`regressor`: ``W`` from the package's own inverse dynamics, not a
  second model: a mass's column is the difference of the forces of two
  robots that differ by 1 kg in that mass (exact, the forces being linear
  in the masses), a friction coefficient's the friction law with that
  coefficient 1 (:func:`mechanics.friction_force`);
- :func:`base_parameters`: some combinations act only together (the
  slider and the rod it carries move as one; so do the two bars of a
  parallelogram; the rods 4 ride with the platform). They are found
  numerically, by a QR decomposition with column pivoting of ``W`` at
  random states: the base parameters ``beta = P theta`` are the ones a log
  can identify;
- :func:`prepare`: a log's samples onto a uniform grid, the platform
  positions from the measured ``lambda``
  (:func:`mechanics.forward_kinematics`) through a zero-phase Butterworth
  low-pass (``scipy.signal.sosfiltfilt``), velocities and accelerations
  by central differences (or the velocity from a measured ``lambdadot``
  through the same low-pass), ``W`` at every sample, then the forces and
  every column of ``W`` through that same zero-phase low-pass (parallel
  filtering) and decimated alike;
- :func:`identify`: least squares for ``beta``, with relative standard
  deviations, the condition number and the RMS residual per actuator, a
  refusal when a base parameter is not excited (its relative standard
  deviation above MAX_RELATIVE_STD), and a complete :class:`Robot` by the
  split rule of :func:`split`.

Logs come from a CSV file (:func:`read_csv`) or a rosbag2 bag, MCAP or
sqlite3 (:func:`read_bag`, with the ``rosbags`` library, no ROS).
``doc/identification.md`` states the method, its choices and its figures.
Units: m, m/s, m/s^2, N, kg, s. scipy and rosbags are imported by the
functions that use them, so that importing this module (as the
``orthoglide`` tool does for every command) costs neither.
"""

from collections import namedtuple
import math
import os

import numpy as np

from orthoglide_ros.formats import cdr
from orthoglide_ros.model import mechanics
from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.cores.parameters import JOINT_NAMES
from orthoglide_ros.model.robot import DESCRIPTIONS, LIMITS

MASSES = ('m1', 'm2', 'm3', 'm4', 'm5', 'm6')
FRICTIONS = ('viscous', 'coulomb')
LEGS = ('a', 'b', 'c')
# The standard parameters: the masses, then per actuator the viscous (N
# s/m) and the Coulomb (N) friction coefficients.
STANDARD = MASSES + tuple(f'{kind}_{leg}' for kind in FRICTIONS
                          for leg in LEGS)
UNITS = dict.fromkeys(MASSES, 'kg') | {
    f'{kind}_{leg}': unit
    for kind, unit in (('viscous', 'N s/m'), ('coulomb', 'N'))
    for leg in LEGS}
# What each standard parameter is, in words (the masses' from the robot's
# parameter descriptions).
MEANINGS = {m: DESCRIPTIONS[m].split(';')[0] for m in MASSES} | {
    f'{kind}_{leg}': f'{label} friction of slider {leg.upper()}'
    for kind, label in (('viscous', 'viscous'), ('coulomb', 'Coulomb'))
    for leg in LEGS}
# Lowest value of each standard parameter (a Robot's bound).
LOWER = np.array([LIMITS['m1'][0]] * 6 + [LIMITS['friction_viscous'][0]] * 3
                 + [LIMITS['friction_coulomb'][0]] * 3)

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

# The log's processing (doc/identification.md): a 4th-order Butterworth
# low-pass at DEFAULT_CUTOFF (Hz) run forwards and backwards (zero phase,
# 8th-order roll-off) on the forces and the regressor's columns alike;
# samples within 2 / cutoff of a segment's ends are dropped (the edges of
# the two filters in series); a gap longer than GAP_FACTOR times the
# median sampling period and longer than GAP_SHARE / cutoff splits the log
# into segments; shorter gaps are interpolated linearly (for a component
# at frequency f, an error below (pi f gap)^2 / 2 of it: 5 % at the
# cutoff, 0.2 % at a fifth of it).
DEFAULT_CUTOFF = 10.0
FILTER_ORDER = 4
# The motion (positions, measured velocities) goes through the same design
# at STATE_CUTOFF_FACTOR times the cutoff, at most STATE_CUTOFF_SHARE of the
# sampling rate: five times the band of the forces, as Gautier filters
# positions, so that the velocity keeps the ripple a Coulomb switch sees
# (at the cutoff itself, the closed-loop logs of the demo gave m1 + m2 5 %
# too heavy) while the encoder's quantisation stays out.
STATE_CUTOFF_FACTOR = 5.0
STATE_CUTOFF_SHARE = 0.4
GAP_FACTOR = 3.0
GAP_SHARE = 0.1
# Fewest samples the least squares may use, per base parameter.
MIN_SAMPLES_PER_PARAMETER = 10
# A base parameter whose relative standard deviation (%) exceeds this is
# not excited by the log: the identification is refused. Well excited
# parameters come out at a few % at most (doc/identification.md).
MAX_RELATIVE_STD = 10.0
# The relative standard deviation of a base parameter is taken against the
# larger of its estimate and this resolution (by the unit of its carrier),
# so that a parameter that is zero (a robot without friction) is judged by
# its deviation: a slider friction below 1 N (or 1 N s/m, 0.4 N at the
# excitation's 0.4 m/s) or a mass below 10 g hardly matters to forces of
# tens to hundreds of N.
RESOLUTION = {'kg': 0.01, 'N s/m': 1.0, 'N': 1.0}
# The log's columns in a CSV file (those `orthoglide batch` writes); the
# measured velocities are optional.
LOG_GROUPS = (('time', ('t',), True),
              ('lambda', ('lambda_a', 'lambda_b', 'lambda_c'), True),
              ('force', ('force_a', 'force_b', 'force_c'), True),
              ('lambdadot', ('lambdadot_a', 'lambdadot_b', 'lambdadot_c'),
               False))
JOINT_STATE_TYPE = 'sensor_msgs/msg/JointState'
DEFAULT_TOPIC = '/joint_states'
BAG_SUFFIXES = ('.mcap', '.db3')

Log = namedtuple('Log', ('times', 'lambdas', 'forces', 'source', 'origin',
                         'lambdadots'), defaults=(0, None))
Log.__doc__ = """A measured log: ``times`` (N,) s, ``lambdas`` (N, 3) m and
``forces`` (N, 3) N of actuators A, B, C; ``source`` names it; ``times``
are counted from ``origin`` (ns; a bag's first header stamp, else 0);
``lambdadots`` (N, 3) m/s: measured velocities, or None."""

Samples = namedtuple('Samples', (
    'times', 'regressor', 'forces', 'segments', 'rate'))
Samples.__doc__ = """A log prepared for identification (:func:`prepare`).

(N,) times (s), the regressor ``W`` (N, 3, 12) of the standard
parameters and the forces (N, 3) (N), both through the same low-pass;
``segments``: how many pieces of the log they come from; ``rate``: their
sampling rate after the decimation (Hz).
"""

Base = namedtuple('Base', ('names', 'independent', 'matrix', 'meanings'))
Base.__doc__ = """The base parameters (:func:`base_parameters`).

``matrix`` ``P`` (n_base, 12): ``beta = P theta`` and ``W theta = W[:,
independent] beta`` for every state; ``independent``: the standard
parameter carrying each base parameter (its column of ``P`` is a unit
one); ``names``: each as a combination, e.g. ``'m5 + 3 m4'``;
``meanings``: the same in words (:data:`MEANINGS`).
"""

Identification = namedtuple('Identification', (
    'base', 'values', 'nominal', 'std', 'relative_std', 'condition',
    'residual_rms', 'force_rms', 'samples', 'predicted', 'robot', 'notes'))
Identification.__doc__ = """What :func:`identify` found.

Per base parameter: ``values`` (identified), ``nominal`` (of the nominal
robot), ``std`` and ``relative_std`` (%, ``100 std / max(|value|,
resolution)``, RESOLUTION);
``condition``: of the base regressor with unit-norm columns;
``residual_rms`` and ``force_rms``: per actuator (N), of the residual and
of the filtered forces; ``samples``: the :class:`Samples` used;
``predicted``: the forces (N, 3) the identified parameters give for them;
``robot``: the identified :class:`Robot` (:func:`split`); ``notes``: what
the split rule had to do beyond the plain rule, as sentences.
"""


class LogError(ValueError):
    """A log that cannot be read or used; the message says why."""


class IdentificationError(ValueError):
    """An identification that cannot give a robot; the message says why."""


def standard_parameters(robot):
    """Return ``theta`` of ``robot``: its :data:`STANDARD` values (12,)."""
    return np.array([getattr(robot, m) for m in MASSES]
                    + list(robot.friction_viscous)
                    + list(robot.friction_coulomb))


def with_parameters(robot, theta):
    """Return ``robot`` with the standard parameters ``theta`` (validated)."""
    theta = [float(v) for v in theta]
    return robot.replace(**dict(zip(MASSES, theta[:6])),
                         friction_viscous=tuple(theta[6:9]),
                         friction_coulomb=tuple(theta[9:12]))


def regressor(robot, positions, velocities, accelerations,
              margin=mechanics.DEFAULT_SINGULARITY_MARGIN):
    """
    Return ``W`` (N, 3, 12): ``force = W @ theta`` per sample and actuator.

    ``positions`` (m), ``velocities`` (m/s), ``accelerations`` (m/s^2):
    (N, 3) arrays of the platform centre in frame 0. Built from
    :func:`mechanics.solve_batch` on ``robot``'s geometry and gravity (its
    masses and friction do not matter): column ``m_i`` is the force of a
    robot whose masses are all 2 kg less that of one whose masses are all
    1 kg but ``m_i`` (exact: the rigid forces are ``sum_i m_i W_i``), the
    friction columns :func:`mechanics.friction_force` with one coefficient
    1 at the samples' ``lambdadot`` and ``robot.friction_velocity``.
    Raises :class:`mechanics.WorkspaceError` as ``solve_batch`` does.
    """
    unit = robot.frictionless().replace(**dict.fromkeys(MASSES, 1.0))
    reference = mechanics.solve_batch(unit, positions, velocities,
                                      accelerations, margin)
    out = np.empty(reference.force.shape + (len(STANDARD),))
    for i, name in enumerate(MASSES):
        heavier = mechanics.solve_batch(unit.replace(**{name: 2.0}),
                                        positions, velocities,
                                        accelerations, margin)
        out[:, :, i] = heavier.force - reference.force
    for j in range(3):
        one = tuple(float(j == k) for k in range(3))
        for column, kind in ((6 + j, 'friction_viscous'),
                             (9 + j, 'friction_coulomb')):
            out[:, :, column] = mechanics.friction_force(
                unit.replace(**{kind: one}, **(
                    {'friction_coulomb_negative': one}
                    if kind == 'friction_coulomb' else {})),
                reference.lambdadot)
    return out


def base_parameters(robot, samples=BASE_SAMPLES, seed=0):
    """
    Find the base parameters of ``robot``'s regressor (a :class:`Base`).

    ``W`` at ``samples`` random states (see BASE_BOX and its neighbours;
    ``seed`` for the generator), each column weighted by its parameter's
    nominal value in ``robot`` (a parameter whose nominal value is zero,
    such as friction on the paper's robot: its column scaled to unit RMS),
    goes through a QR decomposition with column pivoting
    (``scipy.linalg.qr``). The pivots above RANK_TOLERANCE of the first are
    the independent parameters; each other column is a combination of
    those, found by least squares, which gives ``P``. The weighting makes
    the parameter with the largest nominal contribution carry each
    combination (the platform's ``m5`` rather than the rods' ``m4``), so
    that :func:`split` keeps the smaller ones at their nominal values.
    """
    import scipy.linalg
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-BASE_BOX, BASE_BOX, (samples, 3))
    velocities = rng.uniform(-BASE_SPEED, BASE_SPEED, (samples, 3))
    accelerations = rng.uniform(-BASE_ACCELERATION, BASE_ACCELERATION,
                                (samples, 3))
    ok = mechanics.workspace_status(robot, positions).ok
    w = regressor(robot, positions[ok], velocities[ok], accelerations[ok])
    w = w.reshape(-1, len(STANDARD))
    nominal = standard_parameters(robot)
    rms = np.sqrt(np.mean(w * w, axis=0))
    weights = np.where(nominal > 0.0, nominal, 1.0 / rms)
    _, r, pivots = scipy.linalg.qr(w * weights, mode='economic',
                                   pivoting=True)
    diagonal = np.abs(np.diag(r))
    rank = int(np.sum(diagonal > RANK_TOLERANCE * diagonal[0]))
    independent = np.sort(pivots[:rank])
    dependent = np.sort(pivots[rank:])
    matrix = np.zeros((rank, len(STANDARD)))
    matrix[np.arange(rank), independent] = 1.0
    if len(dependent):
        combination = np.linalg.lstsq(w[:, independent], w[:, dependent],
                                      rcond=None)[0]
        combination[np.abs(combination) < COMBINATION_TOLERANCE] = 0.0
        matrix[:, dependent] = combination
    names, meanings = ([_combination(row, j, words, times)
                        for row, j in zip(matrix, independent)]
                       for words, times in ((dict(zip(STANDARD, STANDARD)),
                                             ' '), (MEANINGS, ' x ')))
    return Base(tuple(names), tuple(int(j) for j in independent), matrix,
                tuple(meanings))


def _combination(row, carrier, words, times):
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
            + factor + words[STANDARD[k]]
    return text


def check_log(log, where=None):
    """
    Refuse a :class:`Log` that cannot be identified from (:class:`LogError`).

    Shapes (``times`` (N,), the others (N, 3)), every value finite, times
    strictly increasing, at least three samples. ``where(k)`` names the
    0-based sample ``k`` in the message (default ``'sample k + 1'``; a
    CSV file's data row, a bag's message).
    """
    where = where or (lambda k: f'sample {k + 1}')
    times = np.asarray(log.times, dtype=float)
    arrays = [('lambda', log.lambdas), ('force', log.forces)]
    if log.lambdadots is not None:
        arrays.append(('lambdadot', log.lambdadots))
    arrays = [(q, np.asarray(a, dtype=float)) for q, a in arrays]
    if times.ndim != 1 or any(a.shape != (len(times), 3) for _, a in arrays):
        raise LogError(f'{log.source}: times (N,), lambdas, forces and '
                       'lambdadots (N, 3) expected')
    for quantity, values in [('t', times[:, None])] + arrays:
        bad = ~np.isfinite(values)
        if bad.any():
            k, j = (int(i) for i in np.argwhere(bad)[0])
            column = 't' if quantity == 't' else f'{quantity}_{LEGS[j]}'
            raise LogError(f'{log.source}: {where(k)}: {column} is '
                           f'{float(values[k, j])!r}, not a finite number')
    late = np.flatnonzero(np.diff(times) <= 0.0)
    if len(late):
        k = int(late[0]) + 1
        raise LogError(f'{log.source}: {where(k)}: time {float(times[k])!r} '
                       f's is not after the sample before '
                       f'({float(times[k - 1])!r} s): time must increase '
                       'strictly')
    if len(times) < 3:
        raise LogError(f'{log.source}: {len(times)} sample(s): too few to '
                       'identify anything')


def prepare(robot, log, cutoff=DEFAULT_CUTOFF, force_lag=0.0):
    """
    Turn a :class:`Log` into :class:`Samples` for the least squares.

    The log is checked (:func:`check_log`); split into segments at gaps
    longer than GAP_FACTOR median periods and GAP_SHARE / cutoff; each
    segment interpolated linearly onto a uniform grid of the median period
    (exact where the stamps are on it), the forces taken as applied
    ``force_lag`` s before their stamps (a drive or a simulator that
    reports with each state the force it held over the last period of
    ``dt``: ``dt / 2``). Then, with ``H`` the zero-phase Butterworth
    low-pass of ``cutoff`` Hz (order FILTER_ORDER, run forwards and
    backwards: ``scipy.signal.sosfiltfilt``) and ``H_s`` the same at
    STATE_CUTOFF_FACTOR times ``cutoff`` (at most STATE_CUTOFF_SHARE of
    the sampling rate):

    1. the motion: the platform positions from ``lambda``
       (:func:`mechanics.forward_kinematics`, ``robot``'s geometry)
       through ``H_s``, the velocity their central difference ``(r+ -
       r-) / 2 dt`` (or, with measured ``lambdadots``, theirs through
       ``H_s``: ``rdot = J2^-1 J1 lambdadot``, eq. 15), the acceleration
       the velocity's central difference (at a frequency ``f``, relative
       errors of ``(2 pi f dt)^2 / 6`` and twice that: 7e-6 and 1.3e-5
       at 1 Hz and 1 kHz). ``H_s`` passes what the forces answer to (the
       velocity's ripple at a reversal, which the Coulomb switch sees)
       and stops the encoder's noise;
    2. the regressor ``W`` (:func:`regressor`) at every sample;
    3. parallel filtering: the forces and every column of ``W`` through
       ``H``, so that ``H(f) = H(W) theta`` holds as ``f = W theta`` does:
       nothing out of phase, no bias from the filter (the sharp Coulomb
       switch included);
    4. ``2 / cutoff`` s dropped at each end of a segment (the edges of
       the two filters in series: positions, then ``W``), segments too
       short for that dropped, and one sample in
       ``floor(rate / (2 cutoff))`` kept (parallel decimation, as
       Gautier's: the filtered signals hold nothing above the cutoff, and
       the least squares' residuals become nearly uncorrelated, which the
       standard deviations of :func:`identify` assume).

    Raises :class:`LogError`.
    """
    import scipy.signal
    check_log(log)
    times = np.asarray(log.times, dtype=float)
    lambdas = np.asarray(log.lambdas, dtype=float)
    forces = np.asarray(log.forces, dtype=float)
    measured = None if log.lambdadots is None else np.asarray(
        log.lambdadots, dtype=float)
    period = float(np.median(np.diff(times)))
    rate = 1.0 / period
    if not 0.0 < cutoff < 0.5 * rate:
        raise LogError(f'{log.source}: the cutoff {cutoff:g} Hz must lie in '
                       f'(0, {0.5 * rate:g}) Hz, half the sampling rate '
                       f'{rate:g} Hz')
    sos = scipy.signal.butter(FILTER_ORDER, cutoff, fs=rate, output='sos')
    state_sos = scipy.signal.butter(
        FILTER_ORDER, min(STATE_CUTOFF_FACTOR * cutoff,
                          STATE_CUTOFF_SHARE * rate), fs=rate, output='sos')
    # (1e-9: a median period rounded up must not change these counts.)
    trim = int(math.ceil(2.0 * rate / cutoff * (1.0 - 1e-9)))
    step = max(1, int(rate / (2.0 * cutoff) * (1.0 + 1e-9)))
    if not (math.isfinite(force_lag) and abs(force_lag) < 1.0 / cutoff):
        raise LogError(f'{log.source}: the force lag {force_lag:g} s must be '
                       f'shorter than 1 / cutoff = {1.0 / cutoff:g} s')
    breaks = np.flatnonzero(np.diff(times) > max(
        GAP_FACTOR * period, GAP_SHARE / cutoff)) + 1
    pieces = []
    for start, end in zip(np.r_[0, breaks], np.r_[breaks, len(times)]):
        t = times[start:end]
        grid = t[0] + period * np.arange(
            int(math.floor((t[-1] - t[0]) / period + 1e-9)) + 1)
        if len(grid) < 2 * trim + 3 * (2 * len(sos) + 1):
            continue

        def on_grid(values, lag=0.0):
            return np.column_stack([np.interp(grid, t - lag,
                                              values[start:end, j])
                                    for j in range(3)])
        try:
            position = scipy.signal.sosfiltfilt(
                state_sos, mechanics.forward_kinematics(robot,
                                                        on_grid(lambdas)),
                axis=0)
            if measured is None:
                velocity = np.gradient(position, period, axis=0)
            else:
                j1, j2 = mechanics.jacobians(robot, position)
                velocity = np.linalg.solve(j2, j1 @ scipy.signal.sosfiltfilt(
                    state_sos, on_grid(measured), axis=0)[:, :, None]
                )[:, :, 0]
            acceleration = np.gradient(velocity, period, axis=0)
            w = regressor(robot, position, velocity, acceleration)
        except mechanics.WorkspaceError as error:
            raise LogError(f'{log.source}: the motion at t = '
                           f'{grid[error.row]:.6g} s: {error}') from None
        w = scipy.signal.sosfiltfilt(sos, w.reshape(len(grid), -1),
                                     axis=0).reshape(w.shape)
        force = scipy.signal.sosfiltfilt(sos, on_grid(forces, force_lag),
                                         axis=0)
        inner = slice(trim, len(grid) - trim, step)
        pieces.append((grid[inner], w[inner], force[inner]))
    if not pieces:
        raise LogError(f'{log.source}: no piece of the log lasts more than '
                       f'{2 * trim * period:.3g} s (4 / cutoff) '
                       'between gaps')
    columns = [np.concatenate(c) for c in zip(*pieces)]
    return Samples(*columns, len(pieces), rate / step)


def identify(robot, log, cutoff=DEFAULT_CUTOFF, base=None, force_lag=0.0,
             max_relative_std=MAX_RELATIVE_STD):
    """
    Identify the base parameters from a :class:`Log` (an Identification).

    ``robot``: the nominal robot (its geometry, gravity and
    ``friction_velocity`` are taken as known, its masses and friction are
    the nominal values of the split rule); ``cutoff`` (Hz) and
    ``force_lag`` (s): of :func:`prepare`; ``base``: a :class:`Base`
    (default :func:`base_parameters`).
    Ordinary least squares on every sample and actuator (by the SVD of
    the base regressor with unit-norm columns), the standard deviations
    from the residual's variance ``|r|^2 / (3N - n_base)`` and ``(W^T
    W)^-1``. Refused (:class:`IdentificationError`, naming them) when a
    base parameter's relative standard deviation (against the larger of
    its estimate and its RESOLUTION) exceeds ``max_relative_std`` (%) or
    its column is zero: the log does not excite it. Raises
    :class:`LogError` for a log it cannot use.
    """
    base = base or base_parameters(robot)
    samples = prepare(robot, log, cutoff, force_lag)
    count = len(base.independent)
    if len(samples.times) < MIN_SAMPLES_PER_PARAMETER * count:
        raise LogError(f'{log.source}: {len(samples.times)} usable '
                       f'samples, at least {MIN_SAMPLES_PER_PARAMETER * count}'
                       f' needed ({MIN_SAMPLES_PER_PARAMETER} per base '
                       f'parameter, at {samples.rate:.4g} Hz after the '
                       'decimation)')
    a = samples.regressor[:, :, list(base.independent)].reshape(-1, count)
    y = samples.forces.reshape(-1)
    norms = np.linalg.norm(a, axis=0)
    excited = norms > 0.0
    scaled = a[:, excited] / norms[excited]
    # Least squares by the SVD W = U S V^T: beta = V S^-1 U^T y, and
    # (W^T W)^-1 = V S^-2 V^T. A direction the log does not excite (S
    # below numpy's rank tolerance) adds nothing to beta and a huge
    # deviation, rather than a division by zero.
    u, singular, vt = np.linalg.svd(scaled, full_matrices=False)
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
    resolution = [RESOLUTION[UNITS[STANDARD[j]]] for j in base.independent]
    relative = 100.0 * std / np.maximum(np.abs(values), resolution)
    unexcited = np.flatnonzero(~(relative <= max_relative_std))
    if len(unexcited):
        raise IdentificationError(
            f'{log.source}: the log does not excite '
            + ', '.join(f'{base.names[i]} ({relative[i]:.3g} %)'
                        for i in unexcited)
            + f': relative standard deviation above {max_relative_std:g} %'
            ' (a motion of every axis, at varied speeds and accelerations, '
            'excites them: orthoglide excitation)')
    robot_out, notes = split(robot, base, values)
    return Identification(
        base, values, base.matrix @ standard_parameters(robot), std,
        relative, float(singular[0] / singular[-1]),
        np.sqrt(np.mean(residual.reshape(-1, 3) ** 2, axis=0)),
        np.sqrt(np.mean(samples.forces ** 2, axis=0)), samples,
        (a @ values).reshape(-1, 3), robot_out, notes)


def split(robot, base, values):
    """
    Return ``(robot, notes)``: a complete robot with base parameters ``values``.

    The rule, per base parameter ``beta_i = theta_j + sum_k P_ik theta_k``
    (``j`` its carrier): the other parameters of the combination keep
    their nominal values (those of ``robot``) and the carrier takes the
    rest, ``theta_j = beta_i - sum_k P_ik theta_k``. Where that would put
    the carrier below its bound (a mass below 1e-6 kg), the whole
    combination is scaled from its nominal values instead, ``theta =
    theta_nominal beta_i / beta_i,nominal`` (when the combination's
    coefficients and both values are positive). A friction coefficient
    found below zero is set to zero. A combination no robot within the
    bounds has (a mass combination found below zero: a parameter the log
    hardly excites) keeps its nominal values. Each departure from the
    plain rule is a note. Raises :class:`IdentificationError` only when
    the robot so made is refused (a value beyond a bound of
    :data:`robot.LIMITS`).
    """
    nominal = standard_parameters(robot)
    theta = nominal.copy()
    notes = []
    for i, (name, carrier) in enumerate(zip(base.names, base.independent)):
        row = base.matrix[i]
        others = [k for k in np.flatnonzero(row) if k != carrier]
        value = values[i] - row[others] @ nominal[others]
        if value >= LOWER[carrier]:
            theta[carrier] = value
            continue
        unit = UNITS[STANDARD[carrier]]
        if carrier >= len(MASSES) and not others:
            theta[carrier] = LOWER[carrier]
            notes.append(f'{name} was found {values[i]:.4g} {unit}, below '
                         f'its bound: set to {LOWER[carrier]:g} {unit}')
            continue
        nominal_value = row @ nominal
        shared = any(base.matrix[m, others].any()
                     for m in range(len(base.names)) if m != i)
        members = [carrier] + others
        ratio = values[i] / nominal_value if nominal_value > 0.0 else 0.0
        if ratio > 0.0 and (row >= 0.0).all() and not shared and (
                nominal[members] * ratio >= LOWER[members]).all():
            theta[members] = nominal[members] * ratio
            notes.append(f'{name} = {values[i]:.6g} {unit} is below its '
                         'other members\' nominal share: the combination '
                         f'is scaled by {ratio:.6g} from its nominal '
                         'values')
            continue
        notes.append(f'{name} was found {values[i]:.4g} {unit}, which no '
                     'robot within the bounds has: its nominal value '
                     f'{nominal_value:.4g} {unit} is kept (the log may not '
                     'excite it enough: see its standard deviation)')
    try:
        return with_parameters(robot, theta), notes
    except ValueError as error:
        raise IdentificationError(f'the identified robot is refused: '
                                  f'{error}') from None


def predict(robot, samples):
    """
    Return the forces (N, 3) ``robot`` needs for the prepared samples.

    Through the same low-pass as the samples' forces: ``W theta`` with
    their filtered regressor, for a robot of the geometry, gravity and
    ``friction_velocity`` they were prepared with.
    """
    return samples.regressor @ standard_parameters(robot)


def condition_number(robot, positions, velocities, accelerations,
                     base=None):
    """
    Condition number of the base regressor along a motion (no noise).

    (N, 3) arrays (m, m/s, m/s^2); ``base`` default
    :func:`base_parameters` of ``robot``. Columns scaled to unit norm, as
    :func:`identify` solves them: 1 is ideal, and the larger it is the
    more the noise of the log is amplified into the parameters.
    """
    base = base or base_parameters(robot)
    w = regressor(robot, positions, velocities, accelerations)
    a = w[:, :, list(base.independent)].reshape(-1, len(base.independent))
    singular = np.linalg.svd(a / np.linalg.norm(a, axis=0),
                             compute_uv=False)
    return float(singular[0] / singular[-1])


# Logs ---------------------------------------------------------------------

def crop(log, start=None, end=None):
    """
    Return the samples of ``log`` from ``start`` to ``end`` (s, inclusive).

    Both counted from the log's first sample (its earliest time); None:
    from the first, to the last. Raises :class:`LogError` when nothing is
    left.

    >>> log = Log(np.array([5.0, 5.5, 6.0]), np.zeros((3, 3)),
    ...           np.zeros((3, 3)), 'log')
    >>> crop(log, 0.5).times.tolist()
    [5.5, 6.0]
    """
    times = np.asarray(log.times, dtype=float)
    first = times.min() if len(times) else 0.0
    keep = np.ones(len(times), dtype=bool)
    if start is not None:
        keep &= times >= first + start
    if end is not None:
        keep &= times <= first + end
    if not keep.any():
        raise LogError(f'{log.source}: no sample between {start} s and '
                       f'{end} s from its first')
    return Log(times[keep], np.asarray(log.lambdas)[keep],
               np.asarray(log.forces)[keep], log.source, log.origin,
               None if log.lambdadots is None
               else np.asarray(log.lambdadots)[keep])


def read_log(path, topic=DEFAULT_TOPIC, joint_names=JOINT_NAMES):
    """
    Read a log: a rosbag2 bag (:func:`read_bag`) or a CSV file (:func:`read_csv`).

    A directory, or a ``.mcap`` or ``.db3`` file, is a bag; anything else
    a CSV file.
    """
    path = str(path)
    if os.path.isdir(path) or path.endswith(BAG_SUFFIXES) \
            and os.path.isfile(path):
        return read_bag(path, topic, joint_names)
    return read_csv(path)


def read_csv(path):
    """
    Read a log from a CSV file and check it (:func:`check_log`).

    Columns ``t`` (s), ``lambda_a``, ``lambda_b``, ``lambda_c`` (m),
    ``force_a``, ``force_b``, ``force_c`` (N) and, optional,
    ``lambdadot_a``, ``lambdadot_b``, ``lambdadot_c`` (m/s), matched by
    name as :func:`csvfile.read_columns` does (the columns of ``orthoglide
    batch``); others ignored. Raises :class:`LogError`.
    """
    try:
        values, lines = read_columns(path, LOG_GROUPS)
    except CsvError as error:
        raise LogError(str(error)) from None
    log = Log(values['time'][:, 0], values['lambda'], values['force'],
              str(path), lambdadots=values['lambdadot'])
    check_log(log, lambda k: f'data row {k + 1} (line {lines[k]})')
    return log


def read_bag(path, topic=DEFAULT_TOPIC, joint_names=JOINT_NAMES):
    """
    Read a log from the ``sensor_msgs/JointState`` messages of a rosbag2 bag.

    ``path``: the bag's directory, or its ``.mcap`` or ``.db3`` file (the
    bag of its directory when a ``metadata.yaml`` is beside it, else the
    file alone), MCAP or sqlite3 storage, read by the ``rosbags`` library
    without ROS; ``topic`` (a leading ``/`` is added); ``joint_names``:
    the joints of actuators A, B, C, found by name in each message (other
    joints ignored). Time is each message's header stamp (the
    measurement's time), in s from the earliest (``origin``, ns); position
    is lambda (m), effort the force (N); the velocity is not read (a
    drive's is often a lagging difference of its own). Checked by
    :func:`check_log`. Raises :class:`LogError`.
    """
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:
        raise LogError('reading a rosbag2 bag needs the rosbags package '
                       '(pip install rosbags)') from None
    name = topic if topic.startswith('/') else '/' + topic
    source = str(path)
    if os.path.isfile(path) and os.path.isfile(os.path.join(
            os.path.dirname(source), 'metadata.yaml')):
        path = os.path.dirname(source) or '.'
    times, lambdas, forces = [], [], []
    orders = {}
    try:
        with Reader(path) as reader:
            connections = [c for c in reader.connections if c.topic == name]
            if not connections:
                topics = sorted({c.topic for c in reader.connections})
                raise LogError(f'{source}: no topic {name} in the bag (it '
                               f'has {", ".join(topics) or "none"})')
            for connection in connections:
                if connection.msgtype != JOINT_STATE_TYPE:
                    raise LogError(f'{source}: {name} carries '
                                   f'{connection.msgtype}, not '
                                   f'{JOINT_STATE_TYPE}')
            for _, _, raw in reader.messages(connections=connections):
                stamp, names, position, effort = _joint_state(raw)
                order = orders.get(names)
                if order is None:
                    order = orders[names] = _joint_order(
                        source, names, joint_names, len(position),
                        len(effort))
                times.append(stamp)
                lambdas.append([position[k] for k in order])
                forces.append([effort[k] for k in order])
    except LogError:
        raise
    except Exception as error:  # rosbags' errors, unreadable files
        raise LogError(f'{source}: cannot read the bag: {error}') from None
    if not times:
        raise LogError(f'{source}: no message on {name}')
    stamps = np.array(times, dtype=np.int64)
    origin = int(stamps.min())
    log = Log((stamps - origin) * 1e-9, np.array(lambdas), np.array(forces),
              source, origin)
    check_log(log, lambda k: f'message {k + 1} on {name}')
    return log


def _joint_state(raw):
    """Return ``(stamp ns, names, position, effort)`` of a JointState."""
    try:
        (sec, nanosec), _, names, position, _, effort = cdr.joint_state(raw)
    except ValueError:      # not little-endian CDR: the full deserializer
        from rosbags.typesys import get_typestore, Stores
        msg = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(
            raw, JOINT_STATE_TYPE)
        sec, nanosec = msg.header.stamp.sec, msg.header.stamp.nanosec
        names, position, effort = (tuple(msg.name), tuple(msg.position),
                                   tuple(msg.effort))
    return sec * 10**9 + nanosec, names, position, effort


def _joint_order(path, names, joint_names, positions, efforts):
    """Return the indices of ``joint_names`` in a message's ``names``."""
    missing = [j for j in joint_names if j not in names]
    if missing:
        raise LogError(f'{path}: joint states without {missing[0]!r} '
                       f'(names {list(names)}): set the joint names')
    order = [names.index(j) for j in joint_names]
    if max(order) >= min(positions, efforts):
        raise LogError(f'{path}: joint states without a position and an '
                       'effort per joint: the force must be in effort')
    return order
