"""
Identify the Orthoglide's masses and slider friction from a log, without ROS.

The actuator forces are linear in the masses and the friction coefficients:
``f = W(r_G, rdot_G, rddot_G) theta`` with the standard parameters
``theta = (m1 ... m6, c_A, c_B, c_C, F_A, F_B, F_C, ...)`` (kg, N s/m, N:
:func:`standard_names`) of a friction :class:`Law`: viscous + Coulomb, and
optionally a Coulomb level per direction (``F^-``) and a Stribeck excess
(``S``, whose speed ``v_b`` enters nonlinearly and is searched). The
geometry, gravity and the Coulomb smoothing speed are known (the nominal
robot's). The steps, each a function here:

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
- :func:`identify`: the drive's lag (the forces' delay on the states) by
  the least residual, the friction law by the error on held-out parts of
  the log, least squares for ``beta`` (bounded where the ordinary one
  leaves what a robot can be), with relative standard deviations, the
  condition number and the RMS residual per actuator, a refusal when a
  base parameter is not excited (its relative standard deviation above
  MAX_RELATIVE_STD), and a complete :class:`Robot` by the split rule of
  :func:`split`;
- :func:`validate`: a robot's forces (the full model, not the regressor)
  against another log's.

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
LEGS = ('a', 'b', 'c')
# The friction coefficients by kind: the Robot field each sets, its unit,
# its meaning.
FRICTION_KINDS = {
    'viscous': ('friction_viscous', 'N s/m', 'viscous friction'),
    'coulomb': ('friction_coulomb', 'N', 'Coulomb friction'),
    'coulomb_negative': ('friction_coulomb_negative', 'N',
                         'Coulomb friction moving -lambda'),
    'stribeck': ('friction_stribeck', 'N', 'Stribeck excess'),
}

Law = namedtuple('Law', ('direction', 'stribeck'))
Law.__doc__ = """A friction law to identify: viscous + Coulomb friction,
with a Coulomb level per direction (``direction``) and a Stribeck excess
(``stribeck``) or not. Named by :func:`law_name`, read by
:func:`parse_law`."""
PLAIN = Law(False, False)
# Every law identify chooses from, the simplest first.
LAWS = (PLAIN, Law(True, False), Law(False, True), Law(True, True))


def law_name(law):
    """Name a :class:`Law`: ``coulomb``, ``coulomb+direction``, ..."""
    return 'coulomb' + '+direction' * law.direction \
        + '+stribeck' * law.stribeck


def parse_law(text):
    """Return the :class:`Law` named ``text`` (ValueError if none is)."""
    for law in LAWS:
        if law_name(law) == text:
            return law
    raise ValueError(f'unknown friction law {text!r}: one of '
                     + ', '.join(law_name(law) for law in LAWS))


def friction_kinds(law):
    """Return the friction coefficients' kinds of ``law``, in order."""
    return ('viscous', 'coulomb') + ('coulomb_negative',) * law.direction \
        + ('stribeck',) * law.stribeck


def standard_names(law=PLAIN):
    """Return the standard parameters' names of ``law`` (``m1``, ``viscous_a``...)."""
    return MASSES + tuple(f'{kind}_{leg}' for kind in friction_kinds(law)
                          for leg in LEGS)


# The standard parameters of the plain law (the package's law before the
# Coulomb level per direction and the Stribeck term).
STANDARD = standard_names(PLAIN)
UNITS = dict.fromkeys(MASSES, 'kg') | {
    f'{kind}_{leg}': unit for kind, (_, unit, _) in FRICTION_KINDS.items()
    for leg in LEGS}
# What each standard parameter is, in words (the masses' from the robot's
# parameter descriptions).
MEANINGS = {m: DESCRIPTIONS[m].split(';')[0] for m in MASSES} | {
    f'{kind}_{leg}': f'{words} of slider {leg.upper()}'
    for kind, (_, _, words) in FRICTION_KINDS.items() for leg in LEGS}
# Lowest value of each standard parameter (a Robot's bound).
LOWER = dict.fromkeys(MASSES, LIMITS['m1'][0]) | {
    f'{kind}_{leg}': LIMITS[field][0]
    for kind, (field, _, _) in FRICTION_KINDS.items() for leg in LEGS}

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
# A step between two samples longer than this many median periods is a
# missing sample (interpolated inside a segment; counted in the report).
MISSING_FACTOR = 1.5
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

# The drive's lag (the forces' delay on the states' stamps), when it is
# not given: searched within +-LAG_SEARCH s, first on the log's period,
# then on a quarter of it around the best, and refined by a parabola
# through the three best (doc/identification.md).
LAG_SEARCH = 0.01
LAG_STEPS = 4
# The Stribeck speeds v_b searched (m/s): log-spaced over the speeds at
# which guideways show a Stribeck rise.
STRIBECK_VELOCITIES = tuple(np.geomspace(0.002, 0.1, 12).tolist())
# The friction law is chosen by the RMS error on held-out parts of the log
# (FOLDS contiguous blocks, each predicted from the others): a law with
# more terms is chosen only when it lowers that error by more than
# SELECTION_MARGIN (a share) and by more than SELECTION_FLOOR of the RMS
# force: terms that noise alone would pick are left out.
FOLDS = 5
SELECTION_MARGIN = 0.02
SELECTION_FLOOR = 1e-3

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

Base = namedtuple('Base', ('names', 'independent', 'matrix', 'meanings',
                           'law'), defaults=(PLAIN,))
Base.__doc__ = """The base parameters (:func:`base_parameters`) of a law.

``matrix`` ``P`` (n_base, n): ``beta = P theta`` and ``W theta = W[:,
independent] beta`` for every state, ``theta`` the standard parameters
of ``law`` (:func:`standard_names`); ``independent``: the standard
parameter carrying each base parameter (its column of ``P`` is a unit
one); ``names``: each as a combination, e.g. ``'m5 + 3 m4'``;
``meanings``: the same in words (:data:`MEANINGS`).
"""

Candidate = namedtuple('Candidate', ('law', 'stribeck_velocity',
                                     'held_out_rms'))
Candidate.__doc__ = """A friction law tried by :func:`identify`: its
Stribeck speed (m/s, the best searched; None without the term) and its RMS
error (N) on held-out parts of the log."""

Identification = namedtuple('Identification', (
    'base', 'values', 'nominal', 'std', 'relative_std', 'condition',
    'residual_rms', 'force_rms', 'samples', 'predicted', 'robot', 'notes',
    'law', 'stribeck_velocity', 'force_lag', 'lag_estimated', 'candidates',
    'law_chosen', 'bounded'))
Identification.__doc__ = """What :func:`identify` found.

Per base parameter: ``values`` (identified), ``nominal`` (of the nominal
robot), ``std`` and ``relative_std`` (%, ``100 std / max(|value|,
resolution)``, RESOLUTION);
``condition``: of the base regressor with unit-norm columns;
``residual_rms`` and ``force_rms``: per actuator (N), of the residual and
of the filtered forces; ``samples``: the :class:`Samples` used;
``predicted``: the forces (N, 3) the identified parameters give for them;
``robot``: the identified :class:`Robot` (:func:`split`); ``notes``: what
the split rule had to do beyond the plain rule, as sentences; ``law``: the
friction :class:`Law` and ``stribeck_velocity`` its Stribeck speed (m/s,
None without the term); ``force_lag`` (s) and ``lag_estimated`` (False:
given); ``candidates``: every law tried (:class:`Candidate`);
``law_chosen``: why ``law`` (a sentence); ``bounded``: the base parameters
the bounded least squares held at a bound, as sentences.
"""

Validation = namedtuple('Validation', (
    'source', 'samples', 'measured', 'predicted', 'rms', 'max', 'explained',
    'force_lag', 'lag_estimated'))
Validation.__doc__ = """A robot's forces against a log's (:func:`validate`).

``samples``: the log's :class:`Samples` (their regressor unused: None);
``measured`` and ``predicted``: (N, 3) forces (N) through the same
low-pass; per actuator ``rms`` and ``max`` of the error (N) and
``explained``: the share of the force explained, ``1 - sum(e^2) /
sum(f^2)``; ``force_lag`` (s) and ``lag_estimated`` as in
:class:`Identification`.
"""


class LogError(ValueError):
    """A log that cannot be read or used; the message says why."""


class IdentificationError(ValueError):
    """An identification that cannot give a robot; the message says why."""


def standard_parameters(robot, law=PLAIN):
    """
    Return ``theta`` of ``robot``: its values of :func:`standard_names`.

    Without the ``direction`` term, the Coulomb coefficient is the mean of
    the robot's two levels; without ``stribeck`` its Stribeck term is left
    out.
    """
    coulomb = robot.friction_coulomb if law.direction else tuple(
        0.5 * (f + g) for f, g in zip(robot.friction_coulomb,
                                      robot.friction_coulomb_negative))
    values = [getattr(robot, m) for m in MASSES] \
        + list(robot.friction_viscous) + list(coulomb)
    if law.direction:
        values += robot.friction_coulomb_negative
    if law.stribeck:
        values += robot.friction_stribeck
    return np.array(values, dtype=float)


def with_parameters(robot, theta, law=PLAIN, stribeck_velocity=None):
    """
    Return ``robot`` with the standard parameters ``theta`` of ``law``.

    Validated. Without the ``direction`` term both Coulomb levels take the
    Coulomb coefficient; without ``stribeck`` there is no Stribeck term;
    ``stribeck_velocity`` (m/s), if given, sets its speed.
    """
    values = dict(zip(standard_names(law), (float(v) for v in theta)))
    changes = {m: values[m] for m in MASSES}
    for kind in ('viscous', 'coulomb', 'coulomb_negative', 'stribeck'):
        source = kind if kind in friction_kinds(law) else (
            'coulomb' if kind == 'coulomb_negative' else None)
        changes[FRICTION_KINDS[kind][0]] = tuple(
            values[f'{source}_{leg}'] if source else 0.0 for leg in LEGS)
    if stribeck_velocity is not None:
        changes['friction_stribeck_velocity'] = float(stribeck_velocity)
    return robot.replace(**changes)


def friction_columns(robot, lambdadot, law=PLAIN):
    """
    Return the friction part of ``W`` (N, 3, k) at slider speeds (m/s).

    One column per friction coefficient of ``law``: the force of
    :func:`mechanics.friction_force` for ``robot`` without friction but
    that coefficient 1 (``friction_velocity`` and
    ``friction_stribeck_velocity`` are ``robot``'s). Without the
    ``direction`` term a Coulomb coefficient acts both ways.
    """
    return np.concatenate([_kind_columns(robot, lambdadot, kind,
                                         law.direction)
                           for kind in friction_kinds(law)], axis=2)


def _kind_columns(robot, lambdadot, kind, direction):
    """Return the columns (N, 3, 3) of ``kind``'s three coefficients."""
    bare = robot.frictionless()
    out = np.empty(lambdadot.shape + (3,))
    for j in range(3):
        one = tuple(float(j == i) for i in range(3))
        unit = {FRICTION_KINDS[kind][0]: one}
        if kind == 'coulomb' and not direction:
            unit['friction_coulomb_negative'] = one
        out[:, :, j] = mechanics.friction_force(bare.replace(**unit),
                                                lambdadot)
    return out


def regressor(robot, positions, velocities, accelerations, law=PLAIN,
              margin=mechanics.DEFAULT_SINGULARITY_MARGIN):
    """
    Return ``W`` (N, 3, n): ``force = W @ theta`` per sample and actuator.

    ``positions`` (m), ``velocities`` (m/s), ``accelerations`` (m/s^2):
    (N, 3) arrays of the platform centre in frame 0. Built from
    :func:`mechanics.solve_batch` on ``robot``'s geometry and gravity (its
    masses and friction do not matter): column ``m_i`` is the force of a
    robot whose masses are all 2 kg less that of one whose masses are all
    1 kg but ``m_i`` (exact: the rigid forces are ``sum_i m_i W_i``), the
    friction columns :func:`friction_columns` of ``law`` at the samples'
    ``lambdadot``. Raises :class:`mechanics.WorkspaceError` as
    ``solve_batch`` does.
    """
    rigid, reference = _rigid_columns(robot, positions, velocities,
                                      accelerations, margin)
    return np.concatenate((rigid, friction_columns(
        robot, reference.lambdadot, law)), axis=2)


def _rigid_columns(robot, positions, velocities, accelerations,
                   margin=mechanics.DEFAULT_SINGULARITY_MARGIN):
    """
    Return the masses' columns of ``W`` (N, 3, 6) and the kinematics.

    The kinematics: a :class:`mechanics.Solution` along the motion.
    """
    unit = robot.frictionless().replace(**dict.fromkeys(MASSES, 1.0))
    reference = mechanics.solve_batch(unit, positions, velocities,
                                      accelerations, margin)
    out = np.empty(reference.force.shape + (len(MASSES),))
    for i, name in enumerate(MASSES):
        heavier = mechanics.solve_batch(unit.replace(**{name: 2.0}),
                                        positions, velocities,
                                        accelerations, margin)
        out[:, :, i] = heavier.force - reference.force
    return out, reference


def base_parameters(robot, law=PLAIN, samples=BASE_SAMPLES, seed=0):
    """
    Find the base parameters of ``robot``'s regressor (a :class:`Base`).

    ``W`` of ``law`` at ``samples`` random states (see BASE_BOX and its
    neighbours; ``seed`` for the generator), each column weighted by its
    parameter's nominal value in ``robot`` (a parameter whose nominal
    value is zero, such as friction on the paper's robot: its column
    scaled to unit RMS), goes through a QR decomposition with column
    pivoting (``scipy.linalg.qr``). The pivots above RANK_TOLERANCE of the
    first are the independent parameters; each other column is a
    combination of those, found by least squares, which gives ``P``. The
    weighting makes the parameter with the largest nominal contribution
    carry each combination (the platform's ``m5`` rather than the rods'
    ``m4``), so that :func:`split` keeps the smaller ones at their nominal
    values.
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
    weights = np.where(nominal > 0.0, nominal, 1.0 / rms)
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


Piece = namedtuple('Piece', ('grid', 'stamps', 'forces', 'position',
                             'velocity', 'acceleration', 'lambdas',
                             'lambdadot', 'rigid'))


class Motion:
    """
    A log on uniform grids, piece by piece between its gaps (:func:`prepare`).

    Holds each piece's motion and the masses' columns of ``W`` at the log's
    rate, and filters, trims and decimates whatever is computed from them
    alike (:meth:`filtered`): the forces at any lag (:meth:`forces`), the
    friction columns at any Stribeck speed (:meth:`friction`), a robot's
    forces (:meth:`model_forces`).
    """

    def __init__(self, robot, log, cutoff=DEFAULT_CUTOFF):
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
                rigid, reference = _rigid_columns(robot, position, velocity,
                                                  acceleration)
            except mechanics.WorkspaceError as error:
                raise LogError(f'{log.source}: the motion at t = '
                               f'{grid[error.row]:.6g} s: {error}') from None
            self.pieces.append(Piece(
                grid, t, forces[start:end], position, velocity, acceleration,
                reference.lambda_, reference.lambdadot, rigid))
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
        self._kinds = {}

    def kept(self, arrays):
        """Return the samples kept of per-piece arrays, joined."""
        return np.concatenate([a[i] for a, i in zip(arrays, self.inner)])

    def filtered(self, arrays):
        """Return per-piece arrays (n, ...) low-passed, trimmed, decimated."""
        return self.kept([self._signal.sosfiltfilt(
            self.sos, a.reshape(len(a), -1), axis=0).reshape(a.shape)
            for a in arrays])

    def forces(self, lag=0.0):
        """Return the forces taken as applied ``lag`` s before their stamps."""
        return self.filtered([np.column_stack([
            np.interp(p.grid, p.stamps - lag, p.forces[:, j])
            for j in range(3)]) for p in self.pieces])

    def friction(self, law, stribeck_velocity=None):
        """Return the friction columns of ``law`` (at that Stribeck speed)."""
        return np.concatenate([self._kind(kind, law.direction,
                                          stribeck_velocity)
                               for kind in friction_kinds(law)], axis=2)

    def _kind(self, kind, direction, stribeck_velocity):
        """
        Return the filtered columns (M, 3, 3) of one kind (kept).

        A coefficient's column acts on its own actuator only: that one
        series is filtered.
        """
        key = (kind, direction and kind == 'coulomb',
               stribeck_velocity if kind == 'stribeck' else None)
        if key not in self._kinds:
            robot = self.robot if key[2] is None else self.robot.replace(
                friction_stribeck_velocity=key[2])
            own = self.filtered([
                np.einsum('njj->nj', _kind_columns(robot, p.lambdadot, kind,
                                                   direction))
                for p in self.pieces])
            columns = np.zeros(own.shape + (3,))
            for j in range(3):
                columns[:, j, j] = own[:, j]
            self._kinds[key] = columns
        return self._kinds[key]

    def model_forces(self, robot):
        """Return ``robot``'s forces along the motion (the full model)."""
        return self.filtered([mechanics.solve_batch(
            robot, p.position, p.velocity, p.acceleration).force
            for p in self.pieces])

    def samples(self, regressor, forces, law=PLAIN):
        """Return the :class:`Samples` of a regressor and forces."""
        return Samples(self.times, regressor, forces, len(self.pieces),
                       self.rate, law,
                       self.kept([p.lambdas for p in self.pieces]),
                       self.kept([p.lambdadot for p in self.pieces]),
                       self.coverage)


def prepare(robot, log, cutoff=DEFAULT_CUTOFF, force_lag=0.0, law=PLAIN):
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
    2. the regressor ``W`` of ``law`` (:func:`regressor`) at every sample;
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
    motion = Motion(robot, log, cutoff)
    _check_lag(log.source, force_lag, cutoff)
    return motion.samples(
        np.concatenate((motion.rigid, motion.friction(law)), axis=2),
        motion.forces(force_lag), law)


def _check_lag(source, force_lag, cutoff):
    if not (math.isfinite(force_lag) and abs(force_lag) < 1.0 / cutoff):
        raise LogError(f'{source}: the force lag {force_lag:g} s must be '
                       f'shorter than 1 / cutoff = {1.0 / cutoff:g} s')


def estimate_lag(motion, residual):
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


def _scaled(a):
    """Return ``a`` with unit-norm columns and the norms (zero: kept 0)."""
    norms = np.linalg.norm(a, axis=0)
    return a / np.where(norms > 0.0, norms, 1.0), norms


# The searches (lag, law, Stribeck speed) solve many least squares on the
# same columns: by the normal equations of the unit-norm columns, whose
# Gram matrix is small (n_base^2), solved by lstsq (no failure on a column
# a log does not excite). The final estimate is the SVD's (_least_squares).

def _residual_of(a):
    """Return ``forces -> |y - a x|^2`` for the least squares on ``a``."""
    scaled, _ = _scaled(a)
    gram = scaled.T @ scaled

    def residual(forces):
        y = forces.reshape(-1)
        b = scaled.T @ y
        return float(y @ y - b @ np.linalg.lstsq(gram, b, rcond=None)[0])
    return residual


def _held_out_rms(a, y, folds=FOLDS):
    """RMS error (N) of each of ``folds`` blocks predicted from the others."""
    rows = len(y) // 3
    edges = np.linspace(0, rows, folds + 1).astype(int) * 3
    scaled, _ = _scaled(a)
    blocks = [(scaled[i:j], y[i:j]) for i, j in zip(edges[:-1], edges[1:])]
    grams = [(m.T @ m, m.T @ v) for m, v in blocks]
    gram, b = sum(g for g, _ in grams), sum(c for _, c in grams)
    squares = 0.0
    for (m, v), (g, c) in zip(blocks, grams):
        x = np.linalg.lstsq(gram - g, b - c, rcond=None)[0]
        squares += float(np.sum((v - m @ x) ** 2))
    return math.sqrt(squares / len(y))


def _laws_tried(motion, forces, laws, stribeck_velocity):
    """Return a :class:`Candidate` per law: held-out RMS, best v_b."""
    y = forces.reshape(-1)
    candidates = []
    for law in laws:
        speeds = ((stribeck_velocity,) if stribeck_velocity is not None
                  else STRIBECK_VELOCITIES) if law.stribeck else (None,)
        scores = [(_held_out_rms(_base_columns(motion, law, v), y), v)
                  for v in speeds]
        rms, speed = min(scores)
        candidates.append(Candidate(law, speed, rms))
    return candidates


def _base_columns(motion, law, stribeck_velocity, base=None):
    """Return the base regressor (3N, n_base) of ``law`` along ``motion``."""
    base = base or _base(motion.robot, law)
    w = np.concatenate((motion.rigid, motion.friction(law,
                                                      stribeck_velocity)),
                       axis=2)
    return w[:, :, list(base.independent)].reshape(-1, len(base.independent))


_BASES = {}


def _base(robot, law):
    """Return :func:`base_parameters` of ``robot`` and ``law`` (kept)."""
    key = (robot, law)
    if key not in _BASES:
        if len(_BASES) >= 16:
            _BASES.clear()
        _BASES[key] = base_parameters(robot, law)
    return _BASES[key]


def _refined_speed(motion, law, forces, speed):
    """
    Return the Stribeck speed of the least residual near ``speed`` (m/s).

    Between the neighbours of ``speed`` in STRIBECK_VELOCITIES, by
    Brent's bounded search on its logarithm (the grid is log-spaced).
    """
    from scipy.optimize import minimize_scalar
    grid = np.log(STRIBECK_VELOCITIES)
    k = int(np.argmin(np.abs(grid - math.log(speed))))
    low, high = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]

    def residual(log_speed):
        return _residual_of(_base_columns(motion, law, math.exp(
            log_speed)))(forces)
    found = minimize_scalar(residual, bounds=(low, high), method='bounded',
                            options={'xatol': 1e-3})
    return float(math.exp(found.x)) if found.fun < residual(
        math.log(speed)) else speed


def _chosen(candidates, force_rms):
    """Return the simplest candidate within the selection margins, why."""
    best = min(candidates, key=lambda c: c.held_out_rms)
    floor = SELECTION_FLOOR * force_rms
    for candidate in sorted(candidates, key=lambda c: (sum(c.law),
                                                       c.held_out_rms)):
        if candidate.held_out_rms <= best.held_out_rms * (
                1.0 + SELECTION_MARGIN) + floor:
            if candidate is best:
                return candidate, (f'{law_name(candidate.law)}: the least '
                                   'held-out error')
            return candidate, (
                f'{law_name(candidate.law)}: within '
                f'{100 * SELECTION_MARGIN:g} % of the least held-out error '
                f'({law_name(best.law)}, {best.held_out_rms:.4g} N) with '
                'fewer terms')
    return best, law_name(best.law)


def identify(robot, log, cutoff=DEFAULT_CUTOFF, base=None, force_lag=None,
             max_relative_std=MAX_RELATIVE_STD, friction=None,
             stribeck_velocity=None):
    """
    Identify the base parameters from a :class:`Log` (an Identification).

    ``robot``: the nominal robot (its geometry, gravity and
    ``friction_velocity`` are taken as known, its masses and friction are
    the nominal values of the split rule); ``cutoff`` (Hz): of
    :func:`prepare`; ``force_lag`` (s): of :func:`prepare`, None to
    estimate it (:func:`estimate_lag`, with the richest law tried, at
    each Stribeck speed searched); ``friction``: the :class:`Law`, None to
    choose it: each law of LAWS (its Stribeck speed the best of
    STRIBECK_VELOCITIES, or ``stribeck_velocity`` m/s) is scored by its
    RMS error on FOLDS held-out blocks, and the simplest within
    SELECTION_MARGIN of the best is chosen; the Stribeck speed is then
    refined between its neighbours on the grid (:func:`_refined_speed`)
    unless given; ``base``: a :class:`Base`
    (default :func:`base_parameters`; given, its law is the one used).

    Least squares on every sample and actuator (by the SVD of the base
    regressor with unit-norm columns), the standard deviations from the
    residual's variance ``|r|^2 / (3N - n_base)`` and ``(W^T W)^-1``.
    Where its solution leaves what a robot can be (a friction coefficient
    below zero, a mass combination below its members' bounds), a bounded
    least squares (``scipy.optimize.lsq_linear``) gives the values; the
    deviations stay those of the unbounded problem. Refused
    (:class:`IdentificationError`, naming them) when a base parameter's
    relative standard deviation (against the larger of its estimate and
    its RESOLUTION) exceeds ``max_relative_std`` (%) or its column is
    zero: the log does not excite it. Raises :class:`LogError` for a log
    it cannot use.
    """
    motion = Motion(robot, log, cutoff)
    if base is not None:
        friction = base.law
    laws = LAWS if friction is None else (friction,)
    richest = laws[-1]
    if force_lag is None:
        speeds = ((stribeck_velocity,) if stribeck_velocity is not None
                  else STRIBECK_VELOCITIES) if richest.stribeck else (None,)
        residuals = [_residual_of(_base_columns(motion, richest, v))
                     for v in speeds]
        force_lag = estimate_lag(motion, lambda f: min(r(f)
                                                       for r in residuals))
        lag_estimated = True
    else:
        _check_lag(log.source, force_lag, cutoff)
        lag_estimated = False
    forces = motion.forces(force_lag)
    force_rms = np.sqrt(np.mean(forces ** 2, axis=0))
    candidates = _laws_tried(motion, forces, LAWS if friction is None
                             else (friction,), stribeck_velocity)
    if friction is None:
        chosen, why = _chosen(candidates, float(np.sqrt(np.mean(
            force_rms ** 2))))
    else:
        chosen, why = candidates[0], f'{law_name(friction)}: as asked'
    law, speed = chosen.law, chosen.stribeck_velocity
    if law.stribeck and stribeck_velocity is None:
        speed = _refined_speed(motion, law, forces, speed)
    base = base or _base(robot, law)
    count = len(base.independent)
    if len(motion.times) < MIN_SAMPLES_PER_PARAMETER * count:
        raise LogError(f'{log.source}: {len(motion.times)} usable '
                       f'samples, at least {MIN_SAMPLES_PER_PARAMETER * count}'
                       f' needed ({MIN_SAMPLES_PER_PARAMETER} per base '
                       f'parameter, at {motion.rate:.4g} Hz after the '
                       'decimation)')
    w = np.concatenate((motion.rigid, motion.friction(law, speed)), axis=2)
    samples = motion.samples(w, forces, law)
    a = w[:, :, list(base.independent)].reshape(-1, count)
    y = forces.reshape(-1)
    values, std, singular, bounded = _least_squares(a, y, base)
    residual = y - a @ values
    names = standard_names(law)
    resolution = [RESOLUTION[UNITS[names[j]]] for j in base.independent]
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
    robot_out, notes = split(robot, base, values, speed)
    return Identification(
        base, values, base.matrix @ standard_parameters(robot, law), std,
        relative, float(singular[0] / singular[-1]),
        np.sqrt(np.mean(residual.reshape(-1, 3) ** 2, axis=0)), force_rms,
        samples, (a @ values).reshape(-1, 3), robot_out, notes, law, speed,
        float(force_lag), lag_estimated, tuple(candidates), why, bounded)


def _least_squares(a, y, base):
    """
    Solve ``a beta = y``: (values, std, singular values, bounded notes).

    By the SVD of ``a`` with unit-norm columns; a direction the log does
    not excite (a singular value below numpy's rank tolerance) adds
    nothing to ``beta`` and a huge deviation, rather than a division by
    zero. Where the solution breaks a bound of :func:`bounds`, the bounded
    least squares' instead, and a note per base parameter held at a bound.
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
    lower = bounds(base)
    bounded = []
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
            unit = UNITS[standard_names(base.law)[base.independent[i]]]
            bounded.append(
                f'{base.names[i]} was found {found[i]:.4g} {unit} by '
                f'ordinary least squares: held at its bound {lower[i]:.4g} '
                f'{unit} (bounded least squares)')
    return values, std, singular, bounded


def bounds(base):
    """
    Return the lowest value (n_base,) each base parameter of a robot has.

    ``row @ LOWER`` of a combination of members with coefficients >= 0
    (each member at its bound), else -inf (no bound).
    """
    lower = np.array([LOWER[n] for n in standard_names(base.law)])
    return np.array([row @ lower if (row >= 0.0).all() else -np.inf
                     for row in base.matrix])


def split(robot, base, values, stribeck_velocity=None):
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
    plain rule is a note. The friction law is ``base.law`` (with
    ``stribeck_velocity``, m/s). Raises :class:`IdentificationError` only
    when the robot so made is refused (a value beyond a bound of
    :data:`robot.LIMITS`).
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


def predict(robot, samples):
    """
    Return the forces (N, 3) ``robot`` needs for the prepared samples.

    Through the same low-pass as the samples' forces: ``W theta`` with
    their filtered regressor, for a robot of the geometry, gravity and
    friction speeds they were prepared with (:func:`validate` runs the
    full model instead).
    """
    return samples.regressor @ standard_parameters(robot, samples.law)


def validate(robot, log, cutoff=DEFAULT_CUTOFF, force_lag=None):
    """
    Compare ``robot``'s forces with a log's (a :class:`Validation`).

    The log prepared as by :func:`prepare`; the prediction is the full
    model's (:func:`mechanics.solve_batch` along the log's filtered
    motion, every friction term of ``robot`` included), through the same
    low-pass as the measured forces. ``force_lag`` (s): None to estimate
    the one that best matches the prediction (:func:`estimate_lag`).
    Raises :class:`LogError`.
    """
    motion = Motion(robot, log, cutoff)
    predicted = motion.model_forces(robot)
    if force_lag is None:
        force_lag = estimate_lag(motion, lambda f: float(np.sum(
            (f - predicted) ** 2)))
        lag_estimated = True
    else:
        _check_lag(log.source, force_lag, cutoff)
        lag_estimated = False
    measured = motion.forces(force_lag)
    error = measured - predicted
    squares = np.sum(measured ** 2, axis=0)
    # (No force at all on an actuator: nothing to explain, NaN.)
    explained = 1.0 - np.divide(np.sum(error ** 2, axis=0), squares,
                                out=np.full(3, np.nan), where=squares > 0.0)
    return Validation(
        log.source, motion.samples(None, measured), measured, predicted,
        np.sqrt(np.mean(error ** 2, axis=0)), np.abs(error).max(axis=0),
        explained, float(force_lag), lag_estimated)


def condition_number(robot, positions, velocities, accelerations,
                     base=None):
    """
    Condition number of the base regressor along a motion (no noise).

    (N, 3) arrays (m, m/s, m/s^2); ``base`` default
    :func:`base_parameters` of ``robot``. Columns scaled to unit norm, as
    :func:`identify` solves them: 1 is ideal, and the larger it is the
    more the noise of the log is amplified into the parameters.
    """
    base = base or _base(robot, PLAIN)
    w = regressor(robot, positions, velocities, accelerations, base.law)
    a = w[:, :, list(base.independent)].reshape(-1, len(base.independent))
    # The singular values' ratio, from the eigenvalues of the small Gram
    # matrix (exact to about 1e-16 times the condition number squared).
    scaled = a / np.linalg.norm(a, axis=0)
    eigenvalues = np.linalg.eigvalsh(scaled.T @ scaled)
    return float(math.sqrt(eigenvalues[-1] / max(eigenvalues[0], 0.0))) \
        if eigenvalues[0] > 0.0 else math.inf


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
