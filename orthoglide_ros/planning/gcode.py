r"""
The G-code subset a CAM post-processor for a 3-axis mill emits, read into moves.

:func:`read_gcode` turns the text of a program into moves (:mod:`moves`:
straight lines, exact arcs and helices, splines), each with the line of
the file it came from (counted from 1), its feed and the path control
mode of its end. Nothing is linearised: an arc stays its centre, plane
and angle.

The subset (doc/planning.md has the table):

- motion: ``G0`` (no feed cap), ``G1``, ``G2``/``G3`` (clockwise and
  counter-clockwise seen from the plane's positive normal, ``I J K``
  offsets from the start, incremental as G91.1, or ``R``: positive for the
  arc of at most half a turn, negative for the longer one), helical when
  the third axis moves, a full turn when the end's in-plane coordinates
  are the start's, ``P`` whole turns;
- ``G17``/``G18``/``G19`` planes XY, ZX, YZ; ``G20``/``G21`` inches and
  millimetres (the default); ``G90``/``G91`` absolute (the default) and
  incremental coordinates; ``G94`` feed per minute (the only one);
- ``G61`` exact path (the default): stops only at a corner, a tangent
  junction is passed at speed; ``G61.1`` exact stop at every move's end;
  ``G64 P<p>`` corners blended within ``p`` (program units), ``G64``
  without ``P`` within the planner's tolerance;
- ``G40``, ``G49``, ``G80``, ``G91.1``: the states above, accepted as
  no-ops (a post-processor's safety line);
- ``F`` feed (units per minute, in the units of the move), ``N`` line
  numbers, comments ``( )`` and ``;``, ``%`` delimiter lines,
  ``M2``/``M30`` (the end: what follows is not read).

Anything else is refused with :class:`ProgramError` naming the line:
``line 7: G41 (cutter compensation) is not supported``. Lines are ended by
``\n``, ``\r\n`` or ``\r`` only, as an editor counts them. Every number
follows one rule (:func:`gcode_words.read_number`): ASCII digits with
at most one point and a sign, no exponent, at most NUMBER_BOUND in
magnitude. Coordinates are those of G in the base frame, origin at home;
the moves hold them in m, feeds in m/s. :mod:`gcode_words` reads a line
into its words; this module does what they say.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier
from orthoglide_ros.planning.gcode_words import (lines_of, read_words,
                                                 sort_words)
from orthoglide_ros.planning.moves import (Arc, BLEND, EXACT_PATH, EXACT_STOP,
                                           Line, Move, ProgramError, Spline,
                                           ZERO_LENGTH)

MM = 1e-3                   # m per program unit, G21
INCH = 25.4e-3              # m per program unit, G20
# Longest line read (characters): RS274NGC's is 255; comments may run on.
MAX_LINE = 1024
# Most moves in one program.
MAX_MOVES = 200_000
# An I J K arc is refused where its end's distance to the centre differs
# from its start's by more than ARC_RADIUS_TOLERANCE (m) or by more than
# ARC_RADIUS_SHARE of the radius: both must hold (LinuxCNC's rule, its
# relative tolerance; its absolute one is 0.028 mm). Within them the
# centre moves onto the chord's bisector only as far as moves no point of
# the arc by more than ARC_RADIUS_TOLERANCE.
ARC_RADIUS_TOLERANCE = 2e-6
ARC_RADIUS_SHARE = 1e-3
# In-plane distance (m) below which an arc's end is its start: a full turn.
FULL_TURN_TOLERANCE = 1e-9
# A spline whose least speed is below this share of its largest stops (a
# zero offset, a cusp): refused.
SPLINE_REGULAR = 1e-9

# Planes: the in-plane axes (e1, e2) and the normal e3 = e1 x e2 (indices
# of x, y, z), and the offset letters of e1, e2.
PLANES = {17: ((0, 1, 2), 'IJ'), 18: ((2, 0, 1), 'KI'), 19: ((1, 2, 0), 'JK')}

MOTION = {0, 1, 2, 3, 5, 5.1}


@dataclass
class _State:
    """The interpreter's modal state."""

    position: Array                     # m
    scale: float = MM                   # m per program unit
    absolute: bool = True
    plane: int = 17
    motion: Optional[float] = None      # 0, 1, 2, 3, 5, 5.1
    feed: Optional[float] = None        # program units per minute
    feed_line: int = 0
    mode: str = EXACT_PATH
    tolerance: Optional[float] = None   # m
    # The end's handle of the G5 before (m, in XY), None after any other.
    handle: Optional[Array] = None


def read_gcode(text: str,
               start: Sequence[float] = (0.0, 0.0, 0.0)) -> list[Move]:
    r"""
    Return the moves of the G-code program ``text``, from ``start`` (m).

    Raises :class:`ProgramError` naming the first line it refuses. Moves
    that move nothing are dropped; a program with none left is the
    caller's to refuse.

    >>> moves = read_gcode('G21 G90 F600\nG1 X10\nG2 X20 Y0 I5 J0\nM30')
    >>> [(m.kind, m.line, round(m.feed, 4)) for m in moves]
    [('line', 2, 0.01), ('arc', 3, 0.01)]
    """
    state = _State(np.array(start, dtype=float))
    moves: list[Move] = []
    for number, raw in enumerate(lines_of(text), 1):
        if len(raw) > MAX_LINE:
            raise ProgramError(number, f'longer than {MAX_LINE} characters')
        words = read_words(number, raw)
        if words is None:
            continue
        if _execute(number, words, state, moves):
            break
        if len(moves) > MAX_MOVES:
            raise ProgramError(number, f'more than {MAX_MOVES} moves')
    return moves


def _execute(number, words, state, moves):
    """Apply one line to ``state``, append its move; True at M2/M30."""
    g_codes, values, end = sort_words(number, words)
    p_word = values.pop('P', None)
    if 'F' in values:
        feed = values.pop('F')
        if feed < 0.0:
            raise ProgramError(number, f'negative feed rate F{feed:g}')
        state.feed, state.feed_line = feed, number
    values.pop('N', None)
    motion = None
    blend_p = False
    # Units first, as RS274NGC orders a line's execution: G64 P on the
    # line of a G20 is in inches.
    for code in sorted(g_codes, key=lambda code: code not in (20, 21)):
        if code in (20, 21):
            state.scale = INCH if code == 20 else MM
        elif code in (17, 18, 19):
            state.plane = int(code)
        elif code in (90, 91):
            state.absolute = code == 90
        elif code == 61:
            state.mode, state.tolerance = EXACT_PATH, None
        elif code == 61.1:
            state.mode, state.tolerance = EXACT_STOP, None
        elif code == 64:
            state.mode = BLEND
            state.tolerance = None if p_word is None else _tolerance(
                number, p_word, state.scale)
            blend_p, p_word = p_word is not None, None
        elif code in MOTION:
            motion = code
    if motion is not None:
        state.motion = motion
    axes = {k: values.pop(k) for k in 'XYZ' if k in values}
    arc_words = {k: values.pop(k) for k in 'IJKRQ' if k in values}
    if not axes and not arc_words and motion is None:
        if p_word is not None:
            raise ProgramError(number, 'P without G64 or an arc')
        return end
    if state.motion is None:
        raise ProgramError(number, 'a move without a motion mode (G0, G1, '
                           'G2, G3, G5 or G5.1)')
    if 'Q' in arc_words and state.motion != 5:
        raise ProgramError(number, 'Q only with G5')
    target = state.position.copy()
    for axis, value in axes.items():
        k = 'XYZ'.index(axis)
        target[k] = value * state.scale + (0.0 if state.absolute
                                           else state.position[k])
    if state.motion in (0, 1):
        if arc_words:
            raise ProgramError(number, ', '.join(arc_words)
                               + ' only with G2, G3, G5 or G5.1')
        if p_word is not None:
            raise ProgramError(number, 'P without G64 or an arc')
        move = _line(number, state, target)
    elif state.motion in (2, 3):
        move = _arc(number, state, target, arc_words, p_word)
    else:
        if blend_p:
            raise ProgramError(number, f'G64 P and {_code(state.motion)} '
                               'on one line: whose is P?')
        move = _spline(number, state, target, axes, arc_words, p_word)
    if state.motion != 5:
        state.handle = None
    if move is not None:
        moves.append(move)
        state.position = move.end
    return end


def _code(motion):
    """Return a motion code as written: G1, G5.1."""
    return f'G{motion:g}'


def _tolerance(number, value, scale):
    if value < 0.0:
        raise ProgramError(number, f'negative blending tolerance P{value:g}')
    return value * scale


def _feed(number, state, rapid):
    """Return the move's feed cap (m/s): inf for G0."""
    if rapid:
        return math.inf
    if state.feed is None:
        raise ProgramError(number, f'{_code(state.motion)} without a feed '
                           'rate (F)')
    if state.feed <= 0.0:
        raise ProgramError(number, f'{_code(state.motion)} at feed rate '
                           f'zero (F0 on line {state.feed_line})')
    return state.feed * state.scale / 60.0


def _line(number, state, target):
    if np.linalg.norm(target - state.position) <= ZERO_LENGTH:
        return None
    feed = _feed(number, state, state.motion == 0)
    return Line(state.position.copy(), target, number, feed, state.mode,
                state.tolerance)


def _arc(number, state, target, words, turns):
    """Return the arc (G2, G3) from the state's position to ``target``."""
    feed = _feed(number, state, False)
    (i1, i2, i3), letters = PLANES[state.plane]
    allowed = set(letters) | {'R'}
    wrong = [k for k in words if k not in allowed]
    if wrong:
        raise ProgramError(number, f'{wrong[0]} is not an arc word of the '
                           f'G{state.plane} plane ({", ".join(sorted(allowed))})')
    if 'R' in words and len(words) > 1:
        raise ProgramError(number, 'an arc with both R and I J K')
    if not words:
        raise ProgramError(number, f'{_code(state.motion)} needs I J K '
                           'offsets or R')
    if turns is not None and (turns < 1.0 or turns != int(turns)):
        raise ProgramError(number, f'P{turns:g}: the turns of an arc must be '
                           'a whole number of at least 1')
    start = state.position
    a = np.array([start[i1], start[i2]])
    b = np.array([target[i1], target[i2]])
    ccw = state.motion == 3
    shift = 0.0
    if 'R' in words:
        centre = _centre_from_radius(number, a, b, words['R'] * state.scale,
                                     ccw)
    else:
        offset = np.array([words.get(letters[0], 0.0),
                           words.get(letters[1], 0.0)]) * state.scale
        centre, shift = _centre_from_offsets(number, a, b, a + offset)
    ra, rb = a - centre, b - centre
    full = float(np.hypot(*(b - a))) <= FULL_TURN_TOLERANCE
    if full:
        sweep = 2.0 * math.pi
    else:   # counter-clockwise from the start to the end, in [0, 2 pi)
        sweep = (math.atan2(rb[1], rb[0]) - math.atan2(ra[1], ra[0])) % (
            2.0 * math.pi)
        if not ccw:
            sweep = 2.0 * math.pi - sweep
    # The centre moved by ``shift`` moves the arc's point at sweep psi by
    # 2 shift sin(psi / 2): at most rounding.
    moved = 2.0 * shift * math.sin(0.5 * min(sweep, math.pi))
    if moved > ARC_RADIUS_TOLERANCE:
        raise ProgramError(number, f'the arc\'s end is off its circle: its '
                           f'centre moved onto the chord\'s bisector '
                           f'({shift * 1e3:.6g} mm) would move the arc by '
                           f'{moved * 1e3:.6g} mm, more than '
                           f'{ARC_RADIUS_TOLERANCE * 1e3:g} mm')
    angle = (sweep + 2.0 * math.pi * (int(turns or 1) - 1)) * (
        1.0 if ccw else -1.0)
    centre3 = start.copy()
    centre3[i1], centre3[i2] = centre
    normal = np.zeros(3)
    normal[i3] = 1.0
    end = target.copy()
    if full:    # the end's in-plane coordinates are the start's, exactly
        end[i1], end[i2] = start[i1], start[i2]
    return Arc(start.copy(), end, number, feed, state.mode, state.tolerance,
               centre3, normal, angle, float(target[i3] - start[i3]))


def _spline(number, state, target, axes, words, p_word):
    """
    Return the G5 (cubic) or G5.1 (quadratic) spline to ``target``.

    LinuxCNC's reading, in the XY plane (G17) only, X and Y only: G5's
    first control point is the start plus ``I J``, its second the end plus
    ``P Q`` (both needed); ``I J`` both or neither, neither taking the
    handle of the G5 just before (``-P -Q``: tangent to it), so the first
    of a series needs them. G5.1's control point is the start plus ``I
    J`` (one may be left out: 0), not both zero. As a cubic Bezier (G5.1
    raised exactly); refused where its speed vanishes, where it could not
    be followed by its arc length.
    """
    name = _code(state.motion)
    if state.plane != 17:
        raise ProgramError(number, f'{name} only in the XY plane (G17), not '
                           f'G{state.plane}')
    if 'Z' in axes:
        raise ProgramError(number, f'{name} moves X and Y only, not Z')
    wrong = [k for k in words if k not in ('IJQ' if state.motion == 5
                                           else 'IJ')]
    if wrong or (p_word is not None and state.motion != 5):
        raise ProgramError(number, f'{(wrong or ["P"])[0]} is not a word of '
                           f'{name} (' + ('I J P Q' if state.motion == 5
                                          else 'I J') + ')')
    feed = _feed(number, state, False)
    start = state.position
    scale = state.scale
    first = np.array([words.get('I', 0.0), words.get('J', 0.0), 0.0]) * scale
    if state.motion == 5:
        if ('I' in words) != ('J' in words):
            raise ProgramError(number, 'G5 needs both I and J, or neither')
        if 'I' not in words:
            if state.handle is None:
                raise ProgramError(number, 'the first G5 of a series needs I '
                                   'and J')
            first = state.handle
        if p_word is None or 'Q' not in words:
            raise ProgramError(number, 'G5 needs both P and Q')
        second = np.array([p_word, words['Q'], 0.0]) * scale
        control = np.array([start, start + first, target + second, target])
        state.handle = -second
    else:
        if not first.any():
            raise ProgramError(number, 'G5.1 needs I or J, not zero: the '
                               'control point\'s offset from the start')
        middle = start + first
        control = np.array([start, start + 2.0 / 3.0 * (middle - start),
                            target + 2.0 / 3.0 * (middle - target), target])
    if (np.abs(control - start) <= ZERO_LENGTH).all():
        return None
    least, most = bezier.least_speed(control[None])
    if not least[0] > SPLINE_REGULAR * most[0]:
        raise ProgramError(number, f'the {name} spline stops where its speed '
                           'vanishes (an offset of zero, or a cusp): not a '
                           'path G can follow by its length')
    return Spline(start.copy(), target.copy(), number, feed, state.mode,
                  state.tolerance, control)


def _centre_from_offsets(number, a, b, centre):
    """
    Check an I J K centre; return it moved onto the chord's bisector.

    Returns ``(centre, shift)``: ``shift`` (m) how far it moved.
    """
    ra = float(np.hypot(*(a - centre)))
    rb = float(np.hypot(*(b - centre)))
    if ra <= ZERO_LENGTH:
        raise ProgramError(number, 'an arc of radius zero (its centre is its '
                           'start)')
    differ = abs(rb - ra)
    if differ > ARC_RADIUS_TOLERANCE or differ > ARC_RADIUS_SHARE * max(
            ra, rb):
        raise ProgramError(number, f'the arc\'s end is {rb * 1e3:.6g} mm from '
                           f'its centre, its start {ra * 1e3:.6g} mm: no arc '
                           f'joins them (at most {ARC_RADIUS_TOLERANCE * 1e3:g}'
                           f' mm and {ARC_RADIUS_SHARE:.1%} apart)')
    chord = b - a
    length = float(np.hypot(*chord))
    if length <= FULL_TURN_TOLERANCE:
        return centre, 0.0
    along = chord / length
    shift = float((centre - 0.5 * (a + b)) @ along)
    return centre - along * shift, abs(shift)


def _centre_from_radius(number, a, b, radius, ccw):
    """Centre of the R-format arc (RS274NGC: R < 0 the longer one)."""
    chord = b - a
    length = float(np.hypot(*chord))
    if length <= FULL_TURN_TOLERANCE:
        raise ProgramError(number, 'a full turn needs I J K, not R')
    if radius == 0.0:
        raise ProgramError(number, 'an arc of radius zero')
    half = 0.5 * length
    if abs(radius) < half * (1.0 - 1e-9) - ARC_RADIUS_TOLERANCE:
        raise ProgramError(number, f'the arc radius {abs(radius) * 1e3:.6g} '
                           f'mm does not fit its chord of '
                           f'{length * 1e3:.6g} mm')
    height = math.sqrt(max(radius * radius - half * half, 0.0))
    left = np.array([-chord[1], chord[0]]) / length
    side = 1.0 if ccw else -1.0
    if radius < 0.0:
        side = -side
    return 0.5 * (a + b) + side * height * left
