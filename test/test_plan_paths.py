"""
Paths: every junction decided, every blend within its tolerance.

A tangent junction is passed, a corner stops (G61) or is blended within
G64's P (distance to the programmed path, measured on dense points), an
exact stop (G61.1) stops everywhere, a kink of CAM rounding is smoothed
within a micrometre, an about-turn stops; a circle given as a dense
polyline becomes a circle again; pieces join end to end, tangent where
nothing stops.
"""

import math

import numpy as np
from planning_checks import path_distance
import pytest

from orthoglide_ros.planning import gcode
from orthoglide_ros.planning.path import from_moves, from_waypoints

SQUARE = 'G21 F600 {mode}\nG1 X40\nG1 Y40\nG1 X0\nG1 Y0'
TANGENT = 'G21 F600 G61\nG1 X40\nG3 X60 Y20 I0 J20\nG1 Y40'


def path_of(text, tolerance=1e-5):
    return from_moves(gcode.read_gcode(text), tolerance)


def dense_programmed(text):
    """Return the programmed moves as dense points (no blend)."""
    points = []
    for move in gcode.read_gcode(text):
        piece = from_moves([move], 0.0).pieces[0]
        w = np.linspace(0.0, piece.length, 20001)
        points.append(piece.evaluate(w)[0])
    return np.vstack(points)


def dense(path):
    out = []
    for k, piece in enumerate(path.pieces):
        w = np.linspace(0.0, piece.length, 2001)
        out.append(path.evaluate(np.full(len(w), k), w)[0])
    return np.vstack(out)


def assert_chained(path):
    """Each piece starts where the one before ends; tangent unless a stop."""
    for k in range(1, len(path.pieces)):
        before, after = path.pieces[k - 1], path.pieces[k]
        assert np.allclose(before.point(before.length), after.point(0.0),
                           atol=1e-12)
        if not path.stops[k]:
            turn = math.acos(min(1.0, before.tangent(before.length)
                                 @ after.tangent(0.0)))
            assert turn <= 1e-6


def test_a_tangent_junction_is_passed_a_corner_stops():
    path = path_of(TANGENT)
    assert list(path.stops) == [True, False, False, True]
    assert_chained(path)
    square = path_of(SQUARE.format(mode='G61'))
    assert square.stops.all()
    assert len(square.pieces) == 4


def test_exact_stop_stops_at_every_junction():
    assert path_of(TANGENT.replace('G61', 'G61.1')).stops.all()


@pytest.mark.parametrize('tolerance', (0.01, 0.1, 1.0))
def test_blends_stay_within_their_tolerance(tolerance):
    text = SQUARE.format(mode=f'G64 P{tolerance}')
    path = path_of(text)
    assert not path.stops[1:-1].any()
    assert_chained(path)
    distance = path_distance(dense(path), dense_programmed(text))
    assert distance.max() <= tolerance * 1e-3 * 1.001
    assert distance.max() >= tolerance * 1e-3 * 0.9     # not needlessly tight


def test_blends_between_arcs_stay_within_their_tolerance():
    text = 'G21 F600 G64 P0.05\nG2 X20 Y0 I10 J0\nG3 X20 Y20 I10 J10\nG1 X0'
    path = path_of(text)
    assert not path.stops[1:-1].any()
    assert_chained(path)
    assert path_distance(dense(path), dense_programmed(text)).max() \
        <= 0.05e-3 * 1.001


def test_g64_without_p_blends_within_the_planner_tolerance():
    text = SQUARE.format(mode='G64')
    path = path_of(text, tolerance=2e-5)
    distance = path_distance(dense(path), dense_programmed(text)).max()
    assert 1.8e-5 <= distance <= 2e-5 * 1.001


def test_a_kink_of_rounding_is_smoothed_within_a_micrometre():
    text = 'G21 F600 G61\nG1 X40\nG1 X80 Y0.02'   # 0.5 mrad
    path = path_of(text)
    assert not path.stops[1:-1].any()
    assert path_distance(dense(path), dense_programmed(text)).max() <= 1e-6


def test_an_about_turn_stops_even_when_blending():
    path = path_of('G21 F600 G64 P1\nG1 X40\nG1 X0')
    assert path.stops.all()


def test_a_circle_as_a_dense_polyline_becomes_the_circle():
    radius = 0.1
    angles = np.linspace(0.0, 2 * math.pi, 400)
    points = radius * np.stack((np.cos(angles), np.sin(angles),
                                np.zeros_like(angles)), 1)
    path = from_waypoints(points, None, list(range(1, 401)), 1e-5)
    assert_chained(path)
    assert not path.stops[1:-1].any()
    # Half a segment of line at each end (where G rests), arcs between.
    radii = [piece.radius for piece in path.pieces]
    assert radii[0] == radii[-1] == 0.0
    assert np.allclose(radii[1:-1], radius * math.cos(math.pi / 399),
                       rtol=1e-9)
    circle = np.linalg.norm(dense(path)[:, :2], axis=1)
    assert np.abs(circle - radius).max() <= radius * (1 - math.cos(
        math.pi / 399)) * 1.001


def test_a_polyline_with_a_tight_tolerance_keeps_its_lines():
    points = np.array([[0, 0, 0], [0.05, 0, 0], [0.05, 0.05, 0.0]])
    path = from_waypoints(points, None, [1, 2, 3], 1e-6)
    assert [p.radius == 0.0 for p in path.pieces] == [True, False, True]
    assert path_distance(dense(path), points).max() <= 1e-6 * 1.001
