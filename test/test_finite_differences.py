"""
Invariant 3: element velocities and accelerations are time derivatives.

Along smooth trajectories (the paper's and fast ones), the velocity of every
body's origin joint A_k, the angular velocity of every body and the
relative rates that ``bodies.elements`` returns must equal the time
derivatives of the positions and rotations it returns, and the
accelerations the derivatives of the velocities. Derivatives are taken by
the fourth-order central difference with step ``H`` (s).

Tolerance. The difference's truncation error is ``H^4 f^(5) / 30``. On
``r* (1 - cos(omega t))`` with omega <= 8 rad/s the fifth derivative of a
quantity is about ``(k omega)^4`` times its first, k a small harmonic order
(the angles stay below 0.5 rad): with ``H = 2.5e-4`` s and k = 3, the
relative error is about ``(3 * 8 * 2.5e-4)^4 / 30 = 4e-11``. Rounding adds
about ``1.5 eps |x| / H = 3e-12`` for |x| < 2 m (or 2 rad/s), against
scales above 0.2 m/s. ``RELATIVE_TOLERANCE`` is 1e-8 of the largest value
of the same kind (velocity, acceleration, angular velocity or angular
acceleration) on the trajectory; the paper's sign errata of eq. (18) give
errors of order 10%.
"""

from mechanics_reference import (
    derivative, FAST_TRAJECTORIES, LEGS, OTHER_ROBOT_VALUES, unskew)
import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import (
    PAPER_OMEGA, paper_sample, PAPER_TARGET)
import pytest

H = 2.5e-4
RELATIVE_TOLERANCE = 1e-8
TIMES = np.linspace(0.05, 1.95, 9)
TRAJECTORIES = {'paper': (PAPER_TARGET, PAPER_OMEGA)}
TRAJECTORIES.update({f'fast{omega:g}': (target, omega)
                     for target, omega in FAST_TRAJECTORIES})
ROBOTS = {'paper': Robot(), 'other': Robot(**OTHER_ROBOT_VALUES)}
BODIES = (1, 2, 3, 4, 5, 6)


def state_at(robot, target, omega):
    """elements() along r* (1 - cos(omega t)) as a function of t."""
    def at(t):
        return elements(robot, *paper_sample(t, target, omega))
    return at


def flatten(legs):
    """Every checked quantity of elements() as named arrays."""
    out = {}
    for leg in LEGS:
        e = legs[leg]
        for key in ('lambda', 'lambdadot', 'lambdaddot', 'phi21', 'phi32',
                    'omega21', 'omega32', 'epsilon21', 'epsilon32'):
            out[leg, key] = np.array(e[key])
        for k in BODIES:
            body = e['bodies'][k]
            for key in ('origin', 'velocity', 'acceleration', 'omega',
                        'epsilon'):
                out[leg, k, key] = np.array(body[key])
            # Orientation of body k in frame 0 (body frame -> frame 0).
            out[leg, k, 'orientation'] = body['rotation'].T
        out[leg, 'G'] = e['joints']['G']
    return out


# (derivative of, equals): pairs of flatten() keys per leg.
SCALAR_PAIRS = (('lambda', 'lambdadot'), ('lambdadot', 'lambdaddot'),
                ('phi21', 'omega21'), ('omega21', 'epsilon21'),
                ('phi32', 'omega32'), ('omega32', 'epsilon32'))
BODY_PAIRS = (('origin', 'velocity'), ('velocity', 'acceleration'),
              ('omega', 'epsilon'))


# The kind of each rate: errors are measured against the largest value of
# the same kind over all bodies, legs and samples (a body that does not
# turn has an angular velocity of exactly 0, its rotation's difference not).
KIND = {'lambdadot': 'velocity', 'lambdaddot': 'acceleration',
        'omega21': 'omega', 'omega32': 'omega', 'epsilon21': 'epsilon',
        'epsilon32': 'epsilon', 'velocity': 'velocity',
        'acceleration': 'acceleration', 'omega': 'omega',
        'epsilon': 'epsilon'}


def collect_errors(robot, target, omega):
    """Max error of every pair over the samples, and the scale of its kind."""
    at = state_at(robot, target, omega)
    samples = [flatten(at(t)) for t in TIMES]
    rates = [dict(zip(samples[0], derivative_all(at, t))) for t in TIMES]
    errors, kinds, scales = {}, {}, {}

    def check(name, value_key, rate_key, transform=None):
        worst = 0.0
        kind = KIND[rate_key[-1]]
        for sample, rate in zip(samples, rates):
            fd = rate[value_key]
            if transform is not None:
                fd = transform(fd, sample)
            worst = max(worst, np.abs(fd - sample[rate_key]).max())
            scales[kind] = max(scales.get(kind, 0.0),
                               np.abs(sample[rate_key]).max())
        errors[name] = worst
        kinds[name] = kind

    for leg in LEGS:
        for value, rate in SCALAR_PAIRS:
            check(f'{leg} d{value}/dt', (leg, value), (leg, rate))
        for k in BODIES:
            for value, rate in BODY_PAIRS:
                check(f'{leg}{k} d{value}/dt', (leg, k, value),
                      (leg, k, rate))

            def angular(rdot, sample, leg=leg, k=k):
                return unskew(rdot @ sample[leg, k, 'orientation'].T)
            check(f'{leg}{k} omega', (leg, k, 'orientation'),
                  (leg, k, 'omega'), angular)
    return {name: (errors[name], scales[kinds[name]]) for name in errors}


def derivative_all(at, t):
    """Fourth-order central differences of every flatten() quantity."""
    shifted = [flatten(at(t + k * H)) for k in (-2, -1, 1, 2)]
    return [(a - 8.0 * b + 8.0 * c - d) / (12.0 * H)
            for a, b, c, d in zip(*(s.values() for s in shifted))]


@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
@pytest.mark.parametrize('trajectory', sorted(TRAJECTORIES))
def test_element_rates_are_time_derivatives(robot_name, trajectory):
    target, omega = TRAJECTORIES[trajectory]
    checks = collect_errors(ROBOTS[robot_name], target, omega)
    bad = {name: error / scale for name, (error, scale) in checks.items()
           if error > RELATIVE_TOLERANCE * scale}
    assert not bad, bad


@pytest.mark.parametrize('trajectory', sorted(TRAJECTORIES))
def test_platform_translates_with_the_commanded_motion(trajectory):
    """G through every leg moves as asked; the platform never turns."""
    target, omega = TRAJECTORIES[trajectory]
    robot = Robot()
    at = state_at(robot, target, omega)
    for t in TIMES:
        position, velocity, acceleration = paper_sample(t, target, omega)
        legs = at(t)
        for leg in LEGS:
            g_rate = derivative(lambda s: at(s)[leg]['joints']['G'], t, H)
            assert np.abs(g_rate - velocity).max() <= \
                RELATIVE_TOLERANCE * np.abs(velocity).max()
            platform = legs[leg]['bodies'][5]
            assert np.abs(platform['velocity'] - velocity).max() <= \
                1e-12 * np.abs(velocity).max()
            assert np.abs(platform['acceleration'] - acceleration).max() \
                <= 1e-12 * np.abs(acceleration).max()
            assert np.abs(platform['omega']).max() == 0.0
            assert np.abs(platform['epsilon']).max() == 0.0
