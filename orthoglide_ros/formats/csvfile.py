"""
Read columns of numbers from a CSV file by their header names, without ROS.

The one reader of the package's CSV inputs (``orthoglide batch``, the logs
of ``orthoglide identify``): groups of columns by name, finite numbers
only, as many cells in every row as the header has, read as a stream
into arrays within MAX_ROWS rows, MAX_LINES lines and MAX_LINE
characters a line. Its rules: doc/cli.md#batch and
doc/robustness.md#files-and-paths.
"""

from __future__ import annotations

from typing import Optional, Sequence

from array import array
import contextlib
import csv
import math
import sys

import numpy as np

from orthoglide_ros.model.types import Array, Path

# Most data rows read: 33 minutes at 1 kHz (about 200 MB of doubles for
# the widest input, 13 columns).
MAX_ROWS = 2_000_000
# Longest line (characters, its end not counted): the csv module's field
# limit, applied to a line as it is read.
MAX_LINE = 131_072
# Most lines read, blank ones included: an endless run of blank lines ends.
MAX_LINES = 2 * MAX_ROWS


class CsvError(ValueError):
    """
    A CSV file that cannot be read as asked: ``source: detail``.

    ``source`` names the file, ``detail`` says where in it and why.
    """

    def __init__(self, source: str, detail: str) -> None:
        """Keep the file's name and the message without it."""
        super().__init__(f'{source}: {detail}')
        self.source = source
        self.detail = detail


def read_columns(path: Path, groups: Sequence[tuple[str, Sequence[str], bool]],
                 name: Optional[str] = None, blank: Sequence[str] = (),
                 max_rows: Optional[int] = None
                 ) -> dict[str, Optional[Array]]:
    """
    Read the ``groups`` of columns of the CSV file ``path`` (``-``: stdin).

    ``groups``: ``(group, columns, required)`` triples, e.g. ``('position',
    ('x', 'y', 'z'), True)``. Returns ``(values, lines)``: ``values`` maps
    each group to an (N, len(columns)) array of floats, or None if absent;
    ``lines`` the file line of each data row. ``name`` names the file in
    messages (default ``path``); an empty cell of a column in ``blank`` is
    read as NaN (not measured), of another refused; at most ``max_rows``
    data rows and twice as many lines (default MAX_ROWS and MAX_LINES).
    Raises :class:`CsvError`.
    """
    name = name or ('<stdin>' if path == '-' else str(path))
    try:
        with contextlib.ExitStack() as stack:
            stream = sys.stdin if path == '-' else stack.enter_context(
                open(path, encoding='utf-8-sig', newline=''))
            reader = csv.reader(_lines(stream, name, None if max_rows is None
                                       else 2 * max_rows))
            try:
                return _read(reader, groups, name, frozenset(blank),
                             max_rows)
            except csv.Error as error:
                raise CsvError(name, f'line {reader.line_num}: '
                               f'{error}') from None
    except OSError as error:
        raise CsvError(name, f'cannot read: {error.strerror}') from None
    except UnicodeDecodeError:
        raise CsvError(name, 'not a UTF-8 text file') from None


def _lines(stream, name, most=None):
    """
    Yield the lines of ``stream``; refuse one of over MAX_LINE characters.

    Each line is read at most MAX_LINE + 2 characters at a time (its end
    included), so a longer one is refused before it is held whole; at most
    ``most`` lines (default MAX_LINES).
    """
    most = MAX_LINES if most is None else most
    for number in range(1, most + 1):
        line = stream.readline(MAX_LINE + 2)
        if not line:
            return
        if len(line) > MAX_LINE and len(line.rstrip('\r\n')) > MAX_LINE:
            raise CsvError(name, f'line {number}: longer than {MAX_LINE} '
                           'characters: not a CSV file of numbers')
        yield line
    if stream.readline(1):
        raise CsvError(name, f'more than {most} lines: split the file')


def _read(reader, groups, name, blank=frozenset(), max_rows=None):
    """Read the header and the data rows of ``reader`` (see read_columns)."""
    header = next(reader, None)
    if not header:
        example = ','.join(c for _, columns, _ in groups for c in columns)
        raise CsvError(name, f'empty file: expected a header line such '
                       f'as {example}')
    header = [h.strip().lower() for h in header]
    known = {c for _, columns, _ in groups for c in columns}
    index = {}
    for i, column in enumerate(header):
        if column in index and column in known:
            raise CsvError(name, f'column {column!r} appears twice')
        index.setdefault(column, i)
    present = []
    for group, columns, required in groups:
        found = [c for c in columns if c in index]
        if found and len(found) < len(columns) or required and not found:
            missing = [c for c in columns if c not in index]
            raise CsvError(name, f'no {missing[0]!r} column: the {group} '
                           f'needs all of {", ".join(columns)}')
        present.append(columns if found else None)
    wanted = [c for columns in present if columns for c in columns]
    cells_at = [index[c] for c in wanted]
    max_rows = MAX_ROWS if max_rows is None else max_rows
    data, lines = array('d'), array('q')
    for cells in reader:
        if not any(cell.strip() for cell in cells):
            continue        # blank line
        row, line = len(lines) + 1, reader.line_num
        if row > max_rows:
            raise CsvError(name, f'more than {max_rows} data rows: split '
                           'the file')
        if len(cells) != len(header):
            raise CsvError(name, f'data row {row} (line {line}): '
                           f'{len(cells)} cells where the header has '
                           f'{len(header)}: a comma missing or too many')
        for column, i in zip(wanted, cells_at):
            cell = cells[i].strip()
            if not cell and column in blank:
                data.append(math.nan)
                continue
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise CsvError(
                    name, f'data row {row} (line {line}), column '
                    f'{column!r}: {cell!r} is not a finite number')
            data.append(value)
        lines.append(line)
    rows = len(lines)
    table = np.frombuffer(data, dtype=float).reshape(rows, len(wanted))
    columns = {c: table[:, k] for k, c in enumerate(wanted)}
    values = {group: None if found is None else np.column_stack(
        [columns[c] for c in found]).reshape(rows, len(found))
        for (group, _, _), found in zip(groups, present)}
    return values, lines.tolist()
