r"""
A line of G-code read into its words, as RS274NGC reads before it executes.

:func:`lines_of` splits a program into lines as an editor counts them;
:func:`read_words` reads one line, its comments dropped, into its words (a
letter and a number); :func:`sort_words` splits them into the line's G
codes and other words. What they refuse, naming the line: a letter the
subset has not (named: ``G41 (cutter compensation) is not supported``), a
G or M code it has not (by RS274NGC's families), two codes of one modal
group, a word twice, a malformed number. Every number follows one rule
(:func:`read_number`). What the words do, the modal state and the moves,
is :mod:`gcode`'s.
"""

from __future__ import annotations

import re
from typing import Optional

from orthoglide_ros.formats.text import clip
from orthoglide_ros.planning.moves import NUMBER_BOUND, ProgramError

SUPPORTED_G = {0.0, 1.0, 2.0, 3.0, 5.0, 5.1, 17.0, 18.0, 19.0, 20.0, 21.0,
               40.0, 49.0, 61.0, 61.1, 64.0, 80.0, 90.0, 91.0, 91.1, 94.0}
# Modal groups of the supported codes (two of one group on a line: refused).
GROUPS = {0: 'motion', 1: 'motion', 2: 'motion', 3: 'motion', 5: 'motion',
          5.1: 'motion', 17: 'plane',
          18: 'plane', 19: 'plane', 20: 'units', 21: 'units',
          90: 'distance', 91: 'distance', 61: 'path control',
          61.1: 'path control', 64: 'path control'}
# Why a code is refused, by family (RS274NGC's names).
G_NAMES = (
    ((4,), 'dwell'), ((5.2, 5.3), 'NURBS blocks'),
    ((7, 8), 'lathe diameter mode'), ((10,), 'data setting'),
    ((28, 28.1, 30, 30.1), 'return to a stored position'),
    ((33, 33.1, 76), 'threading'), ((38.2, 38.3, 38.4, 38.5), 'probing'),
    ((41, 41.1, 42, 42.1), 'cutter compensation'),
    ((43, 43.1, 43.2), 'tool length offset'),
    ((52, 92, 92.1, 92.2, 92.3), 'coordinate offsets'),
    ((53,), 'machine coordinates'),
    ((54, 55, 56, 57, 58, 59, 59.1, 59.2, 59.3), 'work offsets'),
    ((73, 81, 82, 83, 84, 85, 86, 87, 88, 89), 'canned cycles'),
    ((90.1,), 'absolute arc centres'), ((93,), 'inverse time feed'),
    ((95,), 'feed per revolution'), ((96, 97), 'spindle speed mode'),
    ((98, 99), 'canned cycle return'))
M_NAMES = (
    ((0, 1, 60), 'program pause'), ((3, 4, 5, 19), 'spindle'),
    ((6, 61), 'tool change'), ((7, 8, 9), 'coolant'),
    ((48, 49, 50, 51, 52, 53), 'override control'),
    ((62, 63, 64, 65, 66, 67, 68), 'digital and analog outputs'),
    ((98, 99), 'subprograms'))
WORD_NAMES = {'S': 'spindle speed', 'T': 'tool', 'H': 'tool length offset',
              'D': 'cutter compensation', 'A': 'rotary axis A',
              'B': 'rotary axis B', 'C': 'rotary axis C', 'U': 'axis U',
              'V': 'axis V', 'W': 'axis W', 'E': 'extruder axis E',
              'L': 'loop count or data setting L', 'O': 'subroutines',
              '#': 'parameters', '[': 'expressions'}
# The letters of the subset's words.
WORDS = frozenset('GMFNXYZIJKRPQ')
NUMBER = re.compile(r'[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)\Z')
NUMBER_CHARS = frozenset('0123456789.+-')
# Only these end a line (str.splitlines also breaks at form feeds, U+2028
# and more, which an editor shows within a line).
LINE_END = re.compile(r'\r\n|\r|\n')

# A word: its letter, its value (None: refused, the reason its text) and
# its text as written.
Word = tuple[str, Optional[float], str]


def read_number(text: str, what: str) -> float:
    """
    Return the value of a number written ``text``, by the one rule.

    ASCII digits with at most one point and an optional sign (RS274NGC's
    form: no exponent), at most NUMBER_BOUND in magnitude. Raises
    ValueError naming ``what`` (``X1..2``) otherwise.

    >>> read_number('-12.5', 'X-12.5')
    -12.5
    """
    if not NUMBER.match(text):
        raise ValueError(f'malformed number {clip(what, 40)}: a number is '
                         'the digits 0-9 with at most one point')
    value = float(text)
    if not abs(value) <= NUMBER_BOUND:
        raise ValueError(f'{clip(what, 40)}: beyond {NUMBER_BOUND:,.0f}, '
                         'the largest magnitude a number may have')
    return value


def lines_of(text: str) -> list[str]:
    """Return the lines of ``text`` as an editor counts them (LINE_END)."""
    return LINE_END.split(text)


def read_words(number: int, raw: str) -> Optional[list[Word]]:
    """
    Return the words of line ``number`` (text ``raw``), None if none.

    The words up to the first one not in the subset, that one last with
    the value None and the reason it is refused as its text.
    """
    text = ''.join(_strip_comments(number, raw).split())
    if not text or text == '%':
        return None
    if text.startswith('/'):
        raise ProgramError(number, '/ (block delete) is not supported')
    out: list[Word] = []
    k = 0
    while k < len(text):
        letter = text[k].upper()
        j = k + 1
        while j < len(text) and text[j] in NUMBER_CHARS:
            j += 1
        digits = text[k + 1:j]
        word = f'{letter}{digits}'
        if letter not in WORDS:     # refused in its turn (a G code first)
            out.append((letter, None, _unknown(text, k, j, out)))
            return out
        if j < len(text) and text[j].isdigit():     # not one of 0-9
            raise ProgramError(number, f'malformed number {word}{text[j]}: '
                               'a number is the digits 0-9 with at most one '
                               'point')
        try:
            out.append((letter, read_number(digits, word), word))
        except ValueError as error:
            raise ProgramError(number, str(error)) from None
        k = j
    return out


def _unknown(text, k, j, words):
    """Say why the word at ``text[k:j]`` is not one of the subset's."""
    letter = text[k].upper()
    if letter == 'E' and words and k > 0 and text[k - 1] in NUMBER_CHARS:
        before = words[-1][2]
        return (f'{before}{text[k:j]}: a number with an exponent; a number '
                'is the digits 0-9 with at most one point (and E, an '
                'extruder axis, is not supported)')
    name = WORD_NAMES.get(letter)
    if name is not None:
        word = letter + text[k + 1:j] if letter.isalpha() else letter
        return f'{clip(word, 40)} ({name}) is not supported'
    if letter.isalpha():
        return f'{clip(text[k:j], 40)} (an unknown word) is not supported'
    return (f'unexpected {text[k]!r} where a word (a letter and a number) '
            'was expected')


def _strip_comments(number, raw):
    """Return ``raw`` without its ``( )`` and ``;`` comments."""
    out = []
    inside = False
    for char in raw:
        if inside:
            if char == ')':
                inside = False
            elif char == '(':
                raise ProgramError(number, 'nested comment')
        elif char == '(':
            inside = True
        elif char == ';':
            break
        else:
            out.append(char)
    if inside:
        raise ProgramError(number, 'comment not closed: ( without )')
    return ''.join(out)


def sort_words(number: int, line: list[Word]
               ) -> tuple[list[float], dict[str, float], bool]:
    """
    Split line ``number``'s words into its G codes, other words, its end.

    Returns ``(g_codes, values, end)``: the G codes (rounded to a tenth),
    the other words' values by letter, and whether the line ends the
    program (M2, M30). Raises :class:`ProgramError` on the first word the
    subset refuses.
    """
    g_codes = []
    values = {}
    groups: dict[str, str] = {}
    end = False
    for letter, value, text in line:
        if value is None:
            raise ProgramError(number, text)
        if letter == 'G':
            code = round(value, 1)
            if code not in SUPPORTED_G or abs(value - code) > 1e-9:
                raise ProgramError(number, f'{text} ({_name(G_NAMES, code)}) '
                                   'is not supported')
            group = GROUPS.get(code)
            if group is not None:
                if group in groups:
                    raise ProgramError(number, f'{groups[group]} and {text} '
                                       f'on one line: two {group} codes')
                groups[group] = text
            g_codes.append(code)
        elif letter == 'M':
            if value in (2.0, 30.0):
                end = True
            else:
                raise ProgramError(number, f'{text} ({_name(M_NAMES, value)})'
                                   ' is not supported')
        else:   # one of FNXYZIJKRP (read_words refuses the others)
            if letter in values:
                raise ProgramError(number, f'two {letter} words on one line')
            values[letter] = value
    return g_codes, values, end


def _name(table, code):
    for codes, name in table:
        if code in codes:
            return name
    return 'not in the subset'
