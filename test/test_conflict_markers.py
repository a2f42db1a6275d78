"""
No tracked file holds an unresolved merge conflict.

A conflict as git writes it: a line starting ``<<<<<<< ``, later a line
that is ``=======`` alone, later a line starting ``>>>>>>> `` (diff3's
``||||||| `` section between the first two changes nothing). A Markdown
heading underlined with ``=======`` is not one: the three must come in
that order. Every file ``git ls-files`` lists is read, binary ones too.
"""

import os
import shutil
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Spelled in pieces so that this file holds none of them at a line start.
OURS, SEPARATOR, THEIRS = b'<' * 7 + b' ', b'=' * 7, b'>' * 7 + b' '


def conflicts(data):
    """Yield the 1-based line of each conflict's ``<<<<<<<`` in ``data``."""
    start = separated = None
    for number, line in enumerate(data.split(b'\n'), 1):
        line = line.rstrip(b'\r')
        if line.startswith(OURS):
            start, separated = number, False
        elif start is not None and line == SEPARATOR:
            separated = True
        elif separated and line.startswith(THEIRS):
            yield start
            start = separated = None


def tracked_files():
    """Return the files git tracks in this checkout (skip the test if none)."""
    if shutil.which('git') is None or not os.path.exists(
            os.path.join(ROOT, '.git')):
        pytest.skip('not a git checkout')
    listed = subprocess.run(['git', 'ls-files', '-z'], cwd=ROOT, check=True,
                            capture_output=True).stdout
    return [name for name in listed.decode().split('\0') if name]


def test_no_tracked_file_holds_a_merge_conflict():
    found = []
    for name in tracked_files():
        path = os.path.join(ROOT, name)
        if os.path.isfile(path):     # a deletion not yet committed
            with open(path, 'rb') as stream:
                found += [f'{name}:{line}' for line in conflicts(stream.read())]
    assert not found, ('unresolved merge conflicts (keep one version, '
                       'delete the markers): ' + ', '.join(found))


def test_conflicts_are_found_and_underlines_are_not():
    conflict = b'\n'.join([b'a', OURS + b'HEAD', b'ours', SEPARATOR,
                           b'theirs', THEIRS + b'branch', b'b'])
    diff3 = b'\r\n'.join([OURS + b'HEAD', b'ours', b'|' * 7 + b' base',
                          b'base', SEPARATOR, b'theirs', THEIRS + b'other'])
    heading = b'\n'.join([b'Title', SEPARATOR, b'text', THEIRS + b'quoted'])
    assert list(conflicts(conflict)) == [2]
    assert list(conflicts(diff3)) == [1]
    assert list(conflicts(conflict + b'\n' + conflict)) == [2, 9]
    assert list(conflicts(heading)) == []
    assert list(conflicts(OURS + b'x\n' + THEIRS + b'y')) == []
