"""
An excitation optimized for identification, without ROS.

:func:`optimize` lowers the base regressor's condition number from a
seed's, never worse than the seed; :func:`check_size` bounds a file before
anything is computed (doc/identification.md#the-excitation).
"""

from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.formats import csvfile
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.tools import identification

# Samples per second along the motion for its condition number (the
# number changes by less than 1 % from 100 Hz to 1 kHz).
CONDITION_RATE = 100.0
# Evaluations of the condition number the search may make.
DEFAULT_EVALUATIONS = 400
# What a refused candidate costs (the log of a condition number).
_REFUSED_COST = 1e3
# Longest period (s): a log of two periods at 1 kHz within the readers'
# row limit (2,000,000 rows: 1000 s).
MAX_PERIOD = csvfile.MAX_ROWS / 2000.0
# Highest rate of an excitation file (Hz): a sample a microsecond.
MAX_RATE = 1e6

Design = namedtuple('Design', ('motion', 'condition', 'peak_force',
                               'start_condition', 'evaluations'))
Design.__doc__ = """What :func:`optimize` found.

``motion``: the :class:`trajectory.Excitation`; ``condition``: its
condition number; ``peak_force``: its largest actuator force (N, of the
robot); ``start_condition``: the seed's; ``evaluations``: condition
numbers computed.
"""


class _BudgetSpent(Exception):
    """The search used every evaluation it was given."""


def check_size(period, rate, harmonics=trajectory.EXCITATION_HARMONICS):
    """
    Refuse an excitation file of one ``period`` s at ``rate`` Hz too big.

    Before anything is allocated: ``period`` at most MAX_PERIOD; its rows
    (those of ``numpy.arange(0, period, 1 / rate)``) at most the readers'
    ``csvfile.MAX_ROWS`` and at least two per cycle of the highest of
    ``harmonics`` harmonics of ``1 / period``; ``rate`` at most MAX_RATE.
    Raises ValueError naming the bound; returns the rows.

    >>> check_size(6.0, 1000.0)
    6000
    """
    limit = csvfile.MAX_ROWS
    if not period <= MAX_PERIOD:
        raise ValueError(f'duration {period:g} s: above {MAX_PERIOD:g} s, '
                         'the longest excitation period (a log of two '
                         f'periods at 1 kHz within the readers\' {limit} '
                         'rows)')
    rows = period / (1.0 / rate) if rate > 0.0 else 0.0
    if not rows <= limit:
        raise ValueError(f'duration {period:g} s at {rate:g} Hz: {rows:.4g} '
                         f'rows, above the {limit} rows the package\'s '
                         'readers take: lower --rate or --duration')
    if not rate <= MAX_RATE:
        raise ValueError(f'rate {rate:g} Hz: above {MAX_RATE:g} Hz, a '
                         'sample a microsecond')
    rows = math.ceil(rows)
    if rows < 2 * harmonics:
        raise ValueError(f'duration {period:g} s at {rate:g} Hz: {rows} '
                         f'row(s), fewer than {2 * harmonics}: the file '
                         f'would not sample its highest harmonic '
                         f'({harmonics / period:.4g} Hz) twice a cycle: '
                         'raise --rate or --duration')
    return rows


def measure(robot, motion, base=None, rate=CONDITION_RATE):
    """Return the condition number and the peak |force| (N) of a motion."""
    times = np.arange(0.0, motion.period, 1.0 / rate)
    p, v, a = trajectory.excitation_batch(motion, times)
    force = mechanics.solve_batch(robot, p, v, a).force
    return (identification.condition_number(robot, p, v, a, base),
            float(np.abs(force).max()))


def optimize(robot, period, seed=0, max_force=math.inf,
             evaluations=DEFAULT_EVALUATIONS, **bounds):
    """
    Search an excitation of ``period`` s with a smaller condition number.

    From the coefficients of :func:`trajectory.excitation` of ``seed``;
    ``bounds``: ``box``, ``max_velocity``, ``max_acceleration``,
    ``harmonics`` and ``margin`` as :func:`trajectory.excitation` takes
    them; ``max_force`` (N): the largest actuator force allowed. Returns a
    :class:`Design`. Raises ValueError when the seed's own motion breaks
    a bound (as :func:`trajectory.excitation` does, or its force above
    ``max_force``).
    """
    from scipy.optimize import minimize
    harmonics = bounds.pop('harmonics', trajectory.EXCITATION_HARMONICS)
    start = trajectory.excitation(seed, period, harmonics, robot=robot,
                                  **bounds)
    base = identification.base_parameters(
        robot, identification.design_law(robot))
    start_condition, start_force = measure(robot, start, base)
    if start_force > max_force:
        raise ValueError(f'the excitation of seed {seed} needs '
                         f'{start_force:.4g} N, above the force limit '
                         f'{max_force:g} N: choose smaller bounds')
    shape = start.sines.shape
    best = [start_condition, start, start_force]
    count = [0]

    def cost(x):
        if count[0] >= evaluations:     # the budget is a bound, not a hint
            raise _BudgetSpent
        count[0] += 1
        try:
            motion = trajectory.shaped_excitation(
                x[:x.size // 2].reshape(shape), x[x.size // 2:].reshape(shape),
                period, robot=robot, **bounds)
            condition, force = measure(robot, motion, base)
        except (ValueError, mechanics.WorkspaceError):
            return _REFUSED_COST
        if not (math.isfinite(condition) and force <= max_force):
            return _REFUSED_COST
        if condition < best[0]:
            best[:] = condition, motion, force
        return math.log(condition)

    # L-BFGS-B checks maxfun once an iteration (its finite-difference
    # gradient alone costs 2 x harmonics x 3 + 1 evaluations): the cost
    # itself stops the search at the budget.
    try:
        minimize(cost, np.concatenate((start.sines.ravel(),
                                       start.cosines.ravel())),
                 method='L-BFGS-B', options={'maxfun': evaluations})
    except _BudgetSpent:
        pass
    condition, motion, force = best
    return Design(motion, condition, force, start_condition, count[0])
