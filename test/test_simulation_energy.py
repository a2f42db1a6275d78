"""
The simulator conserves energy, balances work, and follows feedforward.

``simulation.rk4_step`` integrates ``forward_dynamics`` with the actuator
forces held over each step (1 ms). The energy checks do not trust the
inverse dynamics: T and V come from the independent model of
``mechanics_reference`` (body Jacobians by complex step), and so do the
actuator displacements of the work integral.

- (a) g = 0, no force: T is conserved along a free motion.
- (b) default gravity, no force: T + V is conserved. The robot falls, so
  it is thrown upward (2.2 m/s) from z = -0.25 m and followed for 0.4 s:
  it rises to about z = 0 and falls back to z = -0.2 m, inside the cube.
- (c) with forces held over each step: the work ``sum_k f_k . (lambda_{k+1}
  - lambda_k)`` (exact for a force constant over the step) equals
  ``Delta(T + V)`` over 2 s at 1 kHz. The forces: the paper's feedforward
  (sampled at each step's midpoint), a sinusoidal perturbation of 10 N and
  a joint-space PD term on the simulated state. The PD term is needed: the
  feedforward alone is open-loop unstable (see below), and the perturbation
  alone would carry the platform 0.5 m away within 1.5 s. Also a fast
  trajectory (omega = 8 rad/s) with g = 0, where inertia does the work.
  (The paper's path ends on the cube's face, z = -0.3 m, at t = 2 s.)
- (d) case (c) on a robot with friction on its sliders (viscous and
  smoothed Coulomb, doc/model.md): the work of the forces less the energy
  the friction dissipated equals ``Delta(T + V)``. The dissipated energy
  is the integral of ``sum_j f_j(lambdadot_j) lambdadot_j`` (the friction
  law written again here), integrated step by step by the trapezoid rule
  with its end correction (Euler-Maclaurin: ``dt/2 (P0 + P1) - dt^2/12
  (P1' - P0')``, local error O(dt^5) like RK4's), the rates
  ``lambdadot``, ``lambdaddot`` taken from ``mechanics.solve`` (checked
  against finite differences by invariant 3). The friction's own rate,
  ``|lambdaddot| / friction_velocity``, joins ``omega`` in the bound.

Bounds. Over a step the force is constant, so the equations of motion are
smooth and RK4's local error is about ``(omega dt)^5 / 5!`` of the state
(exact for ``y' = omega y``), with ``omega`` the fastest rate of the
motion: ``|v| / ell`` and ``sqrt(|a| / ell)``, where ``ell = sqrt(l3^2 -
2 * 0.3^2)`` (0.74 m) is the shortest lever of the legs in the cube, the
length over which the mass matrix and the weight's lever arms change.
Summed over N steps the energy error is at most ``N (omega dt)^5 / 120``
of the energy scale (max T plus the range of V), times ``SAFETY = 10`` for
the unknown constant of the fifth derivative. Rounding adds about
``STEP_ROUNDING = 10 eps`` of the energy scale a step (the state's update,
the forward dynamics' few eps, the work's ``f . Delta lambda``),
accumulated linearly (worst case). Measured (printed to stderr), relative
to the scale: (a) 5e-15 and (c) on the paper's trajectory 1.3e-15, at
rounding; (b) 1.1e-12 and (c) on the fast trajectory 2.8e-12, the RK4
truncation (their error falls 16x when dt halves), 20 to 100 times below
their bounds; (d) 2.4e-14 with 5.4 J dissipated (its bound, 2.2e-8, is
wide: the Coulomb smoothing's rate enters it to the fifth power).

Open loop. Holding the platform's weight on the vertical leg C is an
inverted pendulum: at constant forces the potential ``V - f . lambda``
has a negative stiffness of about ``f_C / l3 = 300 N/m`` in x and y, a
growth rate of ``sqrt(300 / 25) = 3.5 /s``: any error grows like
``e^(3.5 t)``. Feeding the paper's feedforward forces through
``rk4_step`` from rest at home, sampled at each step's midpoint (the
midpoint rule: a held force with the right impulse over the step to
O(dt^3)), the platform follows eq. (6) within ``OPEN_LOOP_BOUND = 2e-6``
m over 2 s (measured 1.40e-6 m, at t = 2 s); the error halves twice when
dt halves (O(dt^2), the hold's error). Sampled at each step's start, the
force lags by dt/2 and the error is 5.1e-3 m (3,700 times larger).
"""

import math
import sys

from mechanics_reference import (
    actuator_displacements, CUBE, FAST_TRAJECTORIES, kinetic_energy,
    OTHER_ROBOT_VALUES, potential_energy)
import numpy as np
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.mechanics import WorkspaceError
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.plant import Plant, PlantStep, rk4_step
from orthoglide_ros.model.trajectory import paper_sample, PAPER_OMEGA, \
    PAPER_TARGET
import pytest

DT = 1e-3
SAFETY = 10.0
STEP_ROUNDING = 10.0 * sys.float_info.epsilon
CHECKS = 20
ROBOTS = {'paper': {}, 'other': OTHER_ROBOT_VALUES}
ZERO = (0.0, 0.0, 0.0)
# A joint-space PD that keeps case (c) near its trajectory: 5000 N/m and
# 700 N s/m against ~25 kg (14 rad/s, damping ratio ~1; 1 kHz is ample).
KP, KD = 5000.0, 700.0
PERTURBATION = 10.0     # N, per actuator
PERTURBATION_HZ = 1.5
OPEN_LOOP_BOUND = 2e-6
FAST_OPEN_LOOP_BOUND = 3e-5


def lever(robot):
    """Shortest ``alpha_i`` (m) in the cube: ``sqrt(l3^2 - 2 CUBE^2)``."""
    return math.sqrt(robot.l3 ** 2 - 2.0 * CUBE ** 2)


def energy(robot, position, velocity):
    """(T, V) in J from the reference model."""
    return (kinetic_energy(robot, position, velocity),
            potential_energy(robot, position))


def friction_power(robot, position, velocity, acceleration):
    """
    Return the friction's power and its rate (W, W/s) at a state.

    ``P = sum_j f_j lambdadot_j`` with the law ``f_j = c_j lambdadot_j +
    F_j tanh(lambdadot_j / v_s)``, and ``dP/dt = sum_j (f_j'
    lambdadot_j + f_j) lambdaddot_j``; also the friction's rate
    ``max |lambdaddot_j| / v_s`` (1/s).
    """
    s = mechanics.solve(robot, position, velocity, acceleration)
    lamd, lamdd = np.array(s.lambdadot), np.array(s.lambdaddot)
    c = np.array(robot.friction_viscous)
    coulomb = np.array(robot.friction_coulomb)
    u = lamd / robot.friction_velocity
    f = c * lamd + coulomb * np.tanh(u)
    slope = c + coulomb / robot.friction_velocity / np.cosh(u) ** 2
    return (float(f @ lamd), float(((slope * lamd + f) * lamdd).sum()),
            float(np.abs(lamdd).max() / robot.friction_velocity))


def simulate(robot, position, velocity, steps, force_at):
    """
    Run ``steps`` RK4 steps; compare the energy with the work done.

    ``force_at(k, position, velocity)`` gives the force (N) held over step
    k. Returns a dict: ``drift`` (max |T + V - E0 - work + dissipated| over
    CHECKS evenly spaced checks, J), ``scale`` (max T + range of V, J),
    ``omega`` (1/s, see the module docstring), ``extent`` (the largest
    |coordinate| reached, m), ``work`` and ``dissipated`` (J; 0 without
    friction).
    """
    t0, v0 = energy(robot, position, velocity)
    lam = actuator_displacements(robot, position)
    work = drift = t_max = dissipated = friction_rate = 0.0
    v_low = v_high = v0
    speed = accel = extent = 0.0
    every = steps // CHECKS
    for k in range(steps):
        force = force_at(k, position, velocity)
        start = position, velocity
        position, velocity, acceleration = rk4_step(
            robot, position, velocity, force, DT)
        if robot.has_friction:
            p0, dp0, rate0 = friction_power(robot, *start, acceleration)
            p1, dp1, rate1 = friction_power(
                robot, position, velocity, mechanics.forward_dynamics(
                    robot, position, velocity, force))
            dissipated += 0.5 * DT * (p0 + p1) - DT * DT / 12.0 * (dp1 - dp0)
            friction_rate = max(friction_rate, rate0, rate1)
        new_lam = actuator_displacements(robot, position)
        work += float(np.dot(force, new_lam - lam))
        lam = new_lam
        speed = max(speed, math.hypot(*velocity))
        accel = max(accel, math.hypot(*acceleration))
        extent = max(extent, *(abs(c) for c in position))
        if (k + 1) % every == 0:
            t, v = energy(robot, position, velocity)
            drift = max(drift, abs(t + v - t0 - v0 - work + dissipated))
            t_max = max(t_max, t)
            v_low, v_high = min(v_low, v), max(v_high, v)
    ell = lever(robot)
    return {'drift': drift, 'scale': t_max + v_high - v_low,
            'omega': max(speed / ell, math.sqrt(accel / ell),
                         friction_rate),
            'extent': extent, 'work': work, 'dissipated': dissipated}


def bound(steps, omega):
    """Relative energy error allowed after ``steps`` (module docstring)."""
    return steps * (SAFETY * (omega * DT) ** 5 / 120.0 + STEP_ROUNDING)


def check(name, result, steps):
    relative = result['drift'] / result['scale']
    allowed = bound(steps, result['omega'])
    print(f'{name}: energy drift {result["drift"]:.3g} J = {relative:.3g} '
          f'of the scale {result["scale"]:.4g} J over {steps} steps of '
          f'{DT:g} s (omega {result["omega"]:.3g} /s, bound '
          f'{allowed:.3g}); work {result["work"]:.4g} J, dissipated '
          f'{result["dissipated"]:.4g} J, extent {result["extent"]:.3f} m',
          file=sys.stderr)
    assert result['extent'] <= CUBE
    assert relative <= allowed


def no_force(k, position, velocity):
    return ZERO


@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_kinetic_energy_is_conserved_without_gravity_or_force(robot_name):
    """Case (a): a free motion across the cube for 2 s."""
    robot = Robot(**ROBOTS[robot_name], gravity=ZERO)
    result = simulate(robot, (-0.2, 0.15, -0.1), (0.2, -0.12, 0.1), 2000,
                      no_force)
    check(f'(a) {robot_name}, g = 0, no force', result, 2000)
    assert result['scale'] > 0.1     # T of ~25 kg at ~0.25 m/s


@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_total_energy_is_conserved_without_force(robot_name):
    """Case (b): thrown upward under gravity, 0.4 s, back down inside."""
    robot = Robot(**ROBOTS[robot_name])
    result = simulate(robot, (0.05, -0.05, -0.25), (0.1, -0.1, 2.2), 400,
                      no_force)
    check(f'(b) {robot_name}, default gravity, no force', result, 400)
    assert result['scale'] > 50.0


def forced(robot, target, omega):
    """Feedforward at the midpoint + sinusoid + joint-space PD (case c)."""
    def force_at(k, position, velocity):
        t = k * DT
        feedforward = mechanics.solve(
            robot, *paper_sample(t + 0.5 * DT, target, omega)).force
        ref = mechanics.solve(robot, *paper_sample(t, target, omega))
        now = mechanics.solve(robot, position, velocity)
        return tuple(
            feedforward[j]
            + PERTURBATION * math.sin(2.0 * math.pi * PERTURBATION_HZ * t
                                      + 2.0 * j)
            + KP * (ref.lambda_[j] - now.lambda_[j])
            + KD * (ref.lambdadot[j] - now.lambdadot[j]) for j in range(3))
    return force_at


# The fast case: FAST_TRAJECTORIES' omega = 8 rad/s, its target scaled by
# 0.9 so that the perturbed path (2 r* = 0.27 m) stays inside the cube.
CASES_C = {
    'paper, default gravity': ({}, PAPER_TARGET, PAPER_OMEGA),
    'fast omega 8, g = 0': ({'gravity': ZERO}, tuple(
        0.9 * c for c in FAST_TRAJECTORIES[-1][0]), FAST_TRAJECTORIES[-1][1]),
}


@pytest.mark.parametrize('case', sorted(CASES_C))
def test_work_of_the_forces_equals_the_change_of_energy(case):
    """Case (c): 2 s at 1 kHz, forces held over each step."""
    values, target, omega = CASES_C[case]
    robot = Robot(**values)
    position, velocity, _ = paper_sample(0.0, target, omega)
    result = simulate(robot, position, velocity, 2000,
                      forced(robot, target, omega))
    check(f'(c) {case}', result, 2000)
    assert abs(result['work']) > 1.0    # the forces do real work


# Case (d): friction of the size a ball-screw slider may have, per
# actuator unequal; a smoothing speed that keeps the friction's own rate
# (|lambdaddot| / v_s) a few tens per second on the paper's trajectory.
FRICTION = {'friction_viscous': (30.0, 20.0, 40.0),
            'friction_coulomb': (4.0, 6.0, 3.0), 'friction_velocity': 0.05}


def test_work_less_dissipation_equals_the_change_of_energy():
    """Case (d): case (c) on the paper's trajectory, with friction."""
    robot = Robot(**FRICTION)
    position, velocity, _ = paper_sample(0.0)
    result = simulate(robot, position, velocity, 2000,
                      forced(robot, PAPER_TARGET, PAPER_OMEGA))
    check('(d) paper, default gravity, friction', result, 2000)
    # The friction takes a real share: leaving it out would break the
    # balance by far more than the bound.
    assert result['dissipated'] > 1e3 * bound(2000, result['omega']) \
        * result['scale']


def open_loop_error(robot, target, omega, when, dt=DT):
    """
    Max |r_G - eq. (6)| (m) under the feedforward forces, open loop.

    The force of step k is ``solve`` at ``t_k + when * dt``, held over the
    step; the state starts on the trajectory.
    """
    position, velocity, _ = paper_sample(0.0, target, omega)
    error = 0.0
    for k in range(int(round(2.0 / dt))):
        t = k * dt
        force = mechanics.solve(
            robot, *paper_sample(t + when * dt, target, omega)).force
        position, velocity, _ = rk4_step(robot, position, velocity, force,
                                         dt)
        ref = paper_sample(t + dt, target, omega)[0]
        error = max(error, max(abs(a - b) for a, b in zip(position, ref)))
    return error


def test_open_loop_feedforward_follows_the_paper_trajectory():
    robot = Robot()
    midpoint = open_loop_error(robot, PAPER_TARGET, PAPER_OMEGA, 0.5)
    start = open_loop_error(robot, PAPER_TARGET, PAPER_OMEGA, 0.0)
    half = open_loop_error(robot, PAPER_TARGET, PAPER_OMEGA, 0.5, DT / 2)
    print(f'open loop, paper trajectory over 2 s: max position error '
          f'{midpoint:.3g} m (force at each step\'s midpoint), '
          f'{half:.3g} m with dt/2, {start:.3g} m (force at its start)',
          file=sys.stderr)
    assert midpoint <= OPEN_LOOP_BOUND
    assert 3.5 <= midpoint / half <= 4.5        # O(dt^2)
    assert start >= 1000.0 * midpoint


def test_open_loop_feedforward_follows_a_fast_trajectory():
    robot = Robot(gravity=ZERO)
    target, omega = FAST_TRAJECTORIES[-1]
    error = open_loop_error(robot, target, omega, 0.5)
    print(f'open loop, fast trajectory (omega {omega:g}), g = 0: max '
          f'position error {error:.3g} m', file=sys.stderr)
    assert error <= FAST_OPEN_LOOP_BOUND


def test_rk4_step_returns_the_acceleration_at_the_start():
    robot = Robot()
    state = ((0.05, 0.1, -0.2), (0.3, -0.2, 0.5), (5.0, -20.0, 240.0))
    position, velocity, acceleration = rk4_step(robot, *state, DT)
    assert acceleration == mechanics.forward_dynamics(robot, *state)
    assert all(type(c) is float for c in (*position, *velocity))


def test_rk4_step_refuses_to_step_into_a_singularity():
    """The end of a long step lies beyond the J1 margin: refused."""
    robot = Robot()
    with pytest.raises(WorkspaceError) as error:
        rk4_step(robot, (0.0, 0.5, 0.5), (0.0, 1.0, 1.0), ZERO, 0.1)
    assert error.value.reason in ('singular', 'unreachable')
    with pytest.raises(ValueError, match='dt'):
        rk4_step(robot, ZERO, ZERO, ZERO, 0.0)
    with pytest.raises(ValueError, match='dt'):
        rk4_step(robot, ZERO, ZERO, ZERO, math.nan)


def test_plant_clips_the_forces_and_reports_it():
    robot = Robot()
    plant = Plant(robot, (0.05, 0.1, -0.2), (0.1, 0.0, 0.2),
                  force_limit=(100.0, 200.0, 300.0))
    step = plant.step((150.0, -250.0, 10.0), DT)
    assert isinstance(step, PlantStep)
    assert step.force == (100.0, -200.0, 10.0)
    assert step.clipped == (True, True, False)
    expected = rk4_step(robot, (0.05, 0.1, -0.2), (0.1, 0.0, 0.2),
                        (100.0, -200.0, 10.0), DT)
    assert (plant.position, plant.velocity, step.acceleration) == expected
    assert plant.time == DT
    one_limit = Plant(robot, force_limit=50.0)
    assert one_limit.step((-60.0, 0.0, 60.0), DT).clipped == (
        True, False, True)
    assert Plant(robot).step((1e5, 0.0, 0.0), DT).clipped == (
        False, False, False)


@pytest.mark.parametrize('limit', [0.0, -1.0, math.nan, (1.0, 2.0)])
def test_plant_refuses_bad_force_limits(limit):
    with pytest.raises(ValueError, match='force_limit'):
        Plant(Robot(), force_limit=limit)


def test_plant_refusal_leaves_the_state_unchanged():
    robot = Robot()
    plant = Plant(robot, (0.0, 0.5, 0.5), (0.0, 1.0, 1.0), time=3.0)
    before = (plant.position, plant.velocity, plant.time)
    with pytest.raises(WorkspaceError):
        plant.step(ZERO, 0.1)           # into the J1 margin
    with pytest.raises(WorkspaceError) as error:
        plant.step((math.nan, 0.0, 0.0), DT)
    assert error.value.reason == 'non_finite'
    with pytest.raises(WorkspaceError) as error:
        plant.step((math.inf, 0.0, 0.0), DT)    # not clipped to the limit
    assert error.value.reason == 'non_finite'
    with pytest.raises(ValueError):
        plant.step(ZERO, -DT)
    assert (plant.position, plant.velocity, plant.time) == before
    plant.step(ZERO, DT)
    assert plant.time == 3.0 + DT and plant.position != before[0]


def test_plant_refuses_an_initial_state_outside_the_workspace():
    with pytest.raises(WorkspaceError) as error:
        Plant(Robot(), (0.0, 0.7, 0.7))
    assert error.value.reason == 'unreachable'


def test_plant_joint_state_matches_solve():
    robot = Robot(**OTHER_ROBOT_VALUES)
    plant = Plant(robot, (0.05, -0.1, 0.15), (0.2, 0.1, -0.3))
    for _ in range(5):
        plant.step((10.0, -30.0, 200.0), DT)
    lam, lamd = plant.joint_state()
    s = mechanics.solve(robot, plant.position, plant.velocity)
    assert lam == s.lambda_ and lamd == s.lambdadot
    assert np.allclose(lam, actuator_displacements(robot, plant.position),
                       rtol=0.0, atol=1e-14)
