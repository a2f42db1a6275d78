"""
A robot's forces against a log's: what a model explains of a motion.

:func:`validate` runs the full model (:func:`mechanics.solve_batch`, every
friction term, the drives and a payload included) along a log's filtered
motion and compares its forces with the log's, through the same
low-pass; :func:`predict` gives a robot's forces from prepared samples'
regressor.
"""

from __future__ import annotations

from typing import Optional, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.formats.logs import LogError
from orthoglide_ros.model.robot import LEGS
from orthoglide_ros.model.terms import RIPPLE, RIPPLE_COSINE
from orthoglide_ros.tools.identification.laws import (
    Law, parameter, PLAIN, standard_names, standard_parameters)
from orthoglide_ros.tools.identification.motion import (
    check_lag, DEFAULT_CUTOFF, estimate_lag, Motion)
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.formats.logs import Log
    from orthoglide_ros.model.robot import Robot
    from orthoglide_ros.tools.identification.motion import Samples

# A log whose sliders all moved slower than this (RMS, m/s) shows mostly
# the static load: its share explained says little of the dynamics.
STILL_SPEED = 0.005
# The error is a transient's (start-up, a collision) when the worst
# TRANSIENT_SHARE of the samples carry more than half of it.
TRANSIENT_SHARE = 0.01

Validation = namedtuple('Validation', (
    'source', 'samples', 'measured', 'predicted', 'rms', 'max', 'explained',
    'force_lag', 'lag_estimated', 'warnings', 'screw_lead', 'ripple_left'),
    defaults=((), (0.0, 0.0, 0.0), None))
Validation.__doc__ = """A robot's forces against a log's (:func:`validate`).

``samples``: the log's :class:`Samples` (their regressor unused: None);
``measured`` and ``predicted``: (N, 3) forces (N) through the same
low-pass; per actuator ``rms`` and ``max`` of the error (N) and
``explained``: the share of the force explained, ``1 - sum(e^2) /
sum(f^2)``; ``force_lag`` (s) and ``lag_estimated`` as in
:class:`estimate.Identification`; ``warnings``: sentences on what makes
the figures say little (a robot standing still, an error that is a
transient's); ``screw_lead``: the robot's (m, per actuator; 0.0: none);
``ripple_left``: per actuator, the amplitude (N) of the error's part
periodic in the screw's lead (:func:`ripple_left`; NaN without a lead),
None when no actuator has one.
"""


def predict(robot: Robot, samples: Samples) -> Array:
    """
    Return the forces (N, 3) ``robot`` needs for the prepared samples.

    Through the same low-pass as the samples' forces: ``W theta`` with
    their filtered regressor, for a robot of the geometry, gravity and
    friction speeds they were prepared with (:func:`validate` runs the
    full model instead).
    """
    return samples.regressor @ standard_parameters(robot, samples.law)


def validate(robot: Robot, log: Log, cutoff: float = DEFAULT_CUTOFF,
             force_lag: Optional[float] = None,
             payload: Optional[float] = None) -> 'Validation':
    """
    Compare ``robot``'s forces with a log's (a :class:`Validation`).

    The log prepared as for identification; the prediction is the full
    model's along the log's filtered motion, through the same low-pass as
    the measured forces. ``payload`` (kg): what the log was recorded with
    (None: ``robot.payload``). ``force_lag`` (s): None to estimate the one
    that best matches the prediction (:func:`motion.estimate_lag`).
    Raises :class:`LogError`.
    """
    if payload is not None:
        robot = robot.replace(payload=float(payload))
    motion = Motion(robot, log, cutoff)
    predicted = motion.model_forces(robot)
    if force_lag is None:
        force_lag = estimate_lag(motion, lambda f: float(np.sum(
            (f - predicted) ** 2)))
        lag_estimated = True
    else:
        check_lag(log.source, force_lag, cutoff)
        lag_estimated = False
    measured = motion.forces(force_lag)
    error = measured - predicted
    squares = np.sum(measured ** 2, axis=0)
    # (No force at all on an actuator: nothing to explain, NaN.)
    explained = 1.0 - np.divide(np.sum(error ** 2, axis=0), squares,
                                out=np.full(3, np.nan), where=squares > 0.0)
    samples = motion.samples(None, measured)
    rms = np.sqrt(np.mean(error ** 2, axis=0))
    left = ripple_left(motion, error) if any(robot.screw_lead) else None
    if not np.isfinite(rms).all():
        j = int(np.argmin(np.isfinite(rms)))
        raise LogError(f'{log.source}: the error on actuator {"ABC"[j]} '
                       'is not finite: the robot\'s forces along the log\'s '
                       'motion leave the finite numbers')
    return Validation(
        log.source, samples, measured, predicted, rms,
        np.abs(error).max(axis=0), explained, float(force_lag),
        lag_estimated, _warnings(samples, error), robot.screw_lead, left)


def ripple_left(motion: Motion, error: Array) -> Array:
    """
    Return the amplitude (N, per actuator) of the screw ripple in ``error``.

    ``error`` (M, 3): measured less predicted forces along ``motion``,
    filtered. The least-squares fit of the error on the regressor of
    ``coulomb+ripple`` along the motion (the masses', the friction's and
    the ripple's filtered columns: an error of the masses or friction is
    not taken for a ripple), and per actuator with a lead ``sqrt(s^2 +
    c^2)`` of its ripple coefficients: what of a ripple the model leaves
    (about the noise's share where it holds the ripple). NaN on an
    actuator without a lead.
    """
    law = Law(PLAIN + (RIPPLE,))
    w = motion.columns(law).reshape(-1, len(standard_names(law)))
    norms = np.linalg.norm(w, axis=0)
    fit = np.linalg.lstsq(w / np.where(norms > 0.0, norms, 1.0),
                          error.reshape(-1), rcond=None)[0]
    values = dict(zip(standard_names(law), fit / np.where(norms > 0.0,
                                                          norms, 1.0)))
    return np.array([
        math.hypot(values[parameter(RIPPLE, leg)],
                   values[parameter(RIPPLE_COSINE, leg)]) if lead
        else math.nan for leg, lead in zip(LEGS, motion.robot.screw_lead)])


def _warnings(samples, error):
    """Say what makes a validation's figures say little (see Validation)."""
    warnings = []
    speed = np.sqrt(np.mean(np.asarray(samples.lambdadots) ** 2, axis=0))
    if (speed < STILL_SPEED).all():
        warnings.append(
            'the sliders hardly moved (RMS speed ' + ', '.join(
                f'{1e3 * s:.2g}' for s in speed) + ' mm/s): the forces are '
            'mostly the static load, and the share explained says little '
            'of the dynamics; record the robot following a motion')
    squares = np.sum(error ** 2, axis=1)
    worst = max(1, int(TRANSIENT_SHARE * len(squares)))
    top = np.argsort(squares)[-worst:]
    if squares.sum() > 0.0 and squares[top].sum() > 0.5 * squares.sum():
        times = np.asarray(samples.times)[top]
        warnings.append(
            f'half of the error comes from {worst} sample(s) between '
            f'{times.min():.3g} s and {times.max():.3g} s: a transient '
            '(start-up, a collision) the model does not have; --start and '
            '--end keep the part of the log to compare')
    return tuple(warnings)
