"""
Each leg's geometry rows: defaults, the accessor, and what is refused.

``robot.axis_point_*``, ``axis_direction_*``, ``joint_offset``,
``bar_length`` and ``attachment_*`` are the drawing's by default
(``bar_length`` follows ``l3`` on each leg); ``Robot.legs`` gives each
leg's point, direction, offset, length, attachment and frame, derived
once. A value not finite, beyond 0.1 m of the drawing (a bar length of
``l3``), a direction not a
unit vector, tilted beyond 10 deg or parallel to another, and legs that
do not assemble at home (no position, a leg shorter than its reach, too
near a singularity) are refused when the robot is built, naming the row,
by a parameters file and every node's table alike
(doc/model.md#the-machine-as-built).
"""

from collections import namedtuple
import importlib
import math
import re

from mechanics_reference import (
    lambda_jacobian, leg_geometry, LEGS, platform_position, sphere_residuals)
import numpy as np
from orthoglide_testing.robots_as_built import BUILT as BUILT_VALUES
from orthoglide_ros.cores.parameters import ROBOT_SPECS
from orthoglide_ros.formats.params_file import robot_from_parameters
from orthoglide_ros.model import legs
from orthoglide_ros.model.robot import ParameterError, Robot
import pytest


def refused(name, **values):
    with pytest.raises(ParameterError) as error:
        Robot(**values)
    assert error.value.name == f'robot.{name}', str(error.value)
    assert str(error.value).startswith(f'robot.{name}: ')
    return str(error.value)


def test_the_defaults_are_the_drawing():
    robot = Robot()
    assert robot.as_drawn
    assert robot.bar_length == (0.85, 0.85, 0.85)
    for leg, name, axis, frame in zip(robot.legs, 'abc', legs.DRAWING_AXES,
                                      legs.DRAWING_FRAMES):
        assert leg == legs.Leg(name, (0.0,) * 3, axis, 0.0, 0.85, (0.0,) * 3,
                               frame)
    # The drawing's frames: leg B sees G as (y, z, x), leg C as (z, x, y).
    g = np.array([1.0, 2.0, 3.0])
    assert (np.array(robot.legs[1].frame).T @ g).tolist() == [2.0, 3.0, 1.0]
    assert (np.array(robot.legs[2].frame).T @ g).tolist() == [3.0, 1.0, 2.0]


def test_bar_length_follows_l3_on_each_leg_until_given():
    assert Robot(l3=0.9).bar_length == (0.9, 0.9, 0.9)
    assert Robot(l3=0.9).as_drawn
    assert Robot().replace(l3=0.8).bar_length == (0.8, 0.8, 0.8)
    built = Robot(bar_length=(0.85, 0.86, 0.85))
    assert not built.as_drawn
    assert built.replace(l3=0.9).bar_length == (0.85, 0.86, 0.85)
    assert built.replace(l3=0.9).legs[1].length == 0.86


def test_each_leg_reads_its_rows_and_turns_its_drawing_frame_least():
    robot = Robot(**BUILT_VALUES)
    assert not robot.as_drawn
    for i, (leg, name) in enumerate(zip(robot.legs, 'abc')):
        given = np.array(BUILT_VALUES[f'axis_direction_{name}'])
        assert leg.point == BUILT_VALUES[f'axis_point_{name}']
        assert np.abs(np.array(leg.direction)
                      - given / np.linalg.norm(given)).max() <= 1e-16
        assert leg.offset == BUILT_VALUES['joint_offset'][i]
        assert leg.length == BUILT_VALUES['bar_length'][i]
        assert leg.attachment == BUILT_VALUES[f'attachment_{name}']
        frame = np.array(leg.frame)
        assert np.abs(frame.T @ frame - np.eye(3)).max() <= 1e-15
        assert abs(np.linalg.det(frame) - 1.0) <= 1e-15
        assert np.abs(frame[:, 0] - leg.direction).max() <= 4e-16
        # R_i = Rot P_i, Rot about n x u: no roll about the axis.
        turn = frame @ np.array(legs.DRAWING_FRAMES[i]).T
        axis = np.cross(legs.DRAWING_AXES[i], leg.direction)
        assert np.abs(turn @ axis - axis).max() <= 1e-17


def test_rows_round_trip_through_parameters_and_files():
    robot = Robot(**BUILT_VALUES)
    assert Robot(**robot.as_parameters()) == robot
    assert robot.replace(m5=16.0).legs == robot.legs
    values = {f'robot.{name}': [float(v) for v in value]
              for name, value in BUILT_VALUES.items()}
    assert robot_from_parameters(values) == robot
    specs = {spec.name: spec for spec in ROBOT_SPECS}
    assert specs['robot.bar_length'].type == 'double_array'
    assert specs['robot.bar_length'].default is None
    assert specs['robot.axis_direction_b'].default == [0.0, 1.0, 0.0]
    with pytest.raises(ParameterError) as error:
        robot_from_parameters({'robot.axis_direction_c': [0.0, 0.0, -1.0]})
    assert error.value.name == 'robot.axis_direction_c'


@pytest.mark.parametrize('name, value, words', [
    ('axis_point_a', (0.0, 0.2, 0.0), '[-0.1, 0.1] m'),
    ('axis_point_b', (0.0, 0.0, math.nan), 'finite'),
    ('axis_point_c', (0.0, 0.0), '3-vector'),
    ('joint_offset', (0.5, 0.0, 0.0), '[-0.1, 0.1] m'),
    ('attachment_a', (0.0, 0.0, -0.11), '[-0.1, 0.1] m'),
    ('attachment_c', 'x', '3-vector'),
    ('bar_length', (0.85, 0.0, 0.85), '[0.0001, 100] m'),
    ('bar_length', 0.85, '3-vector'),
    ('bar_length', (0.85, 0.85, 0.05), 'within 0.1 m of robot.l3 (0.85 m)'),
    ('bar_length', (0.001, 0.001, 0.001), 'within 0.1 m of robot.l3'),
    ('bar_length', (0.96, 0.85, 0.85), 'got (0.96, 0.85, 0.85)'),
    ('axis_direction_a', (0.5, 0.0, 0.0), 'unit vector'),
    ('axis_direction_a', (math.nan, 0.0, 0.0), 'finite'),
    ('axis_direction_b', (0.0, math.cos(0.35), math.sin(0.35)),
     'within 10 deg of the drawing\'s axis [0.0, 1.0, 0.0]'),
    ('axis_direction_b', (1.0, 0.0, 0.0), 'parallel to robot.axis_direction_a'),
    ('axis_direction_c', (0.0, 0.0, -1.0), '180 deg from it'),
], ids=repr)
def test_a_bad_row_is_refused_naming_it(name, value, words):
    assert words in refused(name, **{name: value})


def test_bar_lengths_lie_within_a_tenth_of_a_metre_of_l3():
    assert Robot(bar_length=(0.75, 0.95, 0.85)).legs[1].length == 0.95
    assert Robot(l3=0.3, bar_length=(0.2, 0.4, 0.3)).legs[0].length == 0.2
    assert 'got (0.2, 0.41, 0.3)' in refused('bar_length', l3=0.3,
                                             bar_length=(0.2, 0.41, 0.3))
    assert 'robot.l3 (0.3 m)' in refused('bar_length', l3=0.3,
                                         bar_length=(0.85, 0.3, 0.3))


def test_a_leg_shorter_than_its_reach_is_refused_as_its_bar_length():
    # A small robot (bars of 0.1 m), leg A's 0.05 m and 0.08 m off its axis.
    message = refused('bar_length', l3=0.1, bar_length=(0.05, 0.1, 0.1),
                      axis_point_a=(0.0, 0.08, 0.0))
    assert "leg A's bars (0.05 m) are shorter than its reach" in message
    assert '0.08 m from its axis' in message


def test_legs_without_a_home_position_are_refused_naming_the_row_to_blame():
    # Short bars, sliders pulled back 0.1 m: three spheres of 0.05 m, each
    # about 0.21 m from the others, meet nowhere; the drawing's offsets
    # would put them all through the origin.
    message = refused('joint_offset', l3=0.05,
                      joint_offset=(-0.1, -0.1, -0.1))
    assert 'the legs do not assemble: no platform position on the home ' \
        'branch' in message
    assert "with the drawing's value they would" in message


def values_of(**changes):
    """Return a refused robot's rows as the reference reads them."""
    values = {name: tuple(v) if isinstance(v, list) else v
              for name, v in Robot().as_parameters().items()}
    values.update(changes)
    return namedtuple('Values', values)(**values)


def test_legs_assembled_too_near_a_singularity_are_refused():
    # A small robot (bars of 0.1 m), leg A's axis 0.05 m beside home, its
    # bars 0.0642 m: the legs meet at lambda = 0 with a singularity
    # distance near 0.13 < the default margin 0.2.
    changes = {'l3': 0.1, 'axis_point_a': (0.0, 0.05, 0.0),
               'bar_length': (0.0642, 0.1, 0.1)}
    message = refused('axis_point_a', **changes)
    found = re.search(r'the legs assemble at lambda = \(0, 0, 0\) with the '
                      r'platform at \[(.*)\] m, too near a singularity '
                      r'\(distance (.*) < 0.2\)', message)
    assert found, message
    # Where and how near, by the independent model.
    values = values_of(**changes)
    home = platform_position(values, np.zeros(3))
    assert np.abs(sphere_residuals(values, home, np.zeros(3))).max() < 1e-15
    assert np.abs(np.array(found.group(1).split(', '), dtype=float)
                  - home).max() <= 1e-6 * np.abs(home).max()
    ratio = min(leg_geometry(values, leg, home).cos21
                * leg_geometry(values, leg, home).cos32 for leg in LEGS)
    jac = lambda_jacobian(values, home)
    conditioning = 3.0 * abs(np.linalg.det(jac)) / (
        np.linalg.norm(jac) * np.linalg.norm(np.linalg.inv(jac)
                                             * np.linalg.det(jac)))
    assert float(found.group(2)) == float(f'{min(ratio, conditioning):.3g}')
    assert 0.1 < min(ratio, conditioning) < 0.2
    Robot(l3=0.1, axis_point_a=(0.0, 0.05, 0.0), bar_length=(0.066, 0.1, 0.1))


@pytest.mark.parametrize('module', [
    'feedforward', 'simulator', 'tracking_controller',
    'mechanism_state_publisher', 'planner'])
def test_every_node_refuses_legs_that_do_not_assemble(module):
    table = importlib.import_module(f'orthoglide_ros.cores.{module}').PARAMETERS
    assert table.robot
    values = {**table.defaults(), 'robot.l3': 0.1,
              'robot.bar_length': [0.05, 0.1, 0.1],
              'robot.axis_point_a': [0.0, 0.08, 0.0]}
    with pytest.raises(ParameterError) as error:
        table.parse(values)
    assert error.value.name == 'robot.bar_length'
    built = table.parse({**table.defaults(), **{
        f'robot.{name}': [float(v) for v in value]
        for name, value in BUILT_VALUES.items()}})
    assert built.robot == Robot(**BUILT_VALUES)
