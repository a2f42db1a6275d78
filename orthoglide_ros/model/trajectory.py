"""
Platform trajectories: the paper's, eq. (6), the way back, an excitation.

The paper's (``paper_*``), :func:`quintic` (degree 5 between two states:
the ``setpoint_publisher``'s way back) and the excitation (a finite
Fourier series per axis, doc/identification.md#the-excitation).
"""

from __future__ import annotations

from typing import Any, Callable, Optional
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.types import Array, Triple, Vector

# Eq. (6): r_G(t) = r* (1 - cos(pi t / 3)), over 2 s from rest at home.
PAPER_TARGET = (0.05, 0.10, -0.20)
PAPER_DURATION = 2.0
PAPER_OMEGA = math.pi / 3.0
# Time of the way back from the end of a pass to its start (s): with the
# paper's pass it keeps the peak speed and acceleration near the pass's
# own (1.01 and 1.01 times; 2 s would give 1.7 and 3.3 times).
RETURN_DURATION = 4.0


def paper_sample(t: float, target: Vector = PAPER_TARGET,
                 omega: float = PAPER_OMEGA) -> tuple[Triple, Triple, Triple]:
    """
    Position (m), velocity (m/s), acceleration (m/s^2) of eq. (6) at t (s).

    Returns three 3-tuples. ``omega`` (rad/s) scales the speed: the paper's
    is pi/3; a larger one gives the fast trajectories the tests use.

    >>> paper_sample(0.0)[0] == (0.0, 0.0, 0.0)
    True
    """
    c = 1.0 - math.cos(omega * t)
    s = omega * math.sin(omega * t)
    a = omega * omega * math.cos(omega * t)
    return (tuple(r * c for r in target), tuple(r * s for r in target),
            tuple(r * a for r in target))


def paper_batch(times: Any, target: Vector = PAPER_TARGET,
                omega: float = PAPER_OMEGA) -> tuple[Array, Array, Array]:
    """Eq. (6) at an array of times (s): three (N, 3) arrays (m, m/s, m/s^2)."""
    t = np.asarray(times, dtype=float)[:, None]
    r = np.asarray(target, dtype=float)
    return (r * (1.0 - np.cos(omega * t)), r * omega * np.sin(omega * t),
            r * omega * omega * np.cos(omega * t))


def paper_times(samples: int, duration: float = PAPER_DURATION) -> Array:
    """Return ``samples`` instants over [0, duration] s, ends included."""
    if samples < 2:
        raise ValueError(f'samples must be at least 2, got {samples}')
    return np.linspace(0.0, duration, samples)


def quintic(start: Vector, end: Vector,
            duration: float) -> Callable[[float], tuple[Triple, Triple, Triple]]:
    """
    Return the quintic from ``start`` to ``end`` in ``duration`` s.

    ``start``, ``end``: ``(position, velocity, acceleration)``, each a
    3-sequence (m, m/s, m/s^2). The result ``sample(t)`` gives the three
    3-tuples at ``t`` in [0, duration]: the polynomial of degree 5 per axis
    that meets both states exactly (the minimum-jerk form when both are at
    rest).

    >>> way = quintic(((0.0, 0.0, 1.0), (0.0,) * 3, (0.0,) * 3),
    ...               ((0.0, 0.0, 2.0), (0.0,) * 3, (0.0,) * 3), 2.0)
    >>> way(1.0)[0]
    (0.0, 0.0, 1.5)
    """
    T = float(duration)
    # Conditions at 0 give c0..c2; at T, a 3x3 system for c3..c5.
    system = np.array([[T**3, T**4, T**5], [3 * T**2, 4 * T**3, 5 * T**4],
                       [6 * T, 12 * T**2, 20 * T**3]])
    p0, v0, a0 = (np.asarray(x, dtype=float) for x in start)
    p1, v1, a1 = (np.asarray(x, dtype=float) for x in end)
    rhs = np.array([p1 - (p0 + v0 * T + 0.5 * a0 * T**2),
                    v1 - (v0 + a0 * T), a1 - a0])
    c3, c4, c5 = np.linalg.solve(system, rhs)
    c2 = 0.5 * a0

    def sample(t):
        p = p0 + t * (v0 + t * (c2 + t * (c3 + t * (c4 + t * c5))))
        v = v0 + t * (2 * c2 + t * (3 * c3 + t * (4 * c4 + t * 5 * c5)))
        a = 2 * c2 + t * (6 * c3 + t * (12 * c4 + t * 20 * c5))
        return tuple(p.tolist()), tuple(v.tolist()), tuple(a.tolist())
    return sample


# The excitation: EXCITATION_HARMONICS harmonics of 1 / period per axis,
# kept within a box around home (m, each coordinate) and within a speed
# (m/s) and an acceleration (m/s^2) per axis: inside the paper's tested
# cube (|x|, |y|, |z| <= 0.3 m, singularity distance >= 0.274), at rates a
# PD-controlled Orthoglide follows closely.
EXCITATION_HARMONICS = 5
EXCITATION_BOX = 0.15
EXCITATION_MAX_VELOCITY = 0.4
EXCITATION_MAX_ACCELERATION = 4.0
# Fraction of each bound the sampled peaks are scaled to (the true peak
# between two of the PEAK_SAMPLES samples per period is a little higher).
_BOUND_SHARE = 0.99
_PEAK_SAMPLES = 4000

Excitation = namedtuple('Excitation', (
    'period', 'offset', 'sines', 'cosines', 'seed'))
Excitation.__doc__ = """A periodic excitation motion (see :func:`excitation`).

Per axis i of frame 0: ``r_i(t) = offset_i + sum_k (sines[i, k-1] sin(k w
t) + cosines[i, k-1] cos(k w t))``, ``w = 2 pi / period`` (m, s);
``seed`` made it.
"""


def excitation(seed: int, period: float, harmonics: int = EXCITATION_HARMONICS,
               box: float = EXCITATION_BOX,
               max_velocity: float = EXCITATION_MAX_VELOCITY,
               max_acceleration: float = EXCITATION_MAX_ACCELERATION,
               robot: Optional[Robot] = None,
               margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN) -> 'Excitation':
    """
    Return an :class:`Excitation`: a finite Fourier series per axis.

    ``harmonics`` multiples of ``1 / period`` (s), random coefficients from
    ``seed`` (an integer >= 0), corrected to start at home at rest with zero
    acceleration, each axis scaled down to ``box`` (m), ``max_velocity``
    (m/s) and ``max_acceleration`` (m/s^2), the path checked against
    ``robot``'s workspace (default the paper's) with ``margin``
    (doc/identification.md#the-excitation). Raises ValueError for a path
    outside or a period or bound that is not positive.

    >>> motion = excitation(7, 5.0)
    >>> position, velocity, acceleration = excitation_sample(motion, 0.0)
    >>> max(abs(c) for c in position + velocity + acceleration) < 1e-15
    True
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f'seed must be an integer >= 0, got {seed!r}')
    if isinstance(harmonics, bool) or not isinstance(harmonics, int) \
            or harmonics < 1:
        raise ValueError(f'harmonics must be an integer >= 1, got '
                         f'{harmonics!r}')
    rng = np.random.default_rng(seed)
    k = np.arange(1, harmonics + 1, dtype=float)
    return shaped_excitation(rng.standard_normal((3, harmonics)) / k,
                             rng.standard_normal((3, harmonics)) / k, period,
                             box, max_velocity, max_acceleration, robot,
                             margin, seed)


def shaped_excitation(sines: Any, cosines: Any, period: float,
                      box: float = EXCITATION_BOX,
                      max_velocity: float = EXCITATION_MAX_VELOCITY,
                      max_acceleration: float = EXCITATION_MAX_ACCELERATION,
                      robot: Optional[Robot] = None,
                      margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN,
                      seed: Optional[int] = None) -> 'Excitation':
    """
    Return the :class:`Excitation` of given coefficients, shaped.

    ``sines`` and ``cosines`` (3, harmonics): the raw coefficients,
    corrected to start at home at rest and scaled to the bounds as
    :func:`excitation` says; ``seed``: what made them (None: a search).
    """
    for name, value in (('period', period), ('box', box),
                        ('max_velocity', max_velocity),
                        ('max_acceleration', max_acceleration)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f'{name} must be finite and positive, got '
                             f'{value!r}')
    sines = np.array(sines, dtype=float)
    cosines = np.array(cosines, dtype=float)
    harmonics = sines.shape[1]
    k = np.arange(1, harmonics + 1, dtype=float)
    if harmonics > 1:
        # At rest with zero acceleration at t = 0 (one harmonic cannot).
        sines -= np.outer(sines @ k, k) / (k @ k)
        cosines -= np.outer(cosines @ k ** 2, k ** 2) / (k ** 2 @ k ** 2)
    motion = Excitation(float(period), -cosines.sum(axis=1), sines,
                        cosines, seed)
    times = np.linspace(0.0, period, _PEAK_SAMPLES, endpoint=False)
    peaks = [np.abs(x).max(axis=0) for x in excitation_batch(motion, times)]
    with np.errstate(divide='ignore'):
        scale = _BOUND_SHARE * np.min([
            box / peaks[0], max_velocity / peaks[1],
            max_acceleration / peaks[2]], axis=0)
    scale = np.where(np.isfinite(scale), scale, 0.0)
    motion = Excitation(motion.period, motion.offset * scale,
                        sines * scale[:, None], cosines * scale[:, None],
                        seed)
    positions = excitation_batch(motion, times)[0]
    status = mechanics.workspace_status(robot or Robot(), positions, margin)
    if not status.ok.all():
        worst = int(np.argmin(status.singularity_distance))
        raise ValueError(
            f'the excitation leaves the workspace of margin {margin:g} at '
            f'{mechanics.format_vector(positions[worst])} m (singularity '
            f'distance {status.singularity_distance[worst]:.3g}): choose a '
            f'smaller box than {box:g} m')
    return motion


def excitation_sample(motion: 'Excitation',
                      t: float) -> tuple[Triple, Triple, Triple]:
    """Position (m), velocity (m/s), acceleration (m/s^2) at t (s): 3-tuples."""
    p, v, a = excitation_batch(motion, np.array([float(t)]))
    return tuple(p[0].tolist()), tuple(v[0].tolist()), tuple(a[0].tolist())


def excitation_batch(motion: 'Excitation',
                     times: Any) -> tuple[Array, Array, Array]:
    """Return the excitation at an array of times (s): three (N, 3) arrays."""
    w = 2.0 * math.pi / motion.period
    k = w * np.arange(1, motion.sines.shape[1] + 1)
    phase = np.outer(np.asarray(times, dtype=float), k)
    sin, cos = np.sin(phase), np.cos(phase)
    ks, kc = motion.sines * k, motion.cosines * k
    return (motion.offset + sin @ motion.sines.T + cos @ motion.cosines.T,
            cos @ ks.T - sin @ kc.T,
            -(sin @ (ks * k).T + cos @ (kc * k).T))
