"""
The G-code subset: what each word does, and every refusal naming its line.

Arcs are checked against the right-hand rule written here (G17, G18, G19:
counter-clockwise about the plane's normal Z, Y, X for G3), full turns,
helices, R both ways, units, incremental coordinates, feeds, comments,
the end of the program; then each refusal: ``line N: ...`` in one line.
"""

import math

import numpy as np
import pytest

from orthoglide_ros.planning.gcode import read_gcode
from orthoglide_ros.planning.moves import ProgramError
from orthoglide_ros.planning.pieces import move_piece


def midpoint(move):
    piece = move_piece(move)
    return piece.point(0.5 * piece.length)


def rotate(vector, axis, angle):
    """Rodrigues: ``vector`` turned by ``angle`` about the unit ``axis``."""
    v, k = np.asarray(vector, float), np.asarray(axis, float)
    return (v * math.cos(angle) + np.cross(k, v) * math.sin(angle)
            + k * (k @ v) * (1 - math.cos(angle)))


def test_lines_units_incremental_feed_and_comments():
    moves = read_gcode(
        '%\n(a comment) N10 G21 G90 F600 ; and another\n'
        'G1 X10 Y-5.5\nG91 Z+2.\nG20 G1 X1 F60\nM30\nG1 X1000\n')
    assert [m.line for m in moves] == [3, 4, 5]
    assert np.allclose(moves[0].end, [0.010, -0.0055, 0.0])
    assert np.allclose(moves[1].end, [0.010, -0.0055, 0.002])
    assert np.allclose(moves[2].end, [0.010 + 0.0254, -0.0055, 0.002])
    assert moves[0].feed == pytest.approx(0.6 / 60.0)
    assert moves[2].feed == pytest.approx(60 * 0.0254 / 60.0)
    rapid = read_gcode('G0 X1')[0]
    assert rapid.feed == math.inf


def test_a_move_to_where_g_is_is_dropped():
    assert read_gcode('G1 X0 F100\nG0 Y0') == []


@pytest.mark.parametrize('plane, normal', (
    (17, (0, 0, 1)), (18, (0, 1, 0)), (19, (1, 0, 0))))
def test_arcs_turn_about_the_plane_normal_by_the_right_hand_rule(
        plane, normal):
    """A quarter turn about the origin: G3 positive about the normal."""
    start = {17: (10, 0, 0), 18: (10, 0, 0), 19: (0, 10, 0)}[plane]
    start_m = np.array(start) * 1e-3
    for code, sign in (('G3', 1.0), ('G2', -1.0)):
        text = (f'G21 F600 G{plane}\nG0 X{start[0]} Y{start[1]} Z{start[2]}'
                f'\n{code} {_end(plane, start, sign)} '
                f'{_offsets(plane, start)}')
        arc = read_gcode(text)[-1]
        assert abs(arc.angle) == pytest.approx(math.pi / 2)
        expected = rotate(start_m, normal, sign * math.pi / 4)
        assert np.allclose(midpoint(arc), expected, atol=1e-12)


def _end(plane, start, sign):
    """Return the end a quarter turn away about the normal, as words."""
    normal = {17: (0, 0, 1), 18: (0, 1, 0), 19: (1, 0, 0)}[plane]
    end = rotate(start, normal, sign * math.pi / 2)
    return ' '.join(f'{a}{c:.9f}' for a, c in zip('XYZ', end))


def _offsets(plane, start):
    letters = {17: 'IJ', 18: 'IK', 19: 'JK'}[plane]
    index = {'I': 0, 'J': 1, 'K': 2}
    return ' '.join(f'{k}{-start[index[k]]}' for k in letters)


def test_a_full_turn_and_a_helix():
    moves = read_gcode('G21 F600\nG0 X10\nG2 X10 Y0 Z-6 I-10 J0 P2')
    helix = moves[-1]
    assert helix.angle == pytest.approx(-4 * math.pi)
    assert np.allclose(helix.end, [0.010, 0.0, -0.006])
    piece = move_piece(helix)
    length = math.hypot(4 * math.pi * 0.01, 0.006)
    assert piece.length == pytest.approx(length)
    assert np.allclose(piece.point(piece.length), helix.end, atol=1e-15)


def test_r_gives_the_short_arc_positive_and_the_long_one_negative():
    short = read_gcode('G21 F600\nG3 X20 Y0 R10.000001')[0]
    long = read_gcode('G21 F600\nG3 X10 Y10 R-10')[0]
    assert short.angle == pytest.approx(math.pi, abs=1e-3)
    assert long.angle == pytest.approx(1.5 * math.pi)


def test_i_j_k_centres_rounded_are_moved_onto_the_bisector():
    arc = read_gcode('G21 F600\nG3 X20 Y0.0005 I10.0005 J0')[0]
    piece = move_piece(arc)
    assert np.allclose(piece.point(piece.length), arc.end, atol=1e-15)


def test_path_control_modes():
    moves = read_gcode('G21 F600 G61.1\nG1 X1\nG64 P0.02\nG1 X2\nG64\n'
                       'G1 X3\nG61\nG1 X4')
    assert [m.mode for m in moves] == ['exact_stop', 'blend', 'blend',
                                       'exact_path']
    assert moves[1].tolerance == pytest.approx(2e-5)
    assert moves[2].tolerance is None


def test_units_apply_before_the_blend_tolerance_on_their_line():
    """RS274NGC's order of execution: G20 before G64, however written."""
    for text in ('G64 P0.001 G20 F10\nG1 X1', 'G20 G64 P0.001 F10\nG1 X1'):
        assert read_gcode(text)[0].tolerance == pytest.approx(2.54e-5)


@pytest.mark.parametrize('program, message', (
    ('G21\nG1 X1 F100\n\n\n\n\nG41 D1\n',
     'line 7: G41 (cutter compensation) is not supported'),
    ('G43 H1', 'line 1: G43 (tool length offset) is not supported'),
    ('G54', 'line 1: G54 (work offsets) is not supported'),
    ('G81 X1 Y1 Z-1 R1', 'line 1: G81 (canned cycles) is not supported'),
    ('G90.1', 'line 1: G90.1 (absolute arc centres) is not supported'),
    ('M3 S1000', 'line 1: M3 (spindle) is not supported'),
    ('S1000', 'line 1: S1000 (spindle speed) is not supported'),
    ('T1 M6', 'line 1: T1 (tool) is not supported'),
    ('#1=2', 'line 1: # (parameters) is not supported'),
    ('G1 X1..2 F1', 'line 1: malformed number X1..2'),
    ('G1 X- F1', 'line 1: malformed number X-'),
    ('G1 X', 'line 1: malformed number X'),
    ('G1 X1 X2 F1', 'line 1: two X words on one line'),
    ('G0 G1 X1', 'line 1: G0 and G1 on one line: two motion codes'),
    ('(open comment', 'line 1: comment not closed'),
    ('X1', 'line 1: a move without a motion mode'),
    ('G1 X1', 'line 1: G1 without a feed rate (F)'),
    ('F0\nG1 X1', 'line 2: G1 at feed rate zero (F0 on line 1)'),
    ('G1 X1 I1 F1', 'line 1: I only with G2, G3, G5 or G5.1'),
    ('G17 G2 X1 K1 F1', 'line 1: K is not an arc word of the G17 plane'),
    ('G2 X1 R1 I1 F1', 'line 1: an arc with both R and I J K'),
    ('G2 X1 F1', 'line 1: G2 needs I J K offsets or R'),
    ('G21 G2 X30 Y0 R10 F1', 'line 1: the arc radius 10 mm does not fit '
     'its chord of 30 mm'),
    ('G21 G2 X20 Y0 I5 J0 F1', 'line 1: the arc\'s end is 15 mm from its '
     'centre, its start 5 mm'),
    ('G2 X0 Y0 R5 F1', 'line 1: a full turn needs I J K, not R'),
    ('G2 X1 I1 P1.5 F1', 'line 1: P1.5: the turns of an arc'),
    ('/G1 X1 F1', 'line 1: / (block delete) is not supported'),
    ('G1 X1 F1\nG1 Y' + '0' * 2000, 'line 2: longer than 1024 characters'),
))
def test_refusals_name_their_line(program, message):
    with pytest.raises(ProgramError) as error:
        read_gcode(program)
    assert str(error.value).startswith(message), str(error.value)


@pytest.mark.parametrize('program, message', (
    # A form feed, a vertical tab, U+0085, U+2028 and U+2029 end no line.
    ('G21\f\nF100\x0b\nG1 X1 (\x85 \u2028 \u2029)\nG41',
     'line 4: G41 (cutter compensation)'),
    ('G21\rG1 X1 F1\r\nG41\n', 'line 3: G41 (cutter compensation)'),
))
def test_lines_are_counted_as_an_editor_counts_them(program, message):
    with pytest.raises(ProgramError) as error:
        read_gcode(program)
    assert str(error.value).startswith(message), str(error.value)


@pytest.mark.parametrize('program, message', (
    ('G1 F600 X1e308', 'line 1: X1e308: a number with an exponent'),
    ('o100 sub', 'line 1: O100 (subroutines) is not supported'),
    ('G1 F600 X' + '9' * 159, 'the largest magnitude a number may have'),
    ('G1 F' + '1' * 400 + ' X1', 'the largest magnitude a number may have'),
    ('G64 P' + '1' * 400, 'the largest magnitude a number may have'),
    ('G1 F600 X1000000001', 'X1000000001: beyond 1,000,000,000'),
    ('G1 F600 X\u0661\u0662', 'malformed number X\u0661: a number is the '
     'digits 0-9'),
    ('G1 F600 X\uff11\uff12', 'malformed number X\uff11'),
    ('G1 F600 X1\u0662', 'malformed number X1\u0662'),
    ('G2 X20 Iinf J0 F1', 'malformed number I'),
))
def test_every_number_follows_one_rule(program, message):
    """ASCII digits, at most one point, no exponent, at most 1e9."""
    with pytest.raises(ProgramError) as error:
        read_gcode(program)
    assert message in str(error.value), str(error.value)
    assert len(str(error.value)) < 200


@pytest.mark.parametrize('program, words', (
    # 10 mm off a 1 km circle: 0.001 % of the radius, 10 mm of it.
    ('G21 F600\nG0 X10\nG2 X20 I1000000 J0', 'line 3: the arc\'s end is '
     '999990 mm from its centre, its start 1e+06 mm'),
    ('G21 F600\nG0 X10\nG2 X20 I1000000000000000000 J0',
     'line 3: I1000000000000000000: beyond 1,000,000,000'),
    # 0.005 mm off a 100 mm radius: within 0.1 %, not within 0.002 mm.
    ('G21 F600\nG3 X200.005 I100 J0', 'line 2: the arc\'s end is 100.005 '
     'mm from its centre, its start 100 mm'),
    # 0.001 mm from a 5 mm radius, but the centre would move 5 mm.
    ('G21 F600\nG0 X10\nG2 X10.001 I-5 J0', 'line 3: the arc\'s end is off '
     'its circle: its centre moved onto the chord\'s bisector (5.0005 mm) '
     'would move the arc by 10.001 mm'),
))
def test_an_arc_whose_end_is_off_its_circle_is_refused(program, words):
    """
    Both tolerances hold, and the centre moves the arc by rounding at most.

    LinuxCNC's rule: an absolute and a relative tolerance, both kept.
    """
    with pytest.raises(ProgramError) as error:
        read_gcode(program)
    assert str(error.value).startswith(words), str(error.value)


def test_a_centre_rounded_moves_the_arc_by_rounding_only():
    """A quarter turn whose end is 1 um off: the arc moves by < 2 um."""
    arc = read_gcode('G21 F600\nG3 X10 Y10.001 I0 J10')[0]
    piece = move_piece(arc)
    centre = np.array([0.0, 0.010, 0.0])
    points = piece.evaluate(np.linspace(0.0, piece.length, 1001))[0]
    moved = np.abs(np.linalg.norm(points - centre, axis=1) - 0.010)
    assert moved.max() <= 2e-6
    assert np.allclose(piece.point(piece.length), arc.end, atol=1e-12)


def bernstein(control, tau, order=0):
    """Return a cubic Bezier (or its derivative) at ``tau``, written out."""
    t = np.asarray(tau, dtype=float)[:, None]
    p = np.asarray(control)
    if order == 1:
        return 3 * ((1 - t) ** 2 * (p[1] - p[0]) + 2 * (1 - t) * t
                    * (p[2] - p[1]) + t ** 2 * (p[3] - p[2]))
    if order == 2:
        return 6 * ((1 - t) * (p[2] - 2 * p[1] + p[0])
                    + t * (p[3] - 2 * p[2] + p[1]))
    return ((1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1]
            + 3 * (1 - t) * t ** 2 * p[2] + t ** 3 * p[3])


def on_curve(piece, control):
    """
    Return the largest distance (m) of the piece's points to the curve.

    Each point's nearest ``tau`` by Newton's method on ``(B - p) . B'``
    from the nearest of 2001 samples.
    """
    points = piece.evaluate(np.linspace(0.0, piece.length, 41))[0]
    dense = bernstein(control, np.linspace(0.0, 1.0, 2001))
    tau = np.linalg.norm(dense[None] - points[:, None], axis=2).argmin(1) \
        / 2000.0
    for _ in range(30):
        offset = bernstein(control, tau) - points
        d1, d2 = bernstein(control, tau, 1), bernstein(control, tau, 2)
        tau = np.clip(tau - (offset * d1).sum(1) / (
            (d1 * d1).sum(1) + (offset * d2).sum(1)), 0.0, 1.0)
    return float(np.linalg.norm(bernstein(control, tau) - points,
                                axis=1).max())


def test_g5_is_linuxcncs_cubic_and_a_series_is_tangent():
    """
    The curvy N of LinuxCNC's manual: ``G5 I0 J3 P0 Q-3 X1 Y1``, then more.

    ``G5 P0 Q-3 X2 Y2`` after it.

    The first's control points are the start plus I J and the end plus P
    Q; the second, without I J, starts along the first's end (its handle
    the negation of P Q). Followed exactly, by its arc length.
    """
    moves = read_gcode('G21 G90 G17 F600\nG0 X0 Y0\n'
                       'G5 I0 J3 P0 Q-3 X1 Y1\nG5 P0 Q-3 X2 Y2')
    first, second = (m for m in moves if m.kind == 'spline')
    mm = 1e-3
    assert np.allclose(first.control, np.array(
        [(0, 0, 0), (0, 3, 0), (1, -2, 0), (1, 1, 0)]) * mm, atol=1e-15)
    assert np.allclose(second.control, np.array(
        [(1, 1, 0), (1, 4, 0), (2, -1, 0), (2, 2, 0)]) * mm, atol=1e-15)
    for move in (first, second):
        piece = move_piece(move)
        assert on_curve(piece, move.control) <= 1e-12
        assert np.allclose(piece.point(piece.length), move.end, atol=1e-15)
        dense = bernstein(move.control, np.linspace(0.0, 1.0, 200001))
        length = np.linalg.norm(np.diff(dense, axis=0), axis=1).sum()
        assert piece.length == pytest.approx(length, rel=1e-9)
    a, b = move_piece(first), move_piece(second)
    assert np.linalg.norm(np.cross(a.tangent(a.length), b.tangent(0.0))) \
        <= 1e-12


def test_g5_1_is_the_quadratic_through_its_control_point():
    """The parabola of LinuxCNC's manual: ``G5.1 X2 I2 J-8`` is y = x^2."""
    move = read_gcode('G21 G90 G17 F600\nG0 X-2 Y4\nG5.1 X2 I2 J-8')[-1]
    piece = move_piece(move)
    p = piece.evaluate(np.linspace(0.0, piece.length, 1001))[0] * 1e3
    assert np.abs(p[:, 1] - p[:, 0] ** 2).max() <= 1e-9
    assert np.allclose(p[[0, -1], :2], [(-2, 4), (2, 4)], atol=1e-12)
    # One of I J may be left out (0): only both zero is refused.
    assert read_gcode('G21 F600\nG5.1 X2 J1')[0].kind == 'spline'


@pytest.mark.parametrize('program, message', (
    ('G21 F600 G18\nG5 I1 J1 P1 Q1 X2', 'line 2: G5 only in the XY plane '
     '(G17), not G18'),
    ('G21 F600\nG5 I1 J1 P1 X2', 'line 2: G5 needs both P and Q'),
    ('G21 F600\nG5 I1 P1 Q1 X2', 'line 2: G5 needs both I and J, or neither'),
    ('G21 F600\nG5 P1 Q1 X2', 'line 2: the first G5 of a series needs I and '
     'J'),
    ('G21 F600\nG5 I0 J1 P0 Q1 X2\nG1 X3\nG5 P1 Q1 X4',
     'line 4: the first G5 of a series needs I and J'),
    ('G21 F600\nG5.1 X2', 'line 2: G5.1 needs I or J, not zero'),
    ('G21 F600\nG5.1 X2 I0 J0', 'line 2: G5.1 needs I or J, not zero'),
    ('G21 F600\nG5.1 X2 I1 P1', 'line 2: P is not a word of G5.1 (I J)'),
    ('G21 F600\nG5 I1 J1 P1 Q1 X2 Z1', 'line 2: G5 moves X and Y only'),
    ('G21 F600\nG5 I1 J1 K1 P1 Q1 X2', 'line 2: K is not a word of G5'),
    ('G21 F600\nG1 X2 Q1', 'line 2: Q only with G5'),
    ('G21 F600\nG5 I0 J0 P1 Q1 X2', 'line 2: the G5 spline stops where its '
     'speed vanishes'),
    ('G21 F600\nG64 P0.01 G5 I1 J1 Q1 X2', 'line 2: G64 P and G5 on one '
     'line'),
    ('G21\nG5 I1 J1 P1 Q1 X2', 'line 2: G5 without a feed rate (F)'),
    ('G5.2 X1 Y1', 'line 1: G5.2 (NURBS blocks) is not supported'),
))
def test_spline_refusals_name_their_line(program, message):
    with pytest.raises(ProgramError) as error:
        read_gcode(program)
    assert str(error.value).startswith(message), str(error.value)
