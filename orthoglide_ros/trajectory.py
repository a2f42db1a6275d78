"""The paper's test trajectory, eq. (6), and evenly spaced sampling of it."""

import math

import numpy as np

# Eq. (6): r_G(t) = r* (1 - cos(pi t / 3)), over 2 s from rest at home.
PAPER_TARGET = (0.05, 0.10, -0.20)
PAPER_DURATION = 2.0
PAPER_OMEGA = math.pi / 3.0


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
