"""
A new law is one entry in ``model/terms.py``: doc/model.md's example, run.

doc/model.md#adding-a-term shows the diff that adds a quadratic drag ``d_j
v |v|``. Its ``terms.py`` part is applied to a copy of the package, and a
fresh interpreter on that copy checks that everything the page says
follows does: the ``robot.*`` parameter (the Robot's field, the nodes'
declarations, the page's table), the forces of ``solve`` and
``solve_batch`` (the law written here again), the MuJoCo plant's force,
identification's law ``coulomb+quadratic`` and its regressor column, and
``identify --friction``'s choices.
"""

import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / 'doc' / 'model.md'
TERMS = 'orthoglide_ros/model/terms.py'

CHECKS = '''
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import model_tables
import orthoglide_ros
assert orthoglide_ros.__file__.startswith(sys.argv[2]), orthoglide_ros
from orthoglide_ros.cores.parameters import ROBOT_SPECS
from orthoglide_ros.model import mechanics, mjcf
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import identification
from orthoglide_ros.tools.cli import main

DRAG = (30.0, 12.0, 50.0)
robot = Robot(friction_quadratic=DRAG, friction_viscous=(4.0, 5.0, 6.0))
rigid = robot.replace(friction_quadratic=(0.0, 0.0, 0.0))
assert Robot().friction_quadratic == (0.0, 0.0, 0.0)
assert 'robot.friction_quadratic' in [spec.name for spec in ROBOT_SPECS]
assert '| `robot.friction_quadratic` |' in model_tables.parameters_table()
assert '| `quadratic` |' in model_tables.terms_table()

rng = np.random.default_rng(1)
p, v, a = (rng.uniform(-s, s, (200, 3)) for s in (0.3, 1.0, 20.0))
batch, without = (mechanics.solve_batch(r, p, v, a) for r in (robot, rigid))
drag = np.array(DRAG) * without.lambdadot * np.abs(without.lambdadot)
assert np.abs(batch.force - without.force - drag).max() < 1e-12
single = mechanics.solve(robot, p[0], v[0], a[0])
assert np.abs(np.subtract(single.force, batch.force[0])).max() < 1e-12
speeds = (0.2, -0.5, 0.1)
assert np.allclose(mjcf.friction_beyond(robot, speeds),
                   np.array(DRAG) * speeds * np.abs(speeds), 1e-14, 0.0)

law = identification.parse_law('coulomb+quadratic')
w = identification.regressor(robot, p, v, a, law)
theta = identification.standard_parameters(robot, law)
assert np.abs(w @ theta - batch.force).max() < 1e-12 * np.abs(
    batch.force).max()
assert 'quadratic_c' in identification.standard_names(law)
try:
    main(['identify', '--help'])
except SystemExit:
    pass
'''


def terms_diff():
    """Return the ``terms.py`` hunks of the page's diff: (old, new) lines."""
    block = re.search(r'```diff\n(.*?)```', PAGE.read_text(), re.S).group(1)
    part = block.split(f'+++ b/{TERMS}\n', 1)[1].split('\n--- ', 1)[0]
    hunks = []
    for hunk in re.split(r'^@@[^\n]*\n', part, flags=re.M)[1:]:
        lines = hunk.rstrip('\n').split('\n')
        hunks.append(([line[1:] for line in lines if line[:1] in ' -'],
                      [line[1:] for line in lines if line[:1] in ' +']))
    return hunks


def apply(text, hunks):
    """Return ``text`` with every hunk applied at its context's place."""
    for old, new in hunks:
        before = '\n'.join(old) + '\n'
        assert text.count(before) == 1, f'the diff does not apply: {old}'
        text = text.replace(before, '\n'.join(new) + '\n')
    return text


def test_the_pages_diff_is_all_a_new_law_needs(tmp_path):
    copy = tmp_path / 'orthoglide_ros'
    shutil.copytree(ROOT / 'orthoglide_ros', copy,
                    ignore=shutil.ignore_patterns('__pycache__'))
    terms = tmp_path / TERMS
    terms.write_text(apply(terms.read_text(), terms_diff()))
    result = subprocess.run(
        [sys.executable, '-c', CHECKS, str(ROOT / 'test'), str(tmp_path)],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
        env={**os.environ, 'PYTHONPATH': str(tmp_path)})
    assert result.returncode == 0, result.stderr
    assert 'coulomb+quadratic' in result.stdout


def test_the_diff_is_read_from_the_page():
    """The check above can fail: the hunks are the page's, and they apply."""
    hunks = terms_diff()
    assert any('QUADRATIC = Term(' in line for _, new in hunks
               for line in new)
    original = (ROOT / TERMS).read_text()
    assert 'QUADRATIC' not in original
    assert 'QUADRATIC' in apply(original, hunks)
