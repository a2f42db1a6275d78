"""
Runs of chords (plain G64, waypoints, a Path) followed as their curve.

A run of short chords becomes one smooth piece through (or within the
tolerance of) every programmed point; corners, reversals, long moves and
coarse polygons stay what they are, by the rules of doc/planning.md;
G64 P keeps its lines. Distances are measured on the path itself
(``distance_to_path``: dense samples, then a golden-section search), never
on the fitting's own numbers.
"""

import math

from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
from planning_checks import distance_to_path, path_distance
import pytest

from orthoglide_ros.planning import chords, gcode
from orthoglide_ros.planning.moves import ProgramError
from orthoglide_ros.planning.path import from_moves, from_waypoints, TANGENT
from orthoglide_testing.chord_programs import spiral_program

TOLERANCE = 1e-5


def path_of(text, tolerance=TOLERANCE, start=(0.0, 0.0, 0.0)):
    return from_moves(gcode.read_gcode(text, start), tolerance)


def programmed(text, start=(0.0, 0.0, 0.0)):
    """Return the program's points: where each of its moves ends."""
    return np.array([m.end for m in gcode.read_gcode(text, start)])


def chords_of(points, head='G21 G90 G64 F6000'):
    """Return G-code of G1 chords through ``points`` (mm, 6 decimals)."""
    return '\n'.join([head] + ['G1 X{:.6f} Y{:.6f} Z{:.6f}'.format(*p)
                               for p in points] + ['M2', ''])


def arc(count, radius=20.0, sweep=math.pi, centre=(0.0, 0.0), start=0.0,
        z=0.0):
    """Return ``count + 1`` points of an arc in XY (mm)."""
    a = start + np.linspace(0.0, sweep, count + 1)
    return np.stack((centre[0] + radius * np.cos(a),
                     centre[1] + radius * np.sin(a), np.full_like(a, z)), 1)


def kinds(path):
    """Return the pieces: ``'line'``, ``'arc'``, or a Bezier's spans."""
    out = []
    for piece in path.pieces:
        if piece.kind == 'bezier':
            out.append(len(piece.control))
        else:
            out.append('line' if piece.radius == 0.0 else 'arc')
    return out


def turns(path):
    """Return the angle between the tangents at each junction (rad)."""
    return np.array([
        math.atan2(np.linalg.norm(np.cross(a.tangent(a.length),
                                           b.tangent(0.0))),
                   a.tangent(a.length) @ b.tangent(0.0))
        for a, b in zip(path.pieces[:-1], path.pieces[1:])])


@pytest.mark.slow     # 3.6 s of CPU, one process, 2026-12-06
def test_a_run_of_chords_is_one_curve_within_the_tolerance():
    """
    The spiral of 1000 chords: a line from home, a corner, one curve.

    Every programmed point within the tolerance of the curve, G stops only
    at the ends; the chords' own sagitta (63 um outside) is not the path.
    """
    text = spiral_program()
    path = path_of(text)
    shape = kinds(path)
    assert shape[0] == 'line' and shape[-1] == 999 and len(shape) == 3
    assert path.stops.tolist() == [True, False, False, True]
    points = programmed(text)
    assert distance_to_path(path, points).max() <= TOLERANCE
    # Not the chords: midway between two outer points the curve is
    # about the chords' sagitta away from them.
    middle = 0.5 * (points[1:40] + points[2:41])
    assert distance_to_path(path, middle).min() >= 20e-6


def test_rounded_points_do_not_bend_the_curve():
    """
    A circle of 10 mm as 0.1 mm chords written to 1 um: its curvature.

    Through the points as written (a C2 spline) its curvature would range
    from 0 to 5.7 / R; smoothed within half the tolerance, it is within
    5 % of 1 / R all along (3 % away from its ends).
    """
    points = np.round(arc(628, radius=10.0, sweep=2 * math.pi), 3)
    path = path_of(chords_of(points), start=points[0] * 1e-3)
    assert kinds(path) == [628]
    piece = path.pieces[0]
    w = np.linspace(0.0, piece.length, 20001)
    curvature = np.linalg.norm(piece.evaluate(w)[2], axis=1) * 0.010
    assert np.abs(curvature[1000:-1000] - 1.0).max() <= 0.03
    assert np.abs(curvature - 1.0).max() <= 0.05
    assert distance_to_path(path, points * 1e-3).max() <= TOLERANCE


def test_a_corner_stays_a_corner():
    """
    Two arcs of chords meeting square: two curves and a blend between.

    And a turn of 12 degrees among turns of 2: a corner too. The corner's
    point within the tolerance of its blend, G passing it at speed.
    """
    first = arc(20, radius=20.0, sweep=math.pi / 2)
    second = arc(20, radius=20.0, sweep=math.pi / 2, centre=(-20.0, 20.0))
    text = chords_of(np.vstack((first[1:], second[1:])))
    path = path_of(text, start=first[0] * 1e-3)
    shape = kinds(path)
    assert len(shape) == 3 and shape[0] == shape[2] == 20
    assert not path.stops[1:-1].any()
    assert distance_to_path(path, programmed(text, first[0] * 1e-3)).max() \
        <= TOLERANCE
    # 2 degrees a chord, then 12 degrees at one vertex, then 2 again.
    directions = np.radians(np.r_[np.arange(0, 20, 2.0),
                                  np.arange(30, 50, 2.0)])
    points = np.vstack((np.zeros(3), np.cumsum(np.stack((
        np.cos(directions), np.sin(directions),
        np.zeros_like(directions)), 1), axis=0)))
    path = path_of(chords_of(points[1:]))
    shape = kinds(path)
    assert len(shape) == 3 and shape[0] == shape[2] == 10
    assert turns(path).max() <= 1e-6 and not path.stops[1:-1].any()


def test_a_reversal_stops_between_two_curves():
    """Out along an arc of chords and back: G stops where it turns about."""
    out = arc(30)
    text = chords_of(np.vstack((out, out[::-1][1:])))
    path = path_of(text, start=out[0] * 1e-3)
    assert kinds(path) == [30, 30]
    assert path.stops.tolist() == [True, True, True]
    assert np.allclose(path.pieces[0].point(path.pieces[0].length),
                       out[-1] * 1e-3, rtol=0, atol=1e-12)


@pytest.mark.parametrize('off', (2e-6, 1e-4, 0.05))
def test_near_an_about_turn_g_stops_or_its_blend_keeps_its_tangents(off):
    """
    Two splines meeting in a hairpin, ``off`` (rad) short of an about-turn.

    Where a blend's ends would lie nearer than a nanometre their tangents
    are rounding (1e-6 rad at 3e-12 m): G stops; where it fits, the blend
    is tangent to both, as every junction G passes at speed.
    """
    back = math.pi / 4 + off
    text = ('G21 G90 G17 G64 F6000\nG5.1 X10 Y0 I5 J5\n'
            'G5.1 X{:.9f} Y{:.9f} I{:.9f} J{:.9f}\n'.format(
                10 - 20 * math.cos(back), 20 * math.sin(back),
                -5 * math.cos(back), 5 * math.sin(back)))
    path = path_of(text, 1e-6)
    assert min(piece.length for piece in path.pieces) >= 1e-9
    passed = ~path.stops[1:-1]
    assert (turns(path)[passed] <= 1e-6).all(), turns(path)
    assert path.stops[1:-1].any() == (off < 0.01)


def test_a_long_move_beside_short_ones_stays_a_line_passed_at_speed():
    """
    Chords of an arc, a 40 mm line tangent to it, chords of another arc.

    The line is the move as written (LONG_RATIO); the curves leave and
    join it tangentially, so G passes both junctions at speed.
    """
    first = arc(20, sweep=math.pi / 2, start=-math.pi / 2)
    line_end = first[-1] + np.array([0.0, 40.0, 0.0])
    second = arc(20, sweep=math.pi / 2, centre=(0.0, 40.0))[1:]
    text = chords_of(np.vstack((first, line_end, second)))
    path = path_of(text, start=first[0] * 1e-3)
    assert kinds(path) == [20, 'line', 20]
    assert path.pieces[1].length == pytest.approx(0.040, abs=1e-12)
    assert not path.stops[1:-1].any()
    assert turns(path).max() <= TANGENT


def test_a_runs_ends_meet_what_is_beside_them():
    """
    From rest and to rest at the program's points; tangent to an arc.

    The first and the last point of a run are the path's, exactly; where
    a run meets an arc (plain G64, not a corner), it leaves along the
    arc's tangent; after a G61 corner nothing is fitted.
    """
    points = arc(20, sweep=math.pi / 2)[1:]
    text = ('G21 G90 G64 F6000\nG2 X20 Y0 I-10 J0\n'
            + chords_of(points, '').strip())
    start = np.array([0.04, 0.0, 0.0])
    path = path_of(text, start=start)
    assert kinds(path) == ['arc', 20]
    assert np.allclose(path.end, points[-1] * 1e-3, rtol=0, atol=1e-15)
    assert turns(path)[0] <= TANGENT
    alone = path_of(chords_of(points), start=points[0] * 1e-3)
    assert kinds(alone) == [19]
    assert np.allclose(alone.start, points[0] * 1e-3, rtol=0, atol=1e-15)
    assert np.allclose(alone.end, points[-1] * 1e-3, rtol=0, atol=1e-15)
    g61 = path_of(text.replace('G64', 'G61'), start=start)
    assert all(k in ('line', 'arc') for k in kinds(g61))


def test_g64_p_keeps_its_lines():
    """The spiral under G64 P0.01 (inches): lines, blends within P of them."""
    text = spiral_program(mode='G64 P0.01')
    path = path_of(text)
    assert all(k in ('line', 'arc') for k in kinds(path))
    points = np.vstack((np.zeros(3), programmed(text)))
    dense = np.vstack([piece.evaluate(np.linspace(0.0, piece.length, 50))[0]
                       for piece in path.pieces])
    polyline = np.vstack([np.linspace(a, b, 200) for a, b in
                          zip(points[:-1], points[1:])])
    assert path_distance(dense, polyline).max() <= 0.01 * 0.0254 * 1.001


def test_a_feed_change_breaks_a_run_smoothly():
    """Two feeds along one arc of chords: two curves, tangent, no stop."""
    points = arc(40, sweep=math.pi)
    text = chords_of(points[1:21]).replace('M2\n', '') + '\n'.join(
        'G1 X{:.6f} Y{:.6f} Z{:.6f} F3000'.format(*p)
        for p in points[21:]) + '\nM2\n'
    path = path_of(text, start=points[0] * 1e-3)
    assert kinds(path) == [20, 20]
    assert [p.feed for p in path.pieces] == [0.1, 0.05]
    assert turns(path).max() <= TANGENT and not path.stops[1:-1].any()


@pytest.mark.slow     # 2.2 s of CPU, one process, 2026-12-06
def test_chords_far_shorter_than_the_tolerance_are_one_point():
    """
    30,000 chords of 1 um along 30 mm of arc: points 5 um apart at least.

    Each dropped point within half the tolerance of the one kept for it,
    the curve within the tolerance of every point.
    """
    points = arc(30000, sweep=1.5)
    path = path_of(chords_of(points[1:]), start=points[0] * 1e-3)
    assert len(path.pieces) == 1
    assert len(path.pieces[0].control) < 30000 / 4
    assert distance_to_path(path, points[::97] * 1e-3).max() <= TOLERANCE


def test_coarse_polygons_stay_polygons():
    """A 36-gon of 10 mm sides (10 degrees a turn): lines and blends."""
    points = arc(36, radius=57.3, sweep=2 * math.pi)
    path = path_of(chords_of(points), start=points[0] * 1e-3)
    assert all(k in ('line', 'arc') for k in kinds(path))
    assert len(path.pieces) == 2 * 36 - 1


def test_fitted_curves_are_followed_by_their_arc_length():
    """|dp/dw| = 1 along a run, its chords' length its own, d2 of d1."""
    points = np.vstack([arc(30, radius=15.0, sweep=math.pi, z=0.0)])
    points[:, 2] = 5.0 * np.sin(np.linspace(0.0, 3.0, len(points)))
    path = path_of(chords_of(points), start=points[0] * 1e-3)
    piece = path.pieces[0]
    w = np.linspace(0.0, piece.length, 20001)
    p, d1, d2 = piece.evaluate(w)
    assert np.allclose(np.linalg.norm(d1, axis=1), 1.0, rtol=0, atol=1e-12)
    chords_length = np.linalg.norm(np.diff(p, axis=0), axis=1).sum()
    assert chords_length == pytest.approx(piece.length, rel=1e-8)
    assert np.allclose(np.diff(d1, axis=0),
                       0.5 * (d2[1:] + d2[:-1]) * np.diff(w)[:, None],
                       atol=1e-6 * np.abs(d2).max() * w[1])


def test_the_rules_of_a_break():
    """CORNER_ANGLE, CORNER_FLOOR with CORNER_RATIO, LONG_RATIO, feeds."""
    deg = math.radians
    turns_ = np.array([0.0, deg(2), deg(31), deg(2), deg(2), deg(6),
                       deg(2), 0.0])
    lengths = np.full(7, 1e-3)
    corner, broken = chords.breaks(turns_, lengths, np.ones(7), False, False)
    assert corner.tolist() == [False, False, True, False, False, False,
                               False, False]
    assert broken.tolist() == [True, False, True, False, False, False,
                               False, True]
    turns_[5] = deg(9)      # above 5 degrees and 4 times its neighbours'
    corner, _ = chords.breaks(turns_, lengths, np.ones(7), False, False)
    assert corner[5]
    lengths[4] = 4.5e-3     # a long move
    _, broken = chords.breaks(turns_, lengths, np.ones(7), False, False)
    assert broken[4] and broken[5]


def test_every_waypoint_within_the_tolerance_of_a_smooth_path():
    """A nav_msgs/Path's poses of a 3D curve: one curve, every pose kept."""
    t = np.linspace(0.0, 2.0 * math.pi, 300)
    points = np.stack((0.05 * np.cos(t), 0.05 * np.sin(t),
                       0.01 * np.sin(3 * t)), 1)
    points = np.round(points, 6)
    path = from_waypoints(points, None, list(range(1, 301)), TOLERANCE)
    assert kinds(path) == [299]
    assert distance_to_path(path, points).max() <= TOLERANCE


def test_the_documented_chord_program_is_the_generators():
    """doc/programs/loop.nc: the 3D loop at 1 m/s, from home."""
    from pathlib import Path
    from orthoglide_testing.chord_programs import loop_program
    text = (Path(__file__).resolve().parents[1] / 'doc' / 'programs'
            / 'loop.nc').read_text()
    assert text == loop_program(feed=60000.0, approach=True)[0]


@st.composite
def sampled_curves(draw):
    """Draw a 3D curve (sums of sines, mm) as rounded chords; a tolerance."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    count = draw(st.integers(4, 300))
    t = np.linspace(0.0, 1.0, count + 1)
    points = np.zeros((count + 1, 3))
    for _ in range(draw(st.integers(1, 4))):
        amplitude = rng.uniform(-30.0, 30.0, 3)
        points += amplitude * np.sin(rng.uniform(0.5, 12.0) * t
                                     + rng.uniform(0, 2 * math.pi))[:, None]
    if draw(st.booleans()):         # a corner somewhere
        k = int(rng.integers(1, count))
        points[k:] += rng.uniform(-5.0, 5.0, 3) * (t[k:, None] - t[k])
    decimals = draw(st.sampled_from((6, 4, 3)))
    tolerance = draw(st.sampled_from((1e-6, 1e-5, 1e-4)))
    return np.round(points, decimals), tolerance


@pytest.mark.slow     # 8-15 s of CPU, one process, 2026-12-06
@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(sampled_curves())
def test_every_point_of_random_chord_programs_is_within_the_tolerance(
        curve):
    """
    Random smooth curves with corners, rounded as CAM writes them.

    Every programmed point within the tolerance of the path, measured on
    the path; the pieces chained, tangent where G does not stop.
    """
    points, tolerance = curve
    text = chords_of(points)
    try:
        path = path_of(text, tolerance, start=points[0] * 1e-3)
    except ProgramError:          # every point within the tolerance
        return
    near = distance_to_path(path, programmed(text, points[0] * 1e-3))
    assert near.max() <= tolerance * (1 + 1e-9), near.max()
    for k in range(1, len(path.pieces)):
        before, after = path.pieces[k - 1], path.pieces[k]
        assert np.allclose(before.point(before.length), after.point(0.0),
                           rtol=0, atol=1e-12)
        if not path.stops[k]:
            assert turns(path)[k - 1] <= 1e-6
