"""
Invariant 4 (energy balance): ``sum_j f_j lambdadot_j = d(T + V)/dt``.

Along any smooth trajectory, the actuators' power (the package's
``Solution.power``) must equal the rate of change of the robot's energy,
the kinetic energy T and the potential energy V summed over every body
(the platform once). T and V come from the independent model of
``mechanics_reference`` (body Jacobians by complex step, exact to
rounding); d/dt is the fourth-order central difference with step ``H``.

Tolerance. The difference's truncation error is ``H^4 E^(5) / 30``: on
``r* (1 - cos(omega t))`` with omega <= 8 rad/s, about
``(3 omega H)^4 / 30 = 4e-11`` of the power for ``H = 2.5e-4`` s (k = 3
harmonics). Rounding adds ``1.5 eps |E| / H``, about 4e-10 W for
``|E| < 300 J``, against powers of several W. ``RELATIVE_TOLERANCE`` is
1e-8 of the largest total actuator power ``sum_j |p_j|`` on the
trajectory.

The paper's trajectory is dominated by gravity, so the balance is also
checked on fast trajectories and with gravity set to zero, where only the
inertial terms act.
"""

from mechanics_reference import (
    derivative, FAST_TRAJECTORIES, kinetic_energy, OTHER_ROBOT_VALUES,
    potential_energy)
import numpy as np
from orthoglide_ros.model.mechanics import solve
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import (
    PAPER_OMEGA, paper_sample, PAPER_TARGET)
import pytest

H = 2.5e-4
RELATIVE_TOLERANCE = 1e-8
TIMES = np.linspace(0.0, 2.0, 11)[1:-1]
TRAJECTORIES = {'paper': (PAPER_TARGET, PAPER_OMEGA)}
TRAJECTORIES.update({f'fast{omega:g}': (target, omega)
                     for target, omega in FAST_TRAJECTORIES})
GRAVITIES = {'default': (0.0, 0.0, -9.81), 'zero': (0.0, 0.0, 0.0),
             'oblique': (3.0, -4.0, -8.0)}


def energy(robot, target, omega):
    """T + V (J) of the reference model along the trajectory."""
    def at(t):
        position, velocity, _ = paper_sample(t, target, omega)
        return (kinetic_energy(robot, position, velocity)
                + potential_energy(robot, position))
    return at


def check_balance(robot, target, omega):
    """Return (max |power - dE/dt|, scale) over TIMES."""
    e = energy(robot, target, omega)
    errors, scale = [], 0.0
    for t in TIMES:
        s = solve(robot, *paper_sample(t, target, omega))
        power = sum(s.power)
        errors.append(abs(power - derivative(e, t, H)))
        scale = max(scale, sum(abs(p) for p in s.power))
    return max(errors), scale


@pytest.mark.parametrize('gravity', sorted(GRAVITIES))
@pytest.mark.parametrize('trajectory', sorted(TRAJECTORIES))
def test_actuator_power_equals_rate_of_energy(trajectory, gravity):
    robot = Robot(gravity=GRAVITIES[gravity])
    error, scale = check_balance(robot, *TRAJECTORIES[trajectory])
    assert scale > 0.0
    assert error <= RELATIVE_TOLERANCE * scale


@pytest.mark.parametrize('gravity', ['default', 'zero'])
def test_energy_balance_on_a_robot_unlike_the_paper(gravity):
    robot = Robot(**OTHER_ROBOT_VALUES, gravity=GRAVITIES[gravity])
    for target, omega in FAST_TRAJECTORIES:
        error, scale = check_balance(robot, target, omega)
        assert error <= RELATIVE_TOLERANCE * scale


def test_power_is_lambdadot_times_force():
    robot = Robot()
    target, omega = FAST_TRAJECTORIES[-1]
    for t in TIMES:
        s = solve(robot, *paper_sample(t, target, omega))
        for j in range(3):
            assert s.power[j] == s.lambdadot[j] * s.force[j]


def test_inertial_power_is_not_negligible_on_fast_trajectories():
    """Without gravity the balance is all inertia: it must be sizeable."""
    robot = Robot(gravity=(0.0, 0.0, 0.0))
    for target, omega in FAST_TRAJECTORIES:
        _, scale = check_balance(robot, target, omega)
        # Kinetic energy of ~25 kg at ~1 m/s changing over ~0.2 s.
        assert scale > 10.0
