"""
Planned motions: within every limit, on the path, at rest, optimal.

- a straight line rest to rest under one constant limit takes its
  closed-form bang-bang duration;
- a contour of lines, tangent arcs and a helical turn, on a robot with
  drives and a payload, takes within 1 % of toppra's optimum on a fine
  grid (an independent solver of the same problem);
- random programs of lines and arcs inside the workspace, random limits
  (hypothesis): every sample within every limit (the package's model on
  every sample, the Lagrange model of ``mechanics_reference`` on the
  samples nearest their limits), on the programmed path, at rest at both
  ends, velocities and accelerations those of the positions;
- friction (viscous, Coulomb per direction, Stribeck) and jerk limits are
  kept;
- a path out of the workspace, statics beyond a limit and nothing that
  bounds the motion are refused, naming the line;
- a chord program of a 3D loop moves as the loop itself would (toppra on
  the true curve), G5 splines are followed exactly, a fitted curve that
  leaves the workspace is refused naming its line, and G's velocity is
  continuous through fitted curves.
"""

import math

from hypothesis import assume, example, given, HealthCheck, settings, \
    strategies as st
from mechanics_reference import DRIVES_ROBOT_VALUES
import numpy as np
from planning_checks import (CurvePath, distance_to_path,
                             friction_reference, lagrange_check,
                             path_distance, toppra_duration)
import pytest

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.planning import gcode, path as paths
from orthoglide_ros.planning.limits import limits_from_mapping
from orthoglide_ros.planning.limits import paper_limits
from orthoglide_ros.planning.moves import ProgramError, TOO_LARGE
from orthoglide_ros.planning.parametrization import (ACCEPT_SHARE, plan,
                                                     PlanningError)
from orthoglide_testing.chord_programs import (bulge_points, LOOP_RADIUS,
                                               loop_point, loop_program)

RATE = 1000.0
DRIVES = Robot(**DRIVES_ROBOT_VALUES)
# Drives with force limits of 160-520 N (doc/programs/drives_limits.yaml).
EFFORTS = {'slider_a': 160.0, 'slider_b': 250.0, 'slider_c': 520.0}
CONTOUR = """(pocket contour: lines, tangent arcs, a helical turn)
G21 G90 G17 G94
F30000
G1 X50 Y0 Z0
G3 X70 Y20 I0 J20
G1 Y60
G3 X50 Y80 I-20 J0
G1 X-50
G3 X-70 Y60 J-20
G1 Y20
G3 X-50 Y0 I20
G1 X0
G2 X0 Y0 Z-30 I0 J40 (helical turn)
G1 Z-60
M30
"""


def efforts(values=EFFORTS):
    return limits_from_mapping({name: {'has_effort_limits': True,
                                       'max_effort': value}
                                for name, value in values.items()})


def program_path(text, tolerance=1e-5, start=(0.0, 0.0, 0.0)):
    return paths.from_moves(gcode.read_gcode(text, start), tolerance)


def dense(path, points=200000):
    """Return points along ``path``, about every length / ``points``."""
    out = []
    for k, piece in enumerate(path.pieces):
        n = max(8, int(points * piece.length / path.length))
        w = np.linspace(0.0, piece.length, n)
        out.append(path.evaluate(np.full(n, k), w)[0])
    return np.vstack(out)


def shares(motion, limits):
    """Return the largest |value| / limit of each limit over every sample."""
    sol = motion.solution
    with np.errstate(divide='ignore'):
        out = {'effort': np.abs(sol.force) / limits.effort,
               'velocity': np.abs(sol.lambdadot) / limits.velocity,
               'acceleration': np.abs(sol.lambdaddot) / limits.acceleration}
        if np.isfinite(limits.jerk).any():
            jerk = np.abs(np.diff(sol.lambdaddot, axis=0)) / np.diff(
                motion.t)[:, None]
            out['jerk'] = jerk / limits.jerk
    return {k: float(v.max()) for k, v in out.items()}


def nearest_samples(motion, limits, count=3):
    """Return the samples nearest each limit (force, rate, acceleration)."""
    sol = motion.solution
    nearest = set()
    for values, bound in ((sol.force, limits.effort),
                          (sol.lambdadot, limits.velocity),
                          (sol.lambdaddot, limits.acceleration)):
        with np.errstate(divide='ignore'):
            ratio = (np.abs(values) / bound).max(1)
        nearest.update(np.argsort(ratio)[-count:].tolist())
    return sorted(nearest)


def assert_consistent(motion, path=None):
    """
    At rest at both ends; velocity and acceleration those of the positions.

    The first sample holds the acceleration the motion starts with, the
    last one is at rest (velocity and acceleration zero: what holds G
    there), so the last interval's acceleration is its start's. ``path``:
    where its junctions are (a blend there may be passed between two
    samples).
    """
    t, p, v, a = (motion.t, motion.position, motion.velocity,
                  motion.acceleration)
    assert np.all(v[0] == 0.0) and np.all(v[-1] == 0.0)
    assert np.all(a[-1] == 0.0)
    assert np.allclose(np.diff(t), 1.0 / RATE, rtol=0.0, atol=1e-12)
    dt = np.diff(t)[:, None]
    a_in = a[:-1].copy()
    after = a[1:].copy()
    after[-1] = a[-2]       # the last interval: its start's acceleration
    # Positions: the trapezoid of the velocities. Its error over an
    # interval is the integral of (dt / 2 - s) a(s) ds, at most dt^2 / 8
    # times the range of the acceleration within the interval, which its
    # two samples show (a switch of the bang-bang law within it) but for a
    # blend of a few micrometres passed between them: next to a junction
    # the range may be twice the largest acceleration.
    jump = np.linalg.norm(after - a_in, axis=1)[:, None]
    step = np.abs(np.diff(p, axis=0) - 0.5 * (v[1:] + v[:-1]) * dt)
    largest = np.abs(a).max()
    bound = jump * dt ** 2 / 8 + 1e-3 * largest * dt ** 2 + 1e-12
    if path is not None:
        ends = np.array([path.evaluate(np.array([k]),
                                       np.array([piece.length]))[0][0]
                         for k, piece in enumerate(path.pieces)])
        nearest = np.linalg.norm(p[:, None] - ends[None], axis=2).argmin(0)
        for k in nearest:
            bound[max(k - 2, 0):k + 2] += 2.0 * largest * dt[0] ** 2 / 8
    assert (step <= bound).all(), step.max()
    # Velocities: the trapezoid of the accelerations, integrated from
    # rest, each interval off by at most half the jump of the
    # acceleration across it (a switch of the law within it, or a short
    # curve of high curvature passed within a period).
    error = np.abs(v[1:] - np.cumsum(0.5 * (after + a_in) * dt, axis=0))
    budget = np.cumsum(0.5 * jump * dt) + 1e-3 * np.abs(a).max() * t[1:]
    assert (error <= budget[:, None] + 1e-12).all()


@pytest.mark.parametrize('limits, expected', (
    ({'slider_a': {'max_acceleration': 5.0}}, 2.0 * math.sqrt(0.1 / 5.0)),
    ({'slider_a': {'max_acceleration': 5.0, 'max_velocity': 0.5}},
     0.1 / 0.5 + 0.5 / 5.0),
), ids=('triangle', 'trapezoid'))
def test_a_line_rest_to_rest_takes_its_bang_bang_duration(limits, expected):
    """
    Along x through home, lambda_A = x + const: a |lambdaddot_A| limit is G's.

    The bang-bang law under a constant limit, its duration in closed
    form, up to the period the duration is rounded up to.
    """
    path = program_path('G0 X100')
    motion = plan(Robot(), path, limits_from_mapping(limits), RATE)
    assert expected * (1 - 1e-9) <= motion.duration <= expected * 1.001 \
        + 1.0 / RATE
    assert_consistent(motion)


def test_the_contour_is_within_1_percent_of_toppra_on_a_fine_grid():
    """Drives and a payload, force limits of 160-520 N; no friction."""
    path = program_path(CONTOUR)
    limits = efforts()
    motion = plan(DRIVES, path, limits, RATE)
    optimum = toppra_duration(DRIVES, path, limits, intervals=8000)
    assert abs(motion.duration - optimum) <= 0.01 * optimum, (
        motion.duration, optimum)
    assert shares(motion, limits)['effort'] <= 1.0 + ACCEPT_SHARE
    # The tangent junctions are passed at speed: only the corners stop.
    speed = np.linalg.norm(motion.velocity, axis=1)
    rests = np.sum((speed[1:-1] == 0.0))
    assert rests <= 2
    assert path_distance(motion.position, dense(path)).max() <= 2e-6


def _line_or_arc(draw, here):
    """One random G-code move from ``here`` (mm) inside the cube."""
    target = [draw(st.floats(-150.0, 150.0)) for _ in range(3)]
    if draw(st.booleans()):
        return 'G1 X{:.4f} Y{:.4f} Z{:.4f}'.format(*target), target
    plane = draw(st.sampled_from((17, 18, 19)))
    axes = {17: (0, 1, 2), 18: (2, 0, 1), 19: (1, 2, 0)}[plane]
    letters = {17: 'IJ', 18: 'KI', 19: 'JK'}[plane]
    radius = draw(st.floats(10.0, 60.0))
    angle = draw(st.floats(0.0, 2.0 * math.pi))
    offset = (radius * math.cos(angle), radius * math.sin(angle))
    centre = [here[axes[0]] + offset[0], here[axes[1]] + offset[1]]
    sweep = draw(st.floats(0.3, 5.0))
    ccw = draw(st.booleans())
    start = math.atan2(-offset[1], -offset[0])
    end = start + (sweep if ccw else -sweep)
    target = list(here)
    target[axes[0]] = centre[0] + radius * math.cos(end)
    target[axes[1]] = centre[1] + radius * math.sin(end)
    target[axes[2]] = here[axes[2]] + draw(st.floats(-20.0, 20.0))
    if max(abs(c) for c in target) > 160.0 or max(
            abs(c) + radius for c in centre) > 200.0:
        return None, here
    words = ' '.join('{}{:.6f}'.format('XYZ'[k], target[k]) for k in range(3))
    return (f'G{plane} G{3 if ccw else 2} {words} {letters[0]}{offset[0]:.6f} '
            f'{letters[1]}{offset[1]:.6f}'), target


@st.composite
def programs(draw):
    """Draw a G-code program of 1-4 lines and arcs inside the workspace."""
    here = [0.0, 0.0, 0.0]
    mode = draw(st.sampled_from(('G61', 'G61.1', 'G64 P0.01', 'G64')))
    lines = [f'G21 G90 {mode} F{draw(st.floats(3000.0, 60000.0)):.1f}']
    for _ in range(draw(st.integers(1, 4))):
        line, target = _line_or_arc(draw, here)
        if line is not None:
            # Rounded to the program's digits: the arcs' ends as written.
            lines.append(line)
            here = target
    lines.append('M2')
    return '\n'.join(lines)


@st.composite
def limit_sets(draw):
    """Draw limits: efforts above the statics, maybe velocity, acceleration."""
    entries = {}
    for name, statics in zip(('slider_a', 'slider_b', 'slider_c'),
                             (150.0, 150.0, 400.0)):
        entry = {'max_effort': statics + draw(st.floats(50.0, 400.0))}
        if draw(st.booleans()):
            entry['max_velocity'] = draw(st.floats(0.1, 1.0))
        if draw(st.booleans()):
            entry['max_acceleration'] = draw(st.floats(2.0, 40.0))
        entries[name] = entry
    return limits_from_mapping(entries)


@pytest.mark.slow     # 3.1-3.6 s of CPU, one process, 2026-12-06
@settings(max_examples=8, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(programs(), limit_sets())
@example(  # a 10 um blend passed within a few samples
    'G21 G90 G64 P0.01 F19975.7\n'
    'G17 G2 X-38.889844 Y107.404913 Z5.000000 I-34.267190 J48.335517\n'
    'G17 G3 X-25.671738 Y97.936872 Z5.000000 I10.000000 J0.000000\n'
    'G1 X0 Y0 Z0\nG1 X0 Y59 Z0\nM2',
    efforts({'slider_a': 250.0, 'slider_b': 333.0, 'slider_c': 450.0}))
def test_random_programs_keep_every_limit_on_the_path(program, limits):
    try:
        path = program_path(program)
    except ProgramError:      # moves nothing; an arc end off its circle
        assume(False)
    motion = plan(DRIVES, path, limits, RATE)
    for name, share in shares(motion, limits).items():
        assert share <= 1.0 + ACCEPT_SHARE, (name, share)
    # The independent model on the samples nearest their limits.
    for name, share in lagrange_check(DRIVES, motion, limits,
                                      nearest_samples(motion, limits)).items():
        assert share <= 1.0 + ACCEPT_SHARE + 1e-6, (name, share)
    assert path_distance(motion.position, dense(path)).max() <= 2e-6
    assert np.allclose(motion.position[0], 0.0, atol=1e-12)
    assert np.allclose(motion.position[-1], path.end, atol=1e-12)
    assert_consistent(motion, path)


def test_friction_of_every_law_is_kept():
    """Viscous, Coulomb both ways apart, Stribeck: forces within limits."""
    robot = DRIVES.replace(friction_viscous=(30.0, 40.0, 50.0),
                           friction_coulomb=(5.0, 3.0, 4.0),
                           friction_coulomb_negative=(7.0, 2.0, 6.0),
                           friction_stribeck=(3.0, 2.0, 4.0))
    path = program_path(CONTOUR)
    limits = efforts()
    motion = plan(robot, path, limits, RATE)
    force = mechanics.solve_batch(robot.frictionless(), motion.position,
                                  motion.velocity,
                                  motion.acceleration).force
    force = force + friction_reference(robot, motion.solution.lambdadot)
    assert (np.abs(force) / limits.effort).max() <= 1.0 + ACCEPT_SHARE
    # Friction slows it, a little.
    assert motion.duration >= plan(DRIVES, path, limits, RATE).duration


@pytest.mark.parametrize('jerk', (500.0, 5000.0))
def test_jerk_limits_are_kept_from_sample_to_sample(jerk):
    path = program_path(CONTOUR)
    limits = limits_from_mapping({
        name: {'max_effort': value, 'max_jerk': jerk}
        for name, value in EFFORTS.items()})
    motion = plan(DRIVES, path, limits, RATE)
    for name, share in shares(motion, limits).items():
        assert share <= 1.0 + ACCEPT_SHARE, (name, share)
    assert np.all(motion.acceleration[[0, -1]] == 0.0)
    assert path_distance(motion.position, dense(path)).max() <= 2e-6
    unlimited = plan(DRIVES, path, efforts(), RATE).duration
    assert motion.duration > unlimited


def test_a_path_out_of_the_workspace_is_refused_naming_line_and_point():
    path = program_path('G21 G90 F6000\nG1 X100\nG1 X900\nM2')
    with pytest.raises(PlanningError) as error:
        plan(DRIVES, path, efforts(), RATE)
    assert error.value.line == 3
    assert str(error.value).startswith('line 3: the path at [')
    assert '] m is too near a singularity' in str(error.value)


def test_statics_beyond_a_limit_are_refused_naming_line_joint_force():
    """C holds about 305 N at home, 380 N at (-200, -200, -250) mm."""
    path = program_path('G21 G90 F6000\nG1 X10\n\nG1 X-200 Y-200 Z-250\nM2')
    limits = efforts({'slider_a': 400.0, 'slider_b': 400.0,
                      'slider_c': 350.0})
    with pytest.raises(PlanningError) as error:
        plan(DRIVES, path, limits, RATE)
    message = str(error.value)
    assert message.startswith('line 4: at [')
    assert 'slider_c needs 35' in message and 'N at rest' in message
    assert 'beyond its max_effort 350 N' in message


def test_nothing_bounding_is_refused():
    path = program_path('G0 X10\nM2')
    with pytest.raises(PlanningError, match='nothing bounds the motion'):
        plan(DRIVES, path, limits_from_mapping({}), RATE)
    feed_only = program_path('G1 X10 F600\nM2')
    with pytest.raises(PlanningError, match='line 1: nothing bounds the '
                       'acceleration'):
        plan(DRIVES, feed_only, limits_from_mapping({}), RATE)


def velocity_steps(motion):
    """
    Return, per interval, the velocity change its accelerations leave out.

    ``|dv / dt - (a_k + a_k+1) / 2| - |a_k+1 - a_k| / 2`` (m/s^2): the
    trapezoid's error is at most half the acceleration's jump within the
    interval (a switch of the time law there); the last interval (the last
    sample holds no acceleration) left out.
    """
    v, a = motion.velocity, motion.acceleration
    dt = np.diff(motion.t)[:, None]
    change = np.linalg.norm(np.diff(v, axis=0) / dt
                            - 0.5 * (a[1:] + a[:-1]), axis=1)
    jump = np.linalg.norm(np.diff(a, axis=0), axis=1)
    return (change - 0.5 * jump)[:-1]


def assert_continuous_at_100_khz(path):
    """Planned at 100 kHz: every velocity change its accelerations', no stop."""
    motion = plan(Robot(), path, efforts({'slider_a': 650.0, 'slider_b':
                                          650.0, 'slider_c': 650.0}),
                  100000.0)
    largest = np.abs(motion.acceleration).max()
    assert velocity_steps(motion).max() <= 1e-6 * largest
    speed = np.linalg.norm(motion.velocity, axis=1)
    assert (speed[1:-1] > 0.0).all()


def test_g_velocity_is_continuous_through_bezier_blends():
    """
    At 100 kHz every change of G's velocity is its accelerations'.

    A line meeting an arc under G64 P: a Bezier blend, its parameter its
    arc length, so no velocity step where it begins and ends (a parameter
    off its arc length by 1-20 % left 400 m/s^2 unexplained).
    """
    path = program_path('G21 G64 P0.5 F6000\nG1 X20\nG3 X40 Y0 I10 J0\n'
                        'G1 Y20')
    assert 'bezier' in [piece.kind for piece in path.pieces]
    assert_continuous_at_100_khz(path)


@pytest.mark.parametrize('text', (
    'G21 G61 F6000\nG1 X10 Y20\nG1 X20 Y40\nG1 X30 Y60',
    'G21 G64 P0.01 F6000\nG1 X10 Y20\nG1 X20 Y40\nG1 X30 Y60',
    'G21 G64 F6000\nG1 X7 Y13 Z-3\nG1 X14 Y26 Z-6',
))
def test_collinear_moves_are_passed_at_speed(text):
    """One line to the planner: planned as the single move would be."""
    limits = efforts()
    motion = plan(DRIVES, program_path(text), limits, RATE)
    last = text.splitlines()[-1].split()[1:]
    single = plan(DRIVES, program_path(text.splitlines()[0] + '\nG1 '
                                       + ' '.join(last)), limits, RATE)
    assert motion.duration == single.duration
    assert np.allclose(motion.position, single.position, atol=1e-12)
    speed = np.linalg.norm(motion.velocity, axis=1)
    assert (speed[1:-1] > 0.0).all()


def test_a_straight_runs_refusal_names_the_line_of_its_point():
    path = program_path('G21 G90 F6000\nG1 X100\nG1 X500\nG1 X900\nM2')
    assert len(path.pieces) == 1
    with pytest.raises(PlanningError) as error:
        plan(DRIVES, path, efforts(), RATE)
    assert str(error.value).startswith('line 4: the path at ['), str(
        error.value)


def test_a_start_out_of_the_workspace_is_not_blamed_on_a_line():
    path = program_path('G21 G90 F6000\nG1 X100\nM2', start=(0.9, 0.0, 0.0))
    with pytest.raises(PlanningError) as error:
        plan(DRIVES, path, efforts(), RATE)
    assert error.value.line is None
    assert str(error.value).startswith('the start of the path at [0.9, 0, '
                                       '0] m is out of reach of leg B')


@pytest.mark.parametrize('text, words', (
    # 100,000 turns of a 10 mm helix: 18,000,000 gridpoints, counted.
    ('G21 F6000\nG0 X10\nG2 X10 Y0 Z-1 I-10 J0 P100000', 'the path of 2 '
     'pieces and 6283.2 m needs 18,000,006 gridpoints: more than the 900 MB '
     'left for the plan hold (1000 bytes each)'),
    # 10 mm at 0.035 mm/min: 4.8 hours.
    ('G21 G1 F0.035 X10', 'the motion lasts 17160 s: 17,160,001 samples at '
     '1000 Hz, more than the 2,993,320 this planner may hold'),
))
def test_memory_is_bounded_before_anything_is_made(text, words):
    """Refused (TOO_LARGE) naming the size, within a few MB of memory."""
    import tracemalloc
    path = program_path(text)
    tracemalloc.start()
    try:
        with pytest.raises(PlanningError) as error:
            plan(Robot(), path, efforts(), RATE)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert error.value.reason == TOO_LARGE
    assert words in str(error.value), str(error.value)
    assert peak < 20e6


def test_a_plan_past_its_time_is_refused():
    with pytest.raises(PlanningError) as error:
        plan(DRIVES, program_path(CONTOUR), efforts(), RATE,
             max_seconds=1e-9)
    assert error.value.reason == 'timeout'
    assert str(error.value) == 'planning took more than 1e-09 s'


@pytest.mark.slow     # 1.8 s of CPU, one process, 2026-12-06
def test_a_chord_program_of_a_3d_loop_moves_as_its_curve_does():
    """
    A 3D loop as 95 chords (sagitta up to 52 um), plain G64, 1 m/s feed.

    Within 1 % of toppra's optimum along the true curve (which the planner
    never sees), the motion within 15 um of that curve and every
    programmed point within the tolerance; every limit kept (the Lagrange
    model on the samples nearest them). The chords as lines (G64 P0.01)
    take a fifth longer at least: G slows at every vertex.
    """
    text, start = loop_program(feed=60000.0)
    path = program_path(text, start=start)
    limits = efforts()
    motion = plan(DRIVES, path, limits, RATE)
    curve = CurvePath(loop_point, 0.0, 2 * math.pi, LOOP_RADIUS, 1.0)
    optimum = toppra_duration(DRIVES, curve, limits, intervals=8000)
    assert abs(motion.duration - optimum) <= 0.01 * optimum, (
        motion.duration, optimum)
    assert distance_to_path(curve, motion.position).max() <= 15e-6
    points = np.array([m.end for m in gcode.read_gcode(text, start)])
    assert distance_to_path(path, points).max() <= 1e-5
    for name, share in shares(motion, limits).items():
        assert share <= 1.0 + ACCEPT_SHARE, (name, share)
    for name, share in lagrange_check(DRIVES, motion, limits,
                                      nearest_samples(motion, limits)).items():
        assert share <= 1.0 + ACCEPT_SHARE + 1e-6, (name, share)
    assert_consistent(motion, path)
    lines = plan(DRIVES, program_path(text.replace('G64', 'G64 P0.01'),
                                      start=start), limits, RATE)
    assert lines.duration >= 1.2 * motion.duration


def test_g5_splines_are_followed_exactly_and_passed_at_speed():
    """
    A line, then two G5 tangent to it and to each other: no stop inside.

    Every sample on the splines as LinuxCNC defines them (their control
    points written here), velocity and acceleration those of the
    positions.
    """
    text = ('G21 G90 G61 F6000\nG1 X10\nG5 I5 J0 P0 Q-10 X30 Y20\n'
            'G5 P10 Q0 X50 Y0\nM2')
    path = program_path(text)
    motion = plan(DRIVES, path, efforts(), RATE)
    speed = np.linalg.norm(motion.velocity, axis=1)
    assert (speed[1:-1] > 0.0).all()
    mm = 1e-3
    curves = [np.array(c) * mm for c in (
        [(10, 0, 0), (15, 0, 0), (30, 10, 0), (30, 20, 0)],
        [(30, 20, 0), (30, 30, 0), (60, 0, 0), (50, 0, 0)])]

    def cubic(control):
        def curve(t):
            t = np.asarray(t, dtype=float)[:, None]
            u = 1 - t
            p = (u ** 3 * control[0] + 3 * u * u * t * control[1]
                 + 3 * u * t * t * control[2] + t ** 3 * control[3])
            d1 = 3 * (u * u * (control[1] - control[0]) + 2 * u * t * (
                control[2] - control[1]) + t * t * (control[3] - control[2]))
            d2 = 6 * (u * (control[2] - 2 * control[1] + control[0])
                      + t * (control[3] - 2 * control[2] + control[1]))
            return p, d1, d2
        return CurvePath(curve, 0.0, 1.0, 0.05)
    on = motion.position[:, 0] >= 0.010 + 1e-9
    near = np.min([distance_to_path(cubic(c), motion.position[on])
                   for c in curves], axis=0)
    assert near.max() <= 1e-9
    assert_consistent(motion, path)


def test_a_curve_that_bulges_out_of_the_workspace_is_refused():
    """
    A curve through chords within the workspace, itself beyond: refused.

    Chords 20 um inside the singular margin, the curve through them 20 um
    beyond: refused naming the chord's line; as lines (G64 P), planned.
    """
    body = ''.join('G1 X%.6f Y%.6f\n' % (a * 1e3, b * 1e3)
                   for a, b, _ in bulge_points())
    path = program_path('G21 G90 G64 F6000\n' + body)
    with pytest.raises(PlanningError) as error:
        plan(Robot(), path, paper_limits(), RATE)
    assert str(error.value).startswith('line 12: the path at [')
    assert 'too near a singularity' in str(error.value)
    lines = program_path('G21 G90 G64 P0.001 F6000\n' + body)
    assert plan(Robot(), lines, paper_limits(), RATE).duration > 0.0


def test_g_velocity_is_continuous_through_fitted_curves():
    """
    At 100 kHz every change of G's velocity is its accelerations'.

    Chords of an arc, a long line tangent to it, chords of another arc:
    the curves' parameter their arc length, their ends tangent to the line.
    """
    first = np.array([(20 * math.cos(a), 20 * math.sin(a), 0.0)
                      for a in np.linspace(-math.pi / 2, 0.0, 21)])
    second = np.array([(20 * math.cos(a), 40 + 20 * math.sin(a), 0.0)
                       for a in np.linspace(0.0, math.pi / 2, 21)])
    text = 'G21 G90 G64 F6000\n' + ''.join(
        'G1 X{:.6f} Y{:.6f}\n'.format(*p[:2]) for p in np.vstack((
            first[1:], second)))
    path = program_path(text, start=first[0] * 1e-3)
    assert [p.kind for p in path.pieces] == ['bezier', 'helix', 'bezier']
    assert_continuous_at_100_khz(path)
