"""
Corner blends: the fastest curve within a tolerance of the path, proven.

A corner between two pieces of the path (``first`` ends where ``second``
starts, their tangents apart) is replaced by a curve tangent to both,
trimming each by at most ``room``:

- between two lines, the circular arc tangent to both (:func:`line_blend`,
  the fastest curve within the distance): its distance to the lines,
  largest at its middle, is ``trim tan(turn / 4) cos(turn / 2)``, and its
  vertex's, ``trim tan(turn / 4)``;
- between any other pair (arcs, helices, splines, fitted runs), a cubic
  Bezier (:func:`curve_blend`) whose distance to the path beside the
  corner is proven, not sampled (:func:`proven_within`).

``vertex`` (m, or None): how near the blend must pass to the corner's
point, where the corner is a programmed point the path must keep
(plain G64, waypoints: within the tolerance less the slack of points
merged there); G64 P bounds only the distance to the path.

The pieces (:mod:`pieces`) are read through their ``point``, ``tangent``,
``evaluate``, ``sub`` (a part of the piece) and their fields ``length``,
and a helix's ``radius`` and ``angle``, a Bezier's ``control``; what this
module returns, the path makes pieces of.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier
from orthoglide_ros.planning.pieces import BezierPiece, HelixPiece, Piece

# A turn nearer than this to an about-turn (rad) is not blended: G stops.
ABOUT_TURN = 1e-6
# A trim shorter than this (m) blends nothing.
SHORTEST_TRIM = 1e-9
# A Bezier blend whose ends are nearer than this (m; a hairpin's, near an
# about-turn) would have its tangents set by the rounding of its control
# points (1e-6 rad at 3e-12 m): not made, G stops.
SHORTEST_CHORD = 1e-9
# The proof that a Bezier blend is within its tolerance: the programmed
# path as at most PROOF_SEGMENTS chords a piece, the curve split in halves
# at most PROOF_DEPTH times into at most PROOF_CURVES parts.
PROOF_SEGMENTS = 64
PROOF_DEPTH = 16
PROOF_CURVES = 64
# A Bezier's trim is first found on its points at these parameters, then
# shortened by 2 % until proven, at most PROOF_TRIES times.
_SAMPLES = np.linspace(0.0, 1.0, 33)
PROOF_TRIES = 12


def line_blend(first: HelixPiece, second: HelixPiece, tolerance: float,
               turn: float, room: float, vertex: Optional[float] = None
               ) -> Optional[tuple[Array, Array, Array, float, float]]:
    """
    Return the circular arc tangent to two lines, within ``tolerance``.

    Returns ``(origin, e1, e3, radius, trim)`` of the arc (a helix piece
    from ``origin``, turning ``turn`` about ``e3``), or None where its trim
    would be shorter than SHORTEST_TRIM. Its frame from the first line's
    direction ``t1`` and the second's component across it, so that the arc
    leaves along ``t1`` and arrives along ``t2`` to rounding however small
    the turn.
    """
    t1, t2 = first.e3, second.e3
    quarter = math.tan(0.25 * turn)
    trim = min(room, tolerance / (quarter * math.cos(0.5 * turn)))
    if vertex is not None:
        trim = min(trim, vertex / quarter)
    if trim <= SHORTEST_TRIM:
        return None
    corner = first.point(first.length)
    radius = trim / math.tan(0.5 * turn)
    inward = t2 - t1 * float(t1 @ t2)
    inward = _unit(inward - t1 * float(t1 @ inward))
    e1 = -inward
    return corner - trim * t1, e1, np.cross(e1, t1), radius, trim


def curve_blend(first: Piece, second: Piece, tolerance: float, turn: float,
                room: float, vertex: Optional[float] = None
                ) -> Optional[tuple[Array, float]]:
    """
    Return ``(control, trim)``: a Bezier blend proven within ``tolerance``.

    ``control`` (4, 3); None where none is found. The trim: the largest
    (to 0.1 %, by bisection, at most ``room``) whose points at 33
    parameters are within ``tolerance`` of the path (and one of them
    within ``vertex`` of the corner), then shortened by 2 % at a time
    until the whole curve is proven within it (:func:`proven_within`).
    The vertex's distance needs no more: a point of the curve within it is
    the proof.
    """
    corner = first.point(first.length)

    def near_vertex(points):
        return vertex is None or float(np.linalg.norm(
            points - corner, axis=1).min()) <= vertex

    def sampled(trim):
        control = bezier_control(first, second, trim)
        if control is None:
            return False
        points = bezier.evaluate(control, _SAMPLES)[0]
        return near_vertex(points) and _near(
            points, *path_chords(first, second, trim, tolerance), tolerance)
    low, high = (room, room) if sampled(room) else (0.0, room)
    for _ in range(40):
        if high - low <= 1e-3 * high:
            break
        trim = 0.5 * (low + high)
        low, high = (trim, high) if sampled(trim) else (low, trim)
    trim = low
    for _ in range(PROOF_TRIES):
        control = bezier_control(first, second, trim)
        if control is None:
            return None
        if near_vertex(bezier.evaluate(control, _SAMPLES)[0]) and \
                proven_within(control, *path_chords(first, second, trim,
                                                    tolerance), tolerance):
            return control, trim
        trim *= 0.98
    return None


def bezier_control(first: Piece, second: Piece, trim: float
                   ) -> Optional[Array]:
    """
    Return the control points (4, 3) of the Bezier replacing the corner.

    From ``trim`` before the corner to ``trim`` after it, tangent to both
    pieces; None where it cannot be followed by its arc length (its
    hodograph's control points not on one side of a plane, where ``|B'|``
    might vanish), turns about, or would be shorter than SHORTEST_CHORD.
    """
    if trim <= SHORTEST_TRIM:
        return None
    a = first.point(first.length - trim)
    b = second.point(trim)
    ta = first.tangent(first.length - trim)
    tb = second.tangent(trim)
    chord = float(np.linalg.norm(b - a))
    turn = _turn(ta, tb)
    if chord <= SHORTEST_CHORD or turn >= math.pi - ABOUT_TURN:
        return None
    # Arms of the Bezier nearest a circular arc of that turn.
    arm = (2.0 / 3.0) * chord * (math.tan(0.25 * turn) / math.sin(0.5 * turn)
                                 if turn > 1e-8 else 0.5)
    control = np.array([a, a + arm * ta, b - arm * tb, b])
    if (np.diff(control, axis=0) @ _unit(ta + tb)).min() <= 1e-9 * chord:
        return None
    return control


def path_chords(first: Piece, second: Piece, trim: float, tolerance: float
                ) -> tuple[Array, Array, Array]:
    """
    Return the path beside a corner as chords, and their slack.

    The last ``trim`` of ``first`` and the first of ``second`` as segments
    ``(a, b)`` ((k, 3) each), each within ``slack`` (k,) of its part of
    the path, at most a hundredth of ``tolerance`` unless PROOF_SEGMENTS
    do not reach: of a helix, ``radius dphi^2 / 8`` (the error of linear
    interpolation); of a Bezier, the bound of its control points
    (:func:`bezier.bulge`), its parts halved until it holds.
    """
    starts, ends, slack = [], [], []
    for piece, low in ((first, first.length - trim), (second, 0.0)):
        if isinstance(piece, BezierPiece):
            curves = piece.sub(low, low + trim).control
            while 2 * len(curves) <= PROOF_SEGMENTS and (
                    bezier.bulge(curves) > 0.01 * tolerance).any():
                curves = bezier.halves(curves)
            starts.append(curves[:, 0])
            ends.append(curves[:, 3])
            slack.append(bezier.bulge(curves))
            continue
        sweep = abs(piece.angle) * trim / piece.length
        count = 1 if piece.radius == 0.0 else min(PROOF_SEGMENTS, max(
            1, math.ceil(sweep * math.sqrt(piece.radius
                                           / (0.08 * tolerance)))))
        points = piece.evaluate(np.linspace(low, low + trim, count + 1))[0]
        starts.append(points[:-1])
        ends.append(points[1:])
        slack.append(np.full(count, piece.radius * (sweep / count) ** 2 / 8))
    return (np.concatenate(starts), np.concatenate(ends),
            np.concatenate(slack))


def _near(points, a, b, slack, tolerance):
    """Whether no point of the curve is surely beyond ``tolerance``."""
    return not ((bezier.segment_distances(points, a, b) - slack).min(1)
                > tolerance).any()


def proven_within(control: Array, a: Array, b: Array, slack: Array,
                  tolerance: float) -> bool:
    """
    Whether the Bezier ``control`` is proven within ``tolerance`` of the path.

    The path as chords ``(a, b)`` (:func:`path_chords`): the distance of
    any point ``q`` to the path is at most ``dist(q, chord) + slack``. The
    distance to a segment is convex, so over a part of the curve, which
    lies in the convex hull of its control points, it is largest at one of
    them: ``max_i dist(Q_i, chord) + slack`` of the best chord bounds the
    whole part. The curve is halved (de Casteljau) until every part's
    bound is within ``tolerance``; not proven (False) where a point of the
    curve is beyond it, or after PROOF_DEPTH halvings or with more than
    PROOF_CURVES parts.
    """
    curves = control[None]
    for _ in range(PROOF_DEPTH):
        distance = bezier.segment_distances(
            curves.reshape(-1, 3), a, b).reshape(len(curves), 4, -1)
        # The first control point of each part is on the curve.
        if ((distance[:, 0] - slack).min(1) > tolerance).any():
            return False
        curves = curves[(distance.max(1) + slack).min(1) > tolerance]
        if len(curves) == 0:
            return True
        if 2 * len(curves) > PROOF_CURVES:
            return False
        curves = bezier.halves(curves)
    return False


def _turn(t1, t2):
    """Angle (rad) between unit vectors: atan2, exact near 0 and pi."""
    return math.atan2(float(np.linalg.norm(np.cross(t1, t2))),
                      float(t1 @ t2))


def _unit(vector):
    return vector / math.sqrt(float(vector @ vector))
