"""
The one place text from messages, requests and files is shortened.

:func:`clip` cuts a text (a frame id, joint names, a parameter value, a
repr) to about TEXT_LIMIT characters, dropping its middle, before it
reaches a log line, a reply or an error message: no input can make a line
longer than that plus a few dozen characters.
"""

from __future__ import annotations

# Longest log line or reply reason made from a message's text (characters).
TEXT_LIMIT = 2000


def clip(text: object, limit: int = TEXT_LIMIT) -> str:
    """
    Return ``text`` cut to about ``limit`` characters (its middle dropped).

    The one place where text that a message or a request carries (a frame
    id, joint names, a parameter value) is shortened before it is logged or
    sent back, so no input can make a log line longer than ``limit`` plus
    a few dozen characters.

    >>> clip('a' * 10 + 'b' * 10, 4)
    'aa ... [16 characters cut] ... bb'
    """
    text = str(text)
    if len(text) <= limit:
        return text
    half = limit // 2
    return (f'{text[:half]} ... [{len(text) - 2 * half} characters cut] ... '
            f'{text[-half:]}')
