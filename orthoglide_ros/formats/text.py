"""
The one place text from messages, requests and files is made safe to show.

:func:`clip` cuts a text to about TEXT_LIMIT characters; :func:`printable`
also escapes every character that is not printable, so no text a peer
gives can start, forge or colour a log line. See doc/robustness.md#logs.
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


def printable(text: object, limit: int = TEXT_LIMIT) -> str:
    r"""
    Return ``text`` on one line, every unprintable character escaped, clipped.

    A character that ``str.isprintable()`` refuses becomes its Python
    escape (``\n``, ``\x1b``, ``\u2028``), as ``repr`` writes it; the
    result is then cut by :func:`clip`. The one filter between a node's
    text and its log (and its ``/diagnostics`` message).

    >>> print(printable('refused\n[FATAL] [0.0] [node]: FORGED\x1b[2J'))
    refused\n[FATAL] [0.0] [node]: FORGED\x1b[2J
    """
    text = str(text)
    if not text.isprintable():
        text = ''.join(c if c.isprintable() else repr(c)[1:-1]
                       for c in text)
    return clip(text, limit)
