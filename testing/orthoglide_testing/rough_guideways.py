"""
Robots of the rough-guideway kind, drawn at random, and their logs.

What identification is checked against beyond the model
(``test/test_identification_not_the_model.py``,
``benchmarks/bench_rough_guideways.py``): a robot with a Coulomb level
per direction and a Stribeck excess (laws the model holds), a force
ripple periodic in each slider's position (which no model holds), and a
log with every defect a real one has: forces that lag the encoders,
noise, ``lambda`` quantised, jittered stamps, dropped samples and a
logger stall. :func:`drawn_robot` draws one from a seed, :func:`log`
records it, :func:`forces` gives what it needs along a motion (the
ripple included), :func:`errors` how far a robot's forces (those of
``orthoglide batch``) miss them. No ROS.

The limits: no model holds the ripple, so its RMS, ``ripple / sqrt(2)``,
is the floor no identification goes below. Each actuator's RMS error
within EACH and their mean within MEAN times it: 0.55 and 0.46 N for a
ripple of 0.5 N, the targets set for a robot of this kind.

:func:`screw_robot` puts such a robot on ball screws of SCREW_LEAD: a ripple
of 0.5-0.7 N per actuator at the lead, which the model's ripple term holds
once ``robot.screw_lead`` is given, and a second harmonic of up to
SECOND_SHARE of it (the balls' recirculation, a motor's cogging), which it
does not. With the term, each actuator's RMS error on another motion within
SCREW_EACH and their mean within SCREW_MEAN (N).
"""

import math

import numpy as np

from orthoglide_ros.formats.logs import Log
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot

EACH = 1.55
MEAN = 1.30
JITTER = 5e-5           # s, standard deviation of the stamps
QUANTUM = 1e-6          # m, of the measured lambda
LOG_S = 30.0            # s logged for identification
VALIDATION_S = 12.0     # s of another motion to validate on
SCREW_LEAD = 0.005      # m, the ball screws' lead
SCREW_RIPPLE = (0.5, 0.7)   # N, the range of the ripple at the lead
SECOND_SHARE = 0.15     # the second harmonic's share of it, at most
SCREW_EACH = 0.35       # N, RMS error per actuator with the ripple term
SCREW_MEAN = 0.30       # N, and the mean of the three


def drawn_robot(seed):
    """
    Return a robot of this kind and its log's defects, drawn from ``seed``.

    Masses, friction (a Coulomb level per direction up to 3 N apart, a
    Stribeck excess of 0.5-6 N at 2-100 mm/s), a ripple of 0.2-0.6 N with
    a pitch of 5-100 mm, a lag of 0.5-5 ms, 0.1-0.4 N of noise, up to 10 %
    of the samples dropped, a stall of 0.2-3 s, an excitation of 4-10 s
    logged at 250, 500 or 1000 Hz.
    """
    rng = np.random.default_rng(7000 + seed)

    def u(low, high, n=3):
        return tuple(float(x) for x in rng.uniform(low, high, n))
    coulomb = np.array(u(2.0, 8.0))
    negative = np.abs(coulomb + np.array(u(-3.0, 3.0)))
    robot = Robot(
        m5=float(rng.uniform(14.0, 22.0)), m3=float(rng.uniform(2.2, 3.0)),
        friction_viscous=u(20.0, 60.0), friction_coulomb=tuple(coulomb),
        friction_coulomb_negative=tuple(negative),
        friction_stribeck=u(0.5, 6.0),
        friction_stribeck_velocity=float(np.exp(rng.uniform(
            np.log(0.002), np.log(0.1)))))
    defects = dict(
        ripple=float(rng.uniform(0.2, 0.6)),
        pitch=float(np.exp(rng.uniform(np.log(0.005), np.log(0.1)))),
        lag=float(rng.uniform(0.0005, 0.005)),
        noise=float(rng.uniform(0.1, 0.4)), phases=u(0.0, 2.0 * math.pi),
        drops=float(rng.uniform(0.0, 0.1)),
        stall=(float(rng.uniform(3.0, 25.0)), float(rng.uniform(0.2, 3.0))),
        period=float(rng.choice([4.0, 6.0, 8.0, 10.0])),
        rate=float(rng.choice([250.0, 500.0, 1000.0])))
    return robot, defects


def screw_robot(seed):
    """
    Return a robot of this kind on ball screws, and its log's defects.

    :func:`drawn_robot`'s, its ripple now at SCREW_LEAD: SCREW_RIPPLE N per
    actuator, and a second harmonic of up to SECOND_SHARE of it, phases at
    random.
    """
    robot, defects = drawn_robot(seed)
    rng = np.random.default_rng(8000 + seed)
    ripple = rng.uniform(*SCREW_RIPPLE, 3)
    return robot, defects | dict(
        ripple=ripple, pitch=SCREW_LEAD,
        phases=tuple(rng.uniform(0.0, 2.0 * math.pi, 3)),
        second=ripple * rng.uniform(0.0, SECOND_SHARE, 3),
        second_phases=tuple(rng.uniform(0.0, 2.0 * math.pi, 3)))


def forces(robot, defects, times, motion):
    """Return ``lambda`` and the forces along ``motion``, the ripple too."""
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    angle = 2.0 * math.pi * solution.lambda_ / defects['pitch']
    ripple = np.asarray(defects['ripple']) * np.sin(
        angle + np.array(defects['phases']))
    if 'second' in defects:
        ripple = ripple + np.asarray(defects['second']) * np.sin(
            2.0 * angle + np.array(defects['second_phases']))
    return solution.lambda_, solution.force + ripple


def log(robot, defects, seed, noise_seed, duration=LOG_S):
    """Return a log of ``robot`` along excitation ``seed``, every defect."""
    motion = trajectory.excitation(seed, defects['period'])
    times = np.arange(0.0, duration, 1.0 / defects['rate'])
    lambdas, _ = forces(robot, defects, times, motion)
    _, lagged = forces(robot, defects, times - defects['lag'], motion)
    rng = np.random.default_rng(noise_seed)
    stamps = times + rng.normal(0.0, JITTER, len(times))
    start, length = defects['stall']
    keep = (rng.uniform(size=len(times)) > defects['drops']) \
        & ~((times >= start) & (times < start + length))
    keep &= np.r_[True, np.diff(stamps) > 0.0]
    return Log(stamps[keep], np.round(lambdas[keep] / QUANTUM) * QUANTUM,
               lagged[keep] + rng.normal(0.0, defects['noise'],
                                         (keep.sum(), 3)),
               f'drawn, excitation {seed}')


def validation_motion(defects, seed):
    """Return another motion (excitation ``seed``) and its times (s)."""
    return (trajectory.excitation(seed, defects['period']),
            np.arange(0.0, VALIDATION_S, 1.0 / defects['rate']))


def errors(predicted, robot, defects, motion, times):
    """Return the RMS error (N) per actuator of ``predicted`` (N, 3)."""
    _, needed = forces(robot, defects, times, motion)
    return np.sqrt(np.mean((predicted - needed) ** 2, axis=0))


def floor(defects):
    """Return the ripple's RMS (N): what no model explains (per actuator)."""
    return np.sqrt((np.square(defects['ripple'])
                    + np.square(defects.get('second', 0.0))) / 2.0)
