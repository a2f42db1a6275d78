"""
Read columns of numbers from a CSV file by their header names, without ROS.

The one reader of the package's CSV inputs: the trajectories of
``orthoglide batch`` and the logs of ``orthoglide identify``
(:func:`orthoglide_ros.identification.read_csv`). Rules:

- columns are matched by header name, case-insensitively after trimming
  spaces, in any order; other columns are ignored; a known column may not
  appear twice;
- the columns come in groups (``x, y, z``): a group is all there or absent,
  and a required group must be there;
- every cell read must be a finite number; blank lines are skipped; data
  rows are counted from 1 after the header, and errors name the row, its
  line in the file and the column.
"""

import csv
import io
import math
import sys

import numpy as np


class CsvError(ValueError):
    """A CSV file that cannot be read as asked; the message says where."""


def read_columns(path, groups, name=None):
    """
    Read the ``groups`` of columns of the CSV file ``path`` (``-``: stdin).

    ``groups``: ``(group, columns, required)`` triples, e.g. ``('position',
    ('x', 'y', 'z'), True)``. Returns ``(values, lines)``: ``values`` maps
    each group to an (N, len(columns)) array of floats, or None if absent;
    ``lines`` the file line of each data row. ``name`` names the file in
    messages (default ``path``). Raises :class:`CsvError`.
    """
    name = name or ('<stdin>' if path == '-' else str(path))
    try:
        if path == '-':
            text = sys.stdin.read()
        else:
            with open(path, encoding='utf-8-sig', newline='') as stream:
                text = stream.read()
    except OSError as error:
        raise CsvError(f'cannot read {name}: {error.strerror}') from None
    except UnicodeDecodeError:
        raise CsvError(f'{name}: not a UTF-8 text file') from None
    reader = csv.reader(io.StringIO(text, newline=''))
    header = next(reader, None)
    if not header:
        example = ','.join(c for _, columns, _ in groups for c in columns)
        raise CsvError(f'{name}: empty file: expected a header line such '
                       f'as {example}')
    header = [h.strip().lower() for h in header]
    known = {c for _, columns, _ in groups for c in columns}
    index = {}
    for i, column in enumerate(header):
        if column in index and column in known:
            raise CsvError(f'{name}: column {column!r} appears twice')
        index.setdefault(column, i)
    present = []
    for group, columns, required in groups:
        found = [c for c in columns if c in index]
        if found and len(found) < len(columns) or required and not found:
            missing = [c for c in columns if c not in index]
            raise CsvError(f'{name}: no {missing[0]!r} column: the {group} '
                           f'needs all of {", ".join(columns)}')
        present.append(columns if found else None)
    wanted = [c for columns in present if columns for c in columns]
    rows, lines = [], []
    for cells in reader:
        if not any(cell.strip() for cell in cells):
            continue        # blank line
        row, line = len(rows) + 1, reader.line_num
        values = []
        for column in wanted:
            i = index[column]
            cell = cells[i].strip() if i < len(cells) else ''
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise CsvError(
                    f'{name}: data row {row} (line {line}), column '
                    f'{column!r}: {cell!r} is not a finite number')
            values.append(value)
        rows.append(values)
        lines.append(line)
    data = np.array(rows, dtype=float).reshape(len(rows), len(wanted))
    columns = dict(zip(wanted, data.T))
    values = {group: None if found is None else np.column_stack(
        [columns[c] for c in found]).reshape(len(rows), len(found))
        for (group, _, _), found in zip(groups, present)}
    return values, lines
