"""
The tables of doc/model.md written from the code: parameters and terms.

``robot.ROWS`` gives the ``robot.*`` parameters' table, ``terms.TERMS``
the terms' (and identification's laws their last column). Each table
sits between a ``<!-- generated: NAME -->`` line and ``<!-- end:
NAME -->``; ``test_docs.py`` checks that the page holds what this module
writes, and ``.venv/bin/python test/model_tables.py --write`` rewrites
them after a term or a row changed.
"""

import math
from pathlib import Path
import re
import sys

from orthoglide_ros.model import terms
from orthoglide_ros.model.mjcf import RECORDED
from orthoglide_ros.model.robot import is_vector, ROWS
from orthoglide_ros.tools.identification import PLAIN

PAGE = Path(__file__).resolve().parents[1] / 'doc' / 'model.md'


def number(value):
    """Write a bound as a reader does: ``pi/2``, ``1e-4``, ``100``."""
    if value == math.pi / 2:
        return 'pi/2'
    if value and not 1e-3 <= abs(value) < 1e5:
        mantissa, exponent = f'{value:e}'.split('e')
        return f'{float(mantissa):g}e{int(exponent)}'
    return f'{value:g}'


def cell(text):
    """Return ``text`` for a table cell: its pipes escaped."""
    return text.replace('|', '\\|')


def parameters_table():
    """Return the Markdown table of every ``robot.*`` parameter."""
    lines = ['| parameter | type | default | range | meaning |',
             '|---|---|---|---|---|']
    for row in ROWS:
        vector = is_vector(row)
        if row.default is None:
            default = f'none: follows `robot.{row.follows}`'
        elif vector:
            default = '`[' + ', '.join(repr(float(v)) for v in row.default) \
                + ']`'
        else:
            default = f'`{float(row.default)!r}`'
        low, high = (number(v) for v in row.limits)
        bounds = f'({low}, {high})' if row.open else f'[{low}, {high}]'
        if row.none is not None:
            bounds = f'{number(row.none)} (none) or in {bounds}'
        else:
            bounds = f'in {bounds}' if vector else bounds
        bounds = f'each {bounds}' if vector else bounds
        if row.needs:
            bounds += f'; 0 where `robot.{row.needs}` is none'
        lines.append(
            f'| `robot.{row.name}` | {"double[3]" if vector else "double"} '
            f'| {default} | {bounds} '
            f'| {cell(row.description)} ({row.unit}) |')
    return '\n'.join(lines)


def terms_table():
    """Return the Markdown table of the terms beyond the rigid bodies."""
    lines = ['| term | parameters | law, on actuator j (`v = lambdadot_j`) '
             '| in MuJoCo | identified |', '|---|---|---|---|---|']
    for term in terms.TERMS:
        if term.force is None:
            mujoco = 'the platform body\'s `mass`'
        elif term.mujoco:
            mujoco = f'slide joint `{term.mujoco}`'
        elif term in RECORDED:
            mujoco = 'custom numeric data; a force the plant applies'
        else:
            mujoco = 'a force the plant applies'
        if term in PLAIN:
            identified = 'always'
        elif term.identified:
            identified = f'`+{term.part_of or term.name}`'
        else:
            identified = 'known'
        lines.append(
            f'| `{term.name}` | '
            + ', '.join(f'`robot.{row.name}`' for row in term.rows)
            + f' | `{cell(term.formula)}` | {mujoco} | {identified} |')
    return '\n'.join(lines)


TABLES = {'parameters': parameters_table, 'terms': terms_table}


def block(name):
    """Return the pattern of the generated block ``name`` of the page."""
    return re.compile(rf'(<!-- generated: {name} -->\n)(.*?)(<!-- end: '
                      rf'{name} -->)', re.S)


def written(text):
    """Return ``text`` with every generated block as this module writes it."""
    for name, table in TABLES.items():
        text = block(name).sub(lambda m: m.group(1) + table() + '\n'
                               + m.group(3), text)
    return text


if __name__ == '__main__':
    if sys.argv[1:] != ['--write']:
        sys.exit('usage: python test/model_tables.py --write')
    PAGE.write_text(written(PAGE.read_text()))
