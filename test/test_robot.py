"""
``Robot`` validates every parameter once and names the one it refuses.

Lengths and masses must be finite positive numbers, ``alpha`` must lie in
(0, pi/2) rad and ``gravity`` must be a finite 3-vector of numbers; each
bad value raises ``ParameterError`` whose ``name`` and message name the
parameter (``robot.l3``). ``m4`` and ``m6`` default to ``m2`` and ``m3`` (the paper's
``m4 = m2``, ``m6 = m3``), ``friction_coulomb_negative`` to
``friction_coulomb``, and keep following them through ``replace``. The
friction coefficients are 3-vectors of finite values >= 0 and
``friction_velocity`` and ``friction_stribeck_velocity`` positive speeds.
The defaults are the paper's robot (section 2), without friction.
"""

import dataclasses
import math

import numpy as np
from orthoglide_ros.model.robot import ParameterError, Robot, ROW, ROWS
import pytest

POSITIVE = ('l', 'l1', 'l2', 'l3', 'alpha', 'm1', 'm2', 'm3', 'm4', 'm5',
            'm6', 'friction_velocity', 'friction_stribeck_velocity')
FRICTION = ('friction_viscous', 'friction_coulomb',
            'friction_coulomb_negative', 'friction_stribeck')
RIPPLE = ('ripple_sine', 'screw_lead', 'ripple_cosine')
GEOMETRY = ('axis_point_a', 'axis_point_b', 'axis_point_c',
            'axis_direction_a', 'axis_direction_b', 'axis_direction_c',
            'joint_offset', 'bar_length',
            'attachment_a', 'attachment_b', 'attachment_c')
BAD_NUMBERS = (0.0, -0.1, -math.inf, math.inf, math.nan, '0.2', None,
               True, [0.2])


def refused(name, **values):
    with pytest.raises(ParameterError) as error:
        Robot(**values)
    assert error.value.name == f'robot.{name}'
    assert f'robot.{name}' in str(error.value)
    return error.value


def test_defaults_are_the_paper_robot():
    robot = Robot()
    paper = {'l': 0.20, 'l1': 0.15, 'l2': 0.08, 'l3': 0.85,
             'alpha': math.pi / 4, 'm1': 0.35, 'm2': 0.2, 'm3': 2.5,
             'm4': 0.2, 'm5': 15.0, 'm6': 2.5}
    for name, value in paper.items():
        assert getattr(robot, name) == value, name
    assert robot.gravity == (0.0, 0.0, -9.81)
    for name in FRICTION:
        assert getattr(robot, name) == (0.0,) * 3, name
    assert not robot.has_friction
    assert robot.active_terms == ()


@pytest.mark.parametrize('name, value', [
    (name, value) for name in POSITIVE for value in BAD_NUMBERS
    # None means "the default" for m4 and m6.
    if not (value is None and ROW[name].follows)], ids=repr)
def test_each_bad_value_is_refused_with_its_name(name, value):
    refused(name, **{name: value})


@pytest.mark.parametrize('value', [math.pi / 2, 2.0, 3 * math.pi / 4])
def test_alpha_below_a_right_angle(value):
    error = refused('alpha', alpha=value)
    assert 'pi/2' in str(error)


@pytest.mark.parametrize('value', [
    (0.0, 0.0), (0.0, 0.0, -9.81, 0.0), 9.81, 'down', (0.0, 0.0, 'x'),
    (0.0, 0.0, math.nan), (math.inf, 0.0, 0.0), (0.0, True, -9.81),
    None])
def test_gravity_must_be_a_finite_3_vector(value):
    refused('gravity', gravity=value)


def test_gravity_accepts_finite_3_sequences_and_stores_floats():
    robot = Robot(gravity=np.array([1.0, 2.0, -3.0]))
    assert robot.gravity == (1.0, 2.0, -3.0)
    assert all(type(g) is float for g in robot.gravity)
    assert Robot(gravity=[0, 0, 0]).gravity == (0.0, 0.0, 0.0)


@pytest.mark.parametrize('values, shown', [
    ({'joint_offset': (np.float64(0.2), 0.0, 0.0)}, 'got (0.2, 0.0, 0.0)'),
    ({'joint_offset': np.array([0.0, -0.25, 0.0])}, 'got [0.0, -0.25, 0.0]'),
    ({'l3': np.float64(-1.0)}, 'got -1.0'),
    ({'gravity': (np.float64(math.inf), 0.0, 0.0)}, 'got (inf, 0.0, 0.0)'),
    ({'axis_direction_a': (np.float64(0.5), 0.0, 0.0)}, 'got (0.5, 0.0, 0.0)'),
], ids=repr)
def test_a_refusal_shows_numpy_numbers_as_numbers(values, shown):
    error = refused(next(iter(values)), **values)
    assert shown in str(error) and 'np.' not in str(error)


@pytest.mark.parametrize('name', FRICTION)
@pytest.mark.parametrize('value', [
    (0.0, -1e-9, 0.0), (0.0, 0.0), (1.0, 2.0, 3.0, 4.0), 5.0, None,
    (0.0, math.inf, 0.0), (math.nan, 0.0, 0.0), (0.0, 0.0, True),
    (0.0, '1', 0.0), (2e6, 0.0, 0.0)], ids=repr)
def test_friction_coefficients_are_three_finite_values_at_least_zero(
        name, value):
    if value is None and ROW[name].follows:
        return      # None: the default, the value it follows
    refused(name, **{name: value})


def test_friction_is_kept_as_floats_and_flagged():
    robot = Robot(friction_viscous=[0, 2, 0], friction_coulomb=(0.5, 0, 0),
                  friction_velocity=0.002)
    assert robot.friction_viscous == (0.0, 2.0, 0.0)
    assert all(type(c) is float for c in robot.friction_viscous)
    assert robot.friction_coulomb == (0.5, 0.0, 0.0)
    assert robot.has_friction
    assert Robot(friction_coulomb=(0.0, 0.0, 1e-3)).has_friction


def test_m4_and_m6_default_to_m2_and_m3():
    robot = Robot(m2=0.4, m3=3.5)
    assert robot.m4 == 0.4
    assert robot.m6 == 3.5
    robot = Robot(m2=0.4, m3=3.5, m4=0.7, m6=1.1)
    assert (robot.m4, robot.m6) == (0.7, 1.1)


def test_coulomb_friction_is_the_same_both_ways_unless_set_apart():
    robot = Robot(friction_coulomb=(5.0, 3.0, 4.0))
    assert robot.friction_coulomb_negative == (5.0, 3.0, 4.0)
    assert term_names(robot) == ['coulomb']
    apart = robot.replace(friction_coulomb_negative=(6.0, 3.0, 2.0))
    assert apart.friction_coulomb == (5.0, 3.0, 4.0)
    assert term_names(apart) == ['coulomb', 'direction'] \
        and apart.has_friction
    assert term_names(Robot(friction_stribeck=(0.0, 1.0, 0.0))) == \
        ['stribeck']
    assert Robot(friction_stribeck=(0.0, 1.0, 0.0)).has_friction


def term_names(robot):
    """Return the names of the terms whose force ``robot`` has."""
    return [term.name for term in robot.active_terms]


def test_replace_keeps_a_follower_following():
    assert Robot().replace(m2=0.3).m4 == 0.3
    assert Robot(m4=0.5).replace(m2=0.3).m4 == 0.5
    assert Robot(m4=0.2).replace(m2=0.3).m4 == 0.2     # given: it stays
    robot = Robot().replace(friction_coulomb=(1.0, 2.0, 3.0))
    assert robot.friction_coulomb_negative == (1.0, 2.0, 3.0)
    apart = Robot(friction_coulomb=(1.0, 1.0, 1.0),
                  friction_coulomb_negative=(2.0, 2.0, 2.0))
    assert apart.replace(friction_coulomb=(0.0, 0.0, 0.0)) \
        .friction_coulomb_negative == (2.0, 2.0, 2.0)


def test_frictionless_removes_every_friction_force():
    robot = Robot(m5=18.0, friction_viscous=(1.0, 2.0, 3.0),
                  friction_coulomb=(1.0, 1.0, 1.0),
                  friction_coulomb_negative=(2.0, 2.0, 2.0),
                  friction_stribeck=(3.0, 3.0, 3.0))
    bare = robot.frictionless()
    assert not bare.has_friction
    assert bare.m5 == 18.0 and bare == Robot(m5=18.0)


def test_robot_is_frozen_and_replace_validates():
    robot = Robot()
    with pytest.raises(dataclasses.FrozenInstanceError):
        robot.l3 = 1.0
    changed = robot.replace(l3=0.9, gravity=(0.0, -9.81, 0.0))
    assert changed.l3 == 0.9 and changed.gravity == (0.0, -9.81, 0.0)
    assert robot.l3 == 0.85
    with pytest.raises(ParameterError) as error:
        robot.replace(m5=-1.0)
    assert error.value.name == 'robot.m5'


@pytest.mark.parametrize('name,value', [
    ('armature', (-0.1, 0.0, 0.0)), ('armature', (0.0, math.nan, 0.0)),
    ('armature', (0.0, 0.0)), ('armature', (2e6, 0.0, 0.0)),
    ('payload', -1.0), ('payload', math.inf), ('payload', 2e6),
    ('payload', '5'), ('payload', True)])
def test_a_drive_or_payload_no_robot_has_is_refused(name, value):
    refused(name, **{name: value})


def test_no_drives_and_no_payload_by_default_zero_allowed():
    robot = Robot()
    assert robot.armature == (0.0, 0.0, 0.0) and robot.payload == 0.0
    assert Robot(payload=0, armature=(0, 1, 2)).armature == (0.0, 1.0, 2.0)


def test_equal_values_make_equal_robots():
    assert Robot() == Robot(m4=0.2, m6=2.5)
    assert Robot() != Robot(m5=15.5)


def test_parameter_names_and_values_round_trip():
    robot = Robot(m4=0.3, gravity=(1.0, 2.0, 3.0),
                  friction_viscous=(1.0, 2.0, 3.0),
                  friction_coulomb=(4.0, 5.0, 6.0), friction_velocity=0.02,
                  friction_coulomb_negative=(7.0, 8.0, 9.0),
                  friction_stribeck=(1.5, 2.5, 3.5),
                  friction_stribeck_velocity=0.005, armature=(3.2, 1.0, 0.0),
                  screw_lead=(0.005, 0.01, 0.0), ripple_sine=(0.5, -0.2, 0.0),
                  ripple_cosine=(-0.3, 0.0, 0.0), payload=2.5,
                  joint_offset=(1e-3, 0.0, -2e-4),
                  axis_direction_c=(0.001, 0.0, 1.0))
    assert set(Robot.parameter_names()) == set(POSITIVE) | {'gravity'} \
        | set(GEOMETRY) | set(FRICTION) | {'armature', 'payload'} \
        | set(RIPPLE)
    assert Robot(**robot.as_parameters()) == robot
    assert robot.replace() == robot
    assert robot.replace(m5=16.0).friction_coulomb == (4.0, 5.0, 6.0)
    values = robot.as_parameters()
    assert values['friction_viscous'] == [1.0, 2.0, 3.0]
    assert type(values['friction_velocity']) is float


def test_the_fields_are_the_rows_in_their_order_with_their_defaults():
    """One home: every field of Robot is a row of ROWS, default and all."""
    assert Robot.parameter_names() == tuple(row.name for row in ROWS)
    for field in dataclasses.fields(Robot):
        assert field.default == ROW[field.name].default, field.name
