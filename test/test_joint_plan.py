"""
The tracking controller's joint trajectories, without DDS.

``joint_plan.JointPlan`` samples a JointTrajectory as
joint_trajectory_controller does: the cubic Hermite polynomial between
points (from positions and velocities), the effort linear, the robot's
state held before a future start and joined to the first point, the last
point held after the end. ``Tracking.trajectory`` / ``Tracking.tick``
follow it with the same law and path tolerance as a stream of desired
states, and refuse a bad one whole.
"""

import math

import numpy as np
import pytest

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.formats.cdr import JointPoints
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.model.joint_plan import JointPlan
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.plant import Plant
from orthoglide_ros.cores.tracking_controller import PARAMETERS, Tracking

NAMES = ('slider_a', 'slider_b', 'slider_c')
STAMP = (1, 0)     # a joint state's stamp (the controller does not read it)
ZERO = (0.0, 0.0, 0.0)


def cubic(t):
    """Return a cubic per joint (m) and its rate (m/s): Hermite's exact."""
    c = np.array([[0.01, -0.02, 0.03], [0.2, 0.1, -0.3], [-0.4, 0.5, 0.2],
                  [0.3, -0.2, 0.1]])
    p = c[0] + t * (c[1] + t * (c[2] + t * c[3]))
    v = c[1] + t * (2 * c[2] + t * 3 * c[3])
    return p, v


def plan_of_cubic(times, start=100.0):
    p, v = zip(*(cubic(t) for t in times))
    efforts = np.array([[10.0 * t, -t, 250.0 + t] for t in times])
    return JointPlan(start, times, p, v, efforts,
                     (*cubic(times[0]), efforts[0]), start + times[0])


def test_hermite_reproduces_a_cubic_and_efforts_are_linear():
    times = [0.0, 0.3, 0.7, 1.5]
    plan = plan_of_cubic(times)
    c = np.array([[0.2, 0.1, -0.3], [-0.4, 0.5, 0.2], [0.3, -0.2, 0.1]])
    for t in np.linspace(0.0, 1.5, 61)[:-1]:    # at 1.5: held, at rest
        p, v, e = plan.sample(100.0 + t)
        want_p, want_v = cubic(t)
        assert np.allclose(p, want_p, atol=1e-13)
        assert np.allclose(v, want_v, atol=1e-12)
        assert np.allclose(e, [10.0 * t, -t, 250.0 + t], atol=1e-12)
        # The cubic's second derivative, 2 c2 + 6 c3 t.
        assert np.allclose(plan.acceleration(100.0 + t),
                           2 * c[1] + 6 * c[2] * t, atol=1e-10)
    assert plan.acceleration(101.5) == ZERO


@pytest.mark.parametrize('omega, bound', [(math.pi / 3, 1e-12),
                                          (math.pi, 1e-10)])
def test_paper_trajectory_at_the_demo_spacing_interpolates_exactly(omega,
                                                                   bound):
    """
    Points 4 ms apart (the demo's 250 Hz): the cubic misses lambda by < bound.

    Sampled halfway between points, where a cubic segment is worst, and
    compared with the mechanics at those instants: the stand-in's cubic
    and JTC's quintic differ by less than this from the exact motion, far
    below any tracking error (doc/joint_trajectory_controller.md).
    """
    robot, h = Robot(), 0.004
    times = np.arange(0.0, 2 * math.pi / omega + h / 2, h)
    s = mechanics.solve_batch(robot, *trajectory.paper_batch(times,
                                                             omega=omega))
    plan = JointPlan(0.0, times, s.lambda_, s.lambdadot, s.force,
                     (s.lambda_[0], ZERO, s.force[0]), 0.0)
    middle = times[:-1] + h / 2
    exact = mechanics.solve_batch(robot, *trajectory.paper_batch(
        middle, omega=omega))
    sampled = np.array([plan.sample(t)[:2] for t in middle])
    assert np.abs(sampled[:, 0] - exact.lambda_).max() < bound
    assert np.abs(sampled[:, 1] - exact.lambdadot).max() < bound
    # Not a tautology: the linear interpolation of the same points misses
    # by a visible amount.
    linear = (s.lambda_[:-1] + s.lambda_[1:]) / 2
    assert np.abs(linear - exact.lambda_).max() > 1e3 * bound


def test_from_the_acceptance_to_the_first_point_then_the_last_held():
    """
    One cubic from the state at acceptance to the first point, as JTC.

    The stamp (10 s) is in the future and the first point 0.5 s after it:
    accepted at 9 s, the plan goes from the robot's state (at rest, held
    by 9 N) to the first point over 1.5 s, the effort linear.
    """
    plan = JointPlan(10.0, [0.5, 1.0], [[0.1] * 3, [0.2] * 3], [ZERO, ZERO],
                     [[1.0] * 3, [2.0] * 3], (ZERO, ZERO, (9.0,) * 3), 9.0)
    assert plan.sample(8.0) == (ZERO, ZERO, (9.0, 9.0, 9.0))   # before
    assert plan.sample(9.0) == (ZERO, ZERO, (9.0, 9.0, 9.0))
    p, v, e = plan.sample(9.75)     # the middle of the transition
    assert np.allclose(p, 0.05) and np.allclose(v, 1.5 * 0.1 / 1.5)
    assert np.allclose(e, 5.0)
    assert np.allclose(plan.sample(10.5)[0], 0.1)
    # After the end: the last point, at rest, its effort.
    assert plan.sample(12.0) == ((0.2,) * 3, ZERO, (2.0,) * 3)
    assert plan.finished(11.0) and not plan.finished(10.99)


def test_points_past_at_the_acceptance_are_skipped():
    """Accepted at 11 s, 1 s after the start: to the point at 2 s."""
    plan = JointPlan(10.0, [0.5, 1.0, 2.0], [[0.1] * 3, [0.2] * 3,
                                             [0.4] * 3],
                     [ZERO] * 3, [[1.0] * 3, [2.0] * 3, [4.0] * 3],
                     ((0.3,) * 3, ZERO, (6.0,) * 3), 11.0)
    p, v, e = plan.sample(11.5)
    assert np.allclose(p, 0.35) and np.allclose(e, 5.0)
    assert np.allclose(plan.sample(12.0)[0], 0.4)


def points(times, positions, velocities, efforts=None, names=NAMES,
           stamp=(50, 0)):
    n, width = len(times), len(names)
    arrays = [np.asarray(a, dtype=float).reshape(n, width)
              if a is not None else np.full((n, width), np.nan)
              for a in (positions, velocities, None, efforts)]
    lengths = np.array([[width if a is not None else 0] * n
                        for a in (positions, velocities, None, efforts)])
    ns = np.round(np.asarray(times) * 1e9).astype(np.int64)
    return JointPoints(stamp, '', tuple(names), lengths, *arrays,
                       np.column_stack(divmod(ns, 10**9)))


def controller(**changes):
    values = PARAMETERS.defaults()
    values.update(changes)
    return Tracking(PARAMETERS.parse(values))


def test_trajectory_followed_with_the_law_then_its_last_point_held():
    core = controller(kp=[100.0] * 3, kd=[10.0] * 3)
    core.measured(STAMP, '', NAMES, ZERO, ZERO, [], 0.0)
    core.trajectory(points([0.0, 1.0], [ZERO, [0.01] * 3], [ZERO, ZERO],
                           [[5.0] * 3, [7.0] * 3]), 49.0, 0.0)
    # The measurement arrived 10 ms ago: sampled at 50.5 s, halfway,
    # p = 0.005, v = 0.015, the instant the measured state describes.
    command = core.tick(50.51, 0.01)
    assert command.force == pytest.approx((6.0 + 0.5 + 0.15,) * 3)
    assert core.plan_finished is False
    # A desired state while it runs is skipped, counted.
    assert core.desired(STAMP, '', NAMES, ZERO, ZERO, ZERO, 0.02) is None
    assert core.skipped['trajectory_active'] == 1
    core.measured(STAMP, '', NAMES, [0.01] * 3, ZERO, [], 0.03)
    held = core.tick(60.0, 0.04)
    assert core.plan_finished and held.force == pytest.approx((7.0,) * 3)
    # After the end a desired state takes over.
    assert core.desired(STAMP, '', NAMES, [0.01] * 3, ZERO, [1.0] * 3, 0.05)
    assert core.plan is None


def test_a_payload_the_plan_does_not_hold_is_added_to_its_efforts():
    """robot.payload on the controller: the planned efforts plus its force."""
    from orthoglide_ros.model.mechanics import payload_force, solve
    home = solve(Robot(), ZERO)
    lifted = solve(Robot(), (0.0, 0.0, 0.02))
    trajectory = points([0.0, 1.0], [home.lambda_, lifted.lambda_],
                        [ZERO, ZERO], [home.force, lifted.force])
    commands = {}
    for payload in (0.0, 5.0):
        core = controller(kp=[0.0] * 3, kd=[0.0] * 3,
                          **{'robot.payload': payload})
        core.measured(STAMP, '', NAMES, home.lambda_, ZERO, [], 0.0)
        core.trajectory(trajectory, 49.0, 0.0)
        commands[payload] = core.tick(50.3, 0.0).force
        plan = core.plan
    p, v, e = plan.sample(50.3)
    carried = payload_force(Robot(), 5.0, p, v, plan.acceleration(50.3))
    assert commands[0.0] == pytest.approx(e, abs=1e-12)
    assert commands[5.0] == pytest.approx(
        tuple(a + b for a, b in zip(e, carried)), abs=1e-12)
    # Slider C carries the payload's weight, 49 N, and its acceleration.
    assert commands[5.0][2] - commands[0.0][2] == pytest.approx(49.05,
                                                                rel=0.05)
    assert dict(core.status(1.0).values)['payload (kg)'] == 5.0


def test_zero_stamp_starts_at_reception_and_a_new_one_replaces_it():
    core = controller()
    core.measured(STAMP, '', NAMES, ZERO, ZERO, [], 0.0)
    core.trajectory(points([0.5], [[0.01] * 3], [ZERO], [ZERO],
                           stamp=(0, 0)), 20.0, 0.0)
    assert core.plan.start == 20.0
    # Sooner than 1 / rate_hz after the first: it waits for the next tick.
    core.trajectory(points([0.5], [[0.02] * 3], [ZERO], [ZERO],
                           stamp=(30, 500_000_000)), 20.0, 0.0)
    assert core.plan.start == 20.0 and core.trajectories == 1
    core.tick(20.004, 0.004)
    assert core.plan.start == 30.5 and core.trajectories == 2
    # Later than 1 / rate_hz: at once.
    core.trajectory(points([0.5], [[0.03] * 3], [ZERO], [ZERO],
                           stamp=(0, 0)), 21.0, 1.0)
    assert core.plan.start == 21.0 and core.trajectories == 3


def test_accepting_a_plan_does_not_change_the_force():
    """
    The effort goes from the last command to the first point's.

    Not the first point's effort at once: here a large inertial force (a
    motion that starts accelerating), which would push the robot off the
    state the plan starts from for the whole wait.
    """
    core = controller(kp=[100.0] * 3, kd=[10.0] * 3)
    core.measured(STAMP, '', NAMES, ZERO, ZERO, [], 0.0)
    before = core.desired(STAMP, '', NAMES, ZERO, ZERO, [3.0] * 3, 0.0)
    assert before.force == pytest.approx((3.0,) * 3)
    core.trajectory(points([0.0, 1.0], [ZERO, [0.01] * 3], [ZERO, ZERO],
                           [[150.0] * 3, [7.0] * 3]), 49.0, 0.0)
    accepted = core.tick(49.0, 0.0)     # the start is at 50 s
    assert accepted.force == pytest.approx((3.0,) * 3)
    waiting = core.tick(49.5, 0.0)
    assert waiting.force == pytest.approx(((3.0 + 150.0) / 2,) * 3)
    started = core.tick(50.0, 0.0)
    assert started.force == pytest.approx((150.0,) * 3)


def test_a_trajectory_that_ends_in_the_past_is_refused():
    """As JTC: a non-zero stamp whose last point is past; zero is now."""
    core = controller()
    core.measured(STAMP, '', NAMES, ZERO, ZERO, [], 0.0)
    with pytest.raises(Rejected) as info:
        core.trajectory(points([0.5], [ZERO], [ZERO], [ZERO],
                               stamp=(10, 0)), 10.6, 0.0)
    assert info.value.reason == 'time' and 'past' in str(info.value)
    assert core.rejected['trajectory', 'time'] == 1 and core.plan is None
    core.trajectory(points([0.0], [[0.01] * 3], [ZERO], [ZERO],
                           stamp=(0, 0)), 10.6, 0.0)
    assert core.tick(10.6, 0.001).error == pytest.approx((0.01,) * 3)


@pytest.mark.parametrize('reason, build', [
    ('empty', lambda: points([], np.zeros((0, 3)), np.zeros((0, 3)),
                             np.zeros((0, 3)))),
    ('missing_joint', lambda: points([1.0], [ZERO], [ZERO], [ZERO],
                                     names=('a', 'b', 'c'))),
    ('missing_velocity', lambda: points([1.0], [ZERO], None, [ZERO])),
    ('missing_effort', lambda: points([1.0], [ZERO], [ZERO], None)),
    ('non_finite', lambda: points([1.0], [[np.nan, 0.0, 0.0]], [ZERO],
                                  [ZERO])),
    ('time', lambda: points([1.0, 1.0], [ZERO, ZERO], [ZERO, ZERO],
                            [ZERO, ZERO])),
])
def test_a_bad_trajectory_is_refused_whole_and_counted(reason, build):
    core = controller()
    with pytest.raises(Rejected) as info:
        core.trajectory(build(), 0.0, 0.0)
    assert info.value.reason == reason
    assert core.rejected['trajectory', reason] == 1
    assert core.plan is None


# A flood of replacements ----------------------------------------------------
def flood_loop(flood_seconds=1.0, after=None, clock=100.0):
    """
    Run the controller on the simulated robot under a trajectory flood.

    Every millisecond a new one-point trajectory, its target alternating
    between 0 and 10 mm on every slider 50 ms ahead (efforts zero), as the
    hostile peer sends it; the robot measured every
    millisecond, the controller ticking at its rate_hz, the command held
    by the plant (RK4, 1 kHz). ``after``: a trajectory sent once the flood
    is over, followed for 1.5 s. Returns the commands and slider speeds.
    """
    robot = Robot()
    plant = Plant(robot, force_limit=1000.0)
    core = controller()
    settings = core.settings
    ticks_per = round(1000.0 / settings.rate_hz)
    force, commands, speeds = mechanics.solve(robot, ZERO).force, [], []
    steps = int(flood_seconds * 1000) + (1500 if after is not None else 0)
    for k in range(steps):
        now = k * 1e-3
        lam, lamdot = plant.joint_state()
        speeds.append(max(abs(v) for v in lamdot))
        core.measured(STAMP, '', NAMES, lam, lamdot, [], now)
        if k < flood_seconds * 1000:
            target = [0.01 * (k % 2)] * 3
            core.trajectory(points([0.05], [target], [ZERO], [ZERO],
                                   stamp=(0, 0)), clock + now, now)
        elif k == flood_seconds * 1000:
            core.trajectory(after(lam), clock + now, now)
        if k % ticks_per == 0:
            command = core.tick(clock + now, now)
            if command is not None:
                force = command.force
                commands.append(command)
        plant.step(force, 1e-3)
    return core, commands, np.array(speeds)


def test_a_flood_of_replacements_never_saturates_nor_runs_away():
    """
    1 kHz of alternating one-point trajectories, then a normal one.

    Each replacement starts from the desired state being followed, never
    from the last command, and at most one is taken per tick: no command
    clips, no slider exceeds 0.5 m/s, and the normal trajectory that
    follows (10 mm back to home in 1 s) is followed to within 1 mm.
    """
    def back_home(lam):
        return points([1.0], [ZERO], [ZERO], [mechanics.solve(
            Robot(), ZERO).force], stamp=(0, 0))

    core, commands, speeds = flood_loop(after=back_home)
    assert sum(c.clipped for c in commands) == 0
    assert max(max(abs(f) for f in c.force) for c in commands) < 500.0
    assert speeds.max() <= 0.5
    assert core.mode == 'following' and core.plan_finished
    assert max(abs(e) for e in commands[-1].error) < 1e-3
    assert core.superseded > 0


def test_implausible_trajectories_are_refused_whole():
    """Efforts, positions, velocities of 1e300; a 15 m/s plan."""
    huge = [[0.0, 0.0, 1e300]]
    for reason, build in (
            ('effort_limit', lambda: points([0.5], [ZERO], [ZERO], huge)),
            ('position_limit', lambda: points([0.5], huge, [ZERO], [ZERO])),
            ('velocity_limit', lambda: points([0.5], [ZERO], huge, [ZERO])),
            # Reachable only at 15 m/s from where the robot is.
            ('velocity_limit', lambda: points([0.001], [[0.01] * 3], [ZERO],
                                              [ZERO], stamp=(0, 0)))):
        core = controller()
        core.measured(STAMP, '', NAMES, ZERO, ZERO, [], 0.0)
        with pytest.raises(Rejected) as info:
            core.trajectory(build(), 10.0, 0.0)
        assert info.value.reason == reason, info.value
        assert core.rejected['trajectory', reason] == 1
        assert core.plan is None
