"""
The paper's test trajectory, eq. (6), its sampling, and the way back.

- :func:`paper_sample`, :func:`paper_batch`, :func:`paper_times`: eq. (6);
- :func:`quintic`: the polynomial of degree 5 between two states
  (position, velocity, acceleration), the smooth way from one to another
  (the ``setpoint_publisher`` loops eq. (6) with it).
"""

import math

import numpy as np

# Eq. (6): r_G(t) = r* (1 - cos(pi t / 3)), over 2 s from rest at home.
PAPER_TARGET = (0.05, 0.10, -0.20)
PAPER_DURATION = 2.0
PAPER_OMEGA = math.pi / 3.0
# Time of the way back from the end of a pass to its start (s): with the
# paper's pass it keeps the peak speed and acceleration near the pass's
# own (1.01 and 1.01 times; 2 s would give 1.7 and 3.3 times).
RETURN_DURATION = 4.0


def paper_sample(t, target=PAPER_TARGET, omega=PAPER_OMEGA):
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


def paper_batch(times, target=PAPER_TARGET, omega=PAPER_OMEGA):
    """Eq. (6) at an array of times (s): three (N, 3) arrays (m, m/s, m/s^2)."""
    t = np.asarray(times, dtype=float)[:, None]
    r = np.asarray(target, dtype=float)
    return (r * (1.0 - np.cos(omega * t)), r * omega * np.sin(omega * t),
            r * omega * omega * np.cos(omega * t))


def paper_times(samples, duration=PAPER_DURATION):
    """Return ``samples`` instants over [0, duration] s, ends included."""
    if samples < 2:
        raise ValueError(f'samples must be at least 2, got {samples}')
    return np.linspace(0.0, duration, samples)


def quintic(start, end, duration):
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
