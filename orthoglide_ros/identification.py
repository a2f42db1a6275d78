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
- :func:`prepare`: a log's samples onto a uniform grid, the positions from
  the measured ``lambda`` (:func:`mechanics.forward_kinematics`), a
  zero-phase Butterworth low-pass (``scipy.signal.sosfiltfilt``) on the
  positions and the forces alike, and velocities and accelerations by
  central differences of the filtered positions;
- :func:`identify`: least squares for ``beta``, with relative standard
  deviations, the condition number and the RMS residual per actuator, and
  a complete :class:`Robot` by the split rule of :func:`split`.

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

from orthoglide_ros import cdr, mechanics
from orthoglide_ros.csvfile import CsvError, read_columns
from orthoglide_ros.parameters import JOINT_NAMES
from orthoglide_ros.robot import LIMITS

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
# 8th-order roll-off); samples within 1 / cutoff of a segment's ends are
# dropped (the filter's edges); a gap longer than GAP_FACTOR times the
# median sampling period and longer than GAP_SHARE / cutoff splits the log
# into segments; shorter gaps are interpolated linearly (for a component
# at frequency f, an error below (pi f gap)^2 / 2 of it: 5 % at the
# cutoff, 0.2 % at a fifth of it).
DEFAULT_CUTOFF = 10.0
FILTER_ORDER = 4
GAP_FACTOR = 3.0
GAP_SHARE = 0.1
# Fewest samples the least squares may use, per base parameter.
MIN_SAMPLES_PER_PARAMETER = 10
# The log's columns in a CSV file: those that `orthoglide batch`,
# `paper --csv` and `excitation --csv` write.
LOG_GROUPS = (('time', ('t',), True),
              ('lambda', ('lambda_a', 'lambda_b', 'lambda_c'), True),
              ('force', ('force_a', 'force_b', 'force_c'), True))
JOINT_STATE_TYPE = 'sensor_msgs/msg/JointState'

Log = namedtuple('Log', ('times', 'lambdas', 'forces', 'source', 'origin'),
                 defaults=(0,))
Log.__doc__ = """A measured log: ``times`` (N,) s, ``lambdas`` (N, 3) m and
``forces`` (N, 3) N of actuators A, B, C; ``source`` names it; ``times``
are counted from ``origin`` (ns; a bag's first header stamp, else 0)."""

Samples = namedtuple('Samples', (
    'times', 'positions', 'velocities', 'accelerations', 'forces',
    'segments', 'rate'))
Samples.__doc__ = """A log prepared for identification (:func:`prepare`).

(N,) times (s) and (N, 3) platform positions (m), velocities (m/s),
accelerations (m/s^2) and filtered forces (N); ``segments``: how many
pieces of the log they come from; ``rate``: their sampling rate after the
decimation (Hz).
"""

Base = namedtuple('Base', ('names', 'independent', 'matrix'))
Base.__doc__ = """The base parameters (:func:`base_parameters`).

``matrix`` ``P`` (n_base, 12): ``beta = P theta`` and ``W theta = W[:,
independent] beta`` for every state; ``independent``: the standard
parameter carrying each base parameter (its column of ``P`` is a unit
one); ``names``: each as a combination, e.g. ``'m5 + 3 m4'``.
"""

Identification = namedtuple('Identification', (
    'base', 'values', 'nominal', 'std', 'relative_std', 'condition',
    'residual_rms', 'force_rms', 'samples', 'robot', 'notes'))
Identification.__doc__ = """What :func:`identify` found.

Per base parameter: ``values`` (identified), ``nominal`` (of the nominal
robot), ``std`` and ``relative_std`` (%, ``100 std / |value|``);
``condition``: of the base regressor with unit-norm columns;
``residual_rms`` and ``force_rms``: per actuator (N), of the residual and
of the filtered forces; ``samples``: the :class:`Samples` used; ``robot``:
the identified :class:`Robot` (:func:`split`); ``notes``: what the split
rule had to do beyond the plain rule, as sentences.
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
    unit = robot.replace(**dict.fromkeys(MASSES, 1.0),
                         friction_viscous=mechanics.ZERO,
                         friction_coulomb=mechanics.ZERO)
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
                unit.replace(**{kind: one}), reference.lambdadot)
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
    names = tuple(_combination_name(row, j)
                  for row, j in zip(matrix, independent))
    return Base(names, tuple(int(j) for j in independent), matrix)


def _combination_name(row, carrier):
    """Name ``sum_k row_k theta_k``, the carrier first: ``'m5 + 3 m4'``."""
    order = [carrier] + [k for k in range(len(row))
                         if k != carrier and row[k] != 0.0]
    text = ''
    for k in order:
        c = row[k]
        rounded = round(c)
        size = abs(c)
        if abs(c - rounded) <= COMBINATION_TOLERANCE * max(1.0, size):
            size = abs(rounded)
        factor = '' if size == 1 else f'{size:.6g} '
        sign = '-' if c < 0 else '+'
        text += (f'{"-" if c < 0 else ""}' if not text else f' {sign} ') \
            + factor + STANDARD[k]
    return text


def prepare(robot, log, cutoff=DEFAULT_CUTOFF, force_lag=0.0):
    """
    Turn a :class:`Log` into :class:`Samples` for the least squares.

    Sorted by time (equal stamps: the first kept); split into segments at
    gaps longer than GAP_FACTOR median periods and GAP_SHARE / cutoff;
    each segment interpolated linearly onto a uniform grid of the median
    period (exact where the stamps are on it), the forces taken as applied
    ``force_lag`` s before their stamps (a drive or a simulator that
    reports with each state the force it held over the last period of
    ``dt``: ``dt / 2``); the platform positions from ``lambda``
    (:func:`mechanics.forward_kinematics`, ``robot``'s geometry); positions
    and forces through the same zero-phase Butterworth low-pass of
    ``cutoff`` Hz (order FILTER_ORDER, forwards and backwards), so that
    the forces and the motion computed from the positions keep the same
    phase and attenuation; velocities and accelerations by central
    differences of the filtered positions (``(r+ - r-) / 2 dt``, ``(r+ -
    2 r + r-) / dt^2``: for the filtered band, errors of about ``(2 pi f
    dt)^2 / 6``, 1e-4 at 10 Hz and 500 Hz). ``1 / cutoff`` s at each end of
    a segment are dropped, and segments too short for that. Then one
    sample in ``floor(rate / (2 cutoff))`` is kept (parallel decimation,
    as Gautier's: the filtered signals hold nothing above the cutoff, so a
    rate of twice the cutoff keeps all they carry, and the least squares'
    residuals become nearly uncorrelated, which the standard deviations of
    :func:`identify` assume). Raises :class:`LogError`.
    """
    import scipy.signal
    times = np.asarray(log.times, dtype=float)
    lambdas = np.asarray(log.lambdas, dtype=float)
    forces = np.asarray(log.forces, dtype=float)
    if not (times.ndim == 1 and lambdas.shape == forces.shape
            == (len(times), 3)):
        raise LogError(f'{log.source}: times (N,), lambdas and forces '
                       f'(N, 3) expected')
    if not (np.isfinite(times).all() and np.isfinite(lambdas).all()
            and np.isfinite(forces).all()):
        raise LogError(f'{log.source}: the log holds values that are not '
                       'finite')
    order = np.argsort(times, kind='stable')
    times, lambdas, forces = times[order], lambdas[order], forces[order]
    keep = np.concatenate(([True], np.diff(times) > 0.0))
    times, lambdas, forces = times[keep], lambdas[keep], forces[keep]
    if len(times) < 3:
        raise LogError(f'{log.source}: {len(times)} distinct samples: too '
                       'few to identify anything')
    period = float(np.median(np.diff(times)))
    rate = 1.0 / period
    if not 0.0 < cutoff < 0.5 * rate:
        raise LogError(f'{log.source}: the cutoff {cutoff:g} Hz must lie in '
                       f'(0, {0.5 * rate:g}) Hz, half the sampling rate '
                       f'{rate:g} Hz')
    sos = scipy.signal.butter(FILTER_ORDER, cutoff, fs=rate, output='sos')
    # (1e-9: a median period rounded up must not change these counts.)
    trim = int(math.ceil(rate / cutoff * (1.0 - 1e-9)))
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
        lam = np.column_stack([np.interp(grid, t, lambdas[start:end, j])
                               for j in range(3)])
        force = np.column_stack([np.interp(grid, t - force_lag,
                                           forces[start:end, j])
                                 for j in range(3)])
        try:
            position = mechanics.forward_kinematics(robot, lam)
        except mechanics.WorkspaceError as error:
            raise LogError(f'{log.source}: lambda at t = '
                           f'{grid[error.row]:.6g} s: {error}') from None
        position = scipy.signal.sosfiltfilt(sos, position, axis=0)
        force = scipy.signal.sosfiltfilt(sos, force, axis=0)
        inner = slice(trim, len(grid) - trim, step)
        ahead = position[trim + 1:len(grid) - trim + 1:step]
        behind = position[trim - 1:len(grid) - trim - 1:step]
        middle = position[inner]
        pieces.append((grid[inner], middle, (ahead - behind) * (0.5 * rate),
                       (ahead - 2.0 * middle + behind) * (rate * rate),
                       force[inner]))
    if not pieces:
        raise LogError(f'{log.source}: no piece of the log lasts more than '
                       f'{2 * trim * period:.3g} s (twice 1 / cutoff) '
                       'between gaps')
    columns = [np.concatenate(c) for c in zip(*pieces)]
    return Samples(*columns, len(pieces), rate / step)


def identify(robot, log, cutoff=DEFAULT_CUTOFF, base=None, force_lag=0.0):
    """
    Identify the base parameters from a :class:`Log` (an Identification).

    ``robot``: the nominal robot (its geometry, gravity and
    ``friction_velocity`` are taken as known, its masses and friction are
    the nominal values of the split rule); ``cutoff`` (Hz) and
    ``force_lag`` (s): of :func:`prepare`; ``base``: a :class:`Base`
    (default :func:`base_parameters`).
    Ordinary least squares on every sample and actuator
    (``numpy.linalg.lstsq`` on unit-norm columns), the standard deviations
    from the residual's variance ``|r|^2 / (3N - n_base)`` and ``(W^T
    W)^-1``. Raises :class:`LogError` or :class:`IdentificationError`.
    """
    base = base or base_parameters(robot)
    samples = prepare(robot, log, cutoff, force_lag)
    count = len(base.independent)
    if len(samples.times) < MIN_SAMPLES_PER_PARAMETER * count:
        raise LogError(f'{log.source}: {len(samples.times)} usable '
                       f'samples, at least {MIN_SAMPLES_PER_PARAMETER * count}'
                       ' needed')
    try:
        w = regressor(robot, samples.positions, samples.velocities,
                      samples.accelerations)
    except mechanics.WorkspaceError as error:
        raise LogError(f'{log.source}: the sample at t = '
                       f'{samples.times[error.row]:.6g} s: {error}') from None
    a = w[:, :, list(base.independent)].reshape(-1, count)
    y = samples.forces.reshape(-1)
    norms = np.linalg.norm(a, axis=0)
    if not (norms > 0.0).all():
        unexcited = [base.names[i] for i in np.flatnonzero(norms == 0.0)]
        raise IdentificationError(f'{log.source}: the log does not excite '
                                  f'{", ".join(unexcited)} at all')
    scaled = a / norms
    solution, _, _, singular = np.linalg.lstsq(scaled, y, rcond=None)
    values = solution / norms
    residual = y - a @ values
    variance = residual @ residual / max(len(y) - count, 1)
    covariance = variance * np.linalg.pinv(scaled.T @ scaled) \
        / np.outer(norms, norms)
    std = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    with np.errstate(divide='ignore', invalid='ignore'):
        relative = 100.0 * std / np.abs(values)
    robot_out, notes = split(robot, base, values)
    return Identification(
        base, values, base.matrix @ standard_parameters(robot), std,
        relative, float(singular[0] / singular[-1]),
        np.sqrt(np.mean(residual.reshape(-1, 3) ** 2, axis=0)),
        np.sqrt(np.mean(samples.forces ** 2, axis=0)), samples, robot_out,
        notes)


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
    """Return the forces (N, 3) ``robot`` needs for the prepared samples."""
    return mechanics.solve_batch(robot, samples.positions,
                                 samples.velocities,
                                 samples.accelerations).force


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
               np.asarray(log.forces)[keep], log.source, log.origin)


def read_log(path, topic='joint_states', joint_names=JOINT_NAMES):
    """
    Read a log: a rosbag2 bag (:func:`read_bag`) or a CSV file (:func:`read_csv`).

    A directory, or a ``.mcap`` or ``.db3`` file inside one, is a bag;
    anything else a CSV file.
    """
    path = str(path)
    if path.endswith(('.mcap', '.db3')) and os.path.isfile(path):
        return read_bag(os.path.dirname(path) or '.', topic, joint_names)
    if os.path.isdir(path):
        return read_bag(path, topic, joint_names)
    return read_csv(path)


def read_csv(path):
    """
    Read a log from a CSV file: columns ``t`` (s), ``lambda_a`` ... (m), ``force_a`` ... (N).

    The columns of the tool's CSV files (``orthoglide batch``, ``paper
    --csv``, ``excitation --csv``), matched by name as
    :func:`csvfile.read_columns` does; others ignored. Raises
    :class:`LogError`.
    """
    try:
        values, _ = read_columns(path, LOG_GROUPS)
    except CsvError as error:
        raise LogError(str(error)) from None
    return Log(values['time'][:, 0], values['lambda'], values['force'],
               str(path))


def read_bag(path, topic='joint_states', joint_names=JOINT_NAMES):
    """
    Read a log from the ``sensor_msgs/JointState`` messages of a rosbag2 bag.

    ``path``: the bag's directory (MCAP or sqlite3 storage, read by the
    ``rosbags`` library, without ROS); ``topic`` (a leading ``/`` is
    added); ``joint_names``: the joints of actuators A, B, C, found by name
    in each message. Time is each message's header stamp (the measurement's
    time), in s from the earliest (``origin``, ns); position is lambda
    (m), effort the force (N). Raises :class:`LogError`.
    """
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:
        raise LogError('reading a rosbag2 bag needs the rosbags package '
                       '(pip install rosbags)') from None
    name = topic if topic.startswith('/') else '/' + topic
    times, lambdas, forces = [], [], []
    orders = {}
    try:
        with Reader(path) as reader:
            connections = [c for c in reader.connections if c.topic == name]
            if not connections:
                topics = sorted({c.topic for c in reader.connections})
                raise LogError(f'{path}: no topic {name} in the bag (it has '
                               f'{", ".join(topics) or "none"})')
            for connection in connections:
                if connection.msgtype != JOINT_STATE_TYPE:
                    raise LogError(f'{path}: {name} carries '
                                   f'{connection.msgtype}, not '
                                   f'{JOINT_STATE_TYPE}')
            for _, _, raw in reader.messages(connections=connections):
                stamp, names, position, effort = _joint_state(raw)
                order = orders.get(names)
                if order is None:
                    order = orders[names] = _joint_order(
                        path, names, joint_names, len(position),
                        len(effort))
                times.append(stamp)
                lambdas.append([position[k] for k in order])
                forces.append([effort[k] for k in order])
    except LogError:
        raise
    except Exception as error:  # rosbags' errors, unreadable files
        raise LogError(f'{path}: cannot read the bag: {error}') from None
    if not times:
        raise LogError(f'{path}: no message on {name}')
    stamps = np.array(times, dtype=np.int64)
    origin = int(stamps.min())
    return Log((stamps - origin) * 1e-9, np.array(lambdas), np.array(forces),
               str(path), origin)


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
