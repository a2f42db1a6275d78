"""
The drawing's robot gives today's figures to the last bit.

``drawing_outputs.json`` holds what the code before per-leg geometry
(commit 7e432b9) gave for three robots at fixed states: every function of
the math library the per-leg rows could change, the refusals' messages
included (``drawing_outputs.py``). Today's code must give the same bits
with the rows absent, and with every row given at the drawing's value
(``bar_length`` as ``l3`` on each leg): then the mechanics take the
drawing's own closed forms (``Robot.as_drawn``).
"""

import json

from drawing_outputs import FILE, outputs
from orthoglide_ros.model.robot import Robot
import pytest

DRAWING_ROWS = {
    'axis_point_a': (0.0, 0.0, 0.0), 'axis_point_b': (0.0, 0.0, 0.0),
    'axis_point_c': (0.0, 0.0, 0.0),
    'axis_direction_a': (1.0, 0.0, 0.0), 'axis_direction_b': (0.0, 1.0, 0.0),
    'axis_direction_c': (0.0, 0.0, 1.0),
    'joint_offset': (0.0, 0.0, 0.0),
    'attachment_a': (0.0, 0.0, 0.0), 'attachment_b': (0.0, 0.0, 0.0),
    'attachment_c': (0.0, 0.0, 0.0),
}


def drawing_rows(values):
    """Every geometry row at the drawing's value for a robot's values."""
    return {**DRAWING_ROWS,
            'bar_length': (values.get('l3', Robot().l3),) * 3}


def mismatches(expected, actual, where=''):
    """Yield the paths where two nests of hex strings differ."""
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and expected.keys() == actual.keys(), where
        for key in expected:
            yield from mismatches(expected[key], actual[key], f'{where}/{key}')
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(expected) == len(actual), where
        for i, (e, a) in enumerate(zip(expected, actual)):
            yield from mismatches(e, a, f'{where}[{i}]')
    elif expected != actual:
        yield f'{where}: {expected} before, {actual} now'


def found_only(robots):
    """
    Blank forward_kinematics_rows' positions where ``found`` is false.

    There they are "meaningless" (its docstring): any number may stand.
    """
    for values in robots.values():
        positions, found = values['forward_kinematics_rows']
        for k, ok in enumerate(found):
            if not ok:
                positions[k] = None
    return robots


@pytest.mark.parametrize('given', ['absent', 'at_the_drawing'])
def test_the_drawing_gives_todays_figures_to_the_last_bit(given):
    stored = json.loads(FILE.read_text())
    commit = stored['commit'][:7]
    stored = found_only(stored['robots'])
    now = found_only(outputs(
        drawing_rows if given == 'at_the_drawing' else None))
    wrong = list(mismatches(stored, now))
    assert not wrong, (f'{len(wrong)} outputs differ from commit '
                       f'{commit}\'s, first: {wrong[:5]}')


def test_rows_at_the_drawing_are_the_drawing():
    for values in ({}, {'l3': 0.93}):
        robot = Robot(**values, **drawing_rows(values))
        assert robot.as_drawn
        assert robot == Robot(**values, bar_length=(robot.l3,) * 3)
    assert not Robot(joint_offset=(0.0, 1e-9, 0.0)).as_drawn
