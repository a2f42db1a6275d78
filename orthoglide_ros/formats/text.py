"""
The one place text from messages, requests and files is made safe.

:func:`clip` cuts a text to about TEXT_LIMIT characters; :func:`printable`
also escapes every character that is not printable, so no text a peer
gives can start, forge or colour a log line (doc/robustness.md#logs);
:func:`read_text` reads a small text file within a bound.
"""

from __future__ import annotations

from typing import BinaryIO, Union

from orthoglide_ros.model.types import Path

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


def read_text(source: Union[Path, BinaryIO], max_bytes: int) -> str:
    """
    Return the UTF-8 text of ``source``: a path, or a binary stream.

    At most ``max_bytes`` are read (a larger source is refused before it
    is held); a byte-order mark is dropped. Raises ValueError with the
    reason, without the path: cannot read, too large, not UTF-8.
    """
    try:
        if hasattr(source, 'read'):
            data = source.read(max_bytes + 1)
        else:
            with open(source, 'rb') as stream:
                data = stream.read(max_bytes + 1)
    except OSError as error:
        raise ValueError(f'cannot read: {error.strerror}') from None
    if len(data) > max_bytes:
        raise ValueError(f'larger than {max_bytes} bytes')
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as error:
        raise ValueError(f'not UTF-8 text (byte {error.start})') from None
