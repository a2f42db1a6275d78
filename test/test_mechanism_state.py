"""
Tests of the mechanism state publisher's ROS-free logic (mechanism_state).

The joint state of the sliders is checked against eq. (9) and its
derivative written independently (the reference model, complex step), by
name, on the paper's robot and on two robots as built; the rules (matching
by name, optional velocities, refusals counted by reason, the status rules)
are driven by hand, time included.
"""

from mechanics_reference import COMPLEX_STEP, leg_geometry
import numpy as np
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.mechanism_state_publisher import (
    joint_state, MechanismState, PARAMETERS, REASONS)
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.cores.status import ERROR, OK, WARN
from orthoglide_testing.robots_as_built import BUILT, FAR
import pytest

NAMES = ('slider_a', 'slider_b', 'slider_c')
NAN = float('nan')
STAMP = (7, 5)     # a joint state's stamp: the output carries it
PASSIVE = {'phi21': ('phi21', 'phi54'), 'phi32': ('phi32', 'phi62', 'phi43')}
# Each leg's geometry: the drawing's, and two robots as built.
GEOMETRIES = {'drawing': {}, 'built': BUILT, 'far': FAR}


def expected(robot, position, velocity):
    """Every joint's value and rate by name, from the reference model."""
    step = np.asarray(position, complex) + 1j * COMPLEX_STEP * np.asarray(
        velocity, float)
    values, rates = {}, {}
    for leg, slider in zip('ABC', NAMES):
        g = leg_geometry(robot, leg, step)
        for key, value in (('lambda', g.lam), ('phi21', np.arcsin(g.sin21)),
                           ('phi32', np.arcsin(g.sin32))):
            names = [slider] if key == 'lambda' else [
                f'{leg.lower()}_{j}' for j in PASSIVE[key]]
            for name in names:
                values[name] = value.real
                rates[name] = value.imag / COMPLEX_STEP
    return values, rates


def by_name(state):
    return (dict(zip(state.names, state.position)),
            dict(zip(state.names, state.velocity)))


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_joint_state_of_the_paper_trajectory_is_eq9_and_its_rates(geometry):
    robot = Robot(**GEOMETRIES[geometry])
    times = trajectory.paper_times(21)
    for p, v, a in zip(*trajectory.paper_batch(times)):
        s = mechanics.solve(robot, p, v, a)
        state = joint_state(robot, NAMES, s.lambda_, s.lambdadot)
        assert len(state.names) == len(set(state.names)) == 18
        values, rates = by_name(state)
        want_values, want_rates = expected(robot, p, v)
        assert values.keys() == want_values.keys()
        for name in values:
            assert values[name] == pytest.approx(want_values[name], abs=1e-12)
            assert rates[name] == pytest.approx(want_rates[name], abs=1e-11)
        # The sliders are the input's, unchanged.
        assert state.position[:3] == tuple(s.lambda_)
        assert state.velocity[:3] == tuple(s.lambdadot)


def test_without_velocities_no_rates():
    state = joint_state(Robot(), NAMES, (0.01, 0.02, -0.03))
    assert state.velocity == () and len(state.position) == 18


@pytest.mark.parametrize('lam, reason', [
    ((1.7, 1.7, 1.7), 'unreachable'),
    ((0.736529, 0.736529, 0.736529), 'singular'),  # G at 0.45 (1, 1, 1)
    ((0.0, NAN, 0.0), 'non_finite'),
])
def test_joint_state_refusals(lam, reason):
    with pytest.raises(mechanics.WorkspaceError) as error:
        joint_state(Robot(), NAMES, lam)
    assert error.value.reason == reason


def core(**changes):
    return MechanismState(PARAMETERS.parse(changes), now=0.0)


def solved_joints(c, names, position, velocity, now):
    """Hand ``c`` one JointState's fields; return the joints it solved."""
    stamp, frame, state = c.joint_state(STAMP, 'base_link', names, position,
                                        velocity, (), now)
    assert (stamp, frame) == (STAMP, 'base_link')     # passed on unchanged
    return state


def test_names_in_any_order_extras_ignored_efforts_unused():
    c = core(joint_names=['x', 'y', 'z'])
    lam = mechanics.solve(Robot(), (0.05, 0.1, -0.2)).lambda_
    state = solved_joints(c, ['other', 'z', 'x', 'y'],
                          [9.0, lam[2], lam[0], lam[1]], [], 1.0)
    assert state.names[:3] == ('x', 'y', 'z')
    assert state.position[:3] == tuple(lam)
    assert state.velocity == ()
    assert c.published == 1 and c.received == {'joint_states': 1}


@pytest.mark.parametrize('names, position, velocity, reason', [
    (['slider_a', 'slider_b'], [0.0, 0.0], [], 'missing_joint'),
    (list(NAMES) + ['slider_a'], [0.0] * 4, [], 'malformed'),
    (list(NAMES), [0.0, 0.0], [], 'malformed'),
    (list(NAMES), [0.0] * 3, [0.0] * 2, 'malformed'),
    (list(NAMES), [], [], 'missing_position'),
    (list(NAMES), [0.0, NAN, 0.0], [], 'non_finite'),
    (list(NAMES), [0.0] * 3, [0.0, 0.0, float('inf')], 'non_finite'),
    (list(NAMES), [1.7, 1.7, 1.7], [], 'unreachable'),
    (list(NAMES), [0.736529] * 3, [], 'singular'),
])
def test_rejections_are_counted_by_reason(names, position, velocity, reason):
    c = core()
    with pytest.raises(Rejected) as error:
        solved_joints(c, names, position, velocity, 1.0)
    assert error.value.reason == reason
    assert c.rejected[reason] == 1 and sum(c.rejected.values()) == 1
    assert c.published == 0 and c.latest is None
    assert set(c.rejected) == set(REASONS)


def test_margin_parameter_decides_singular():
    lam = mechanics.solve(Robot(), (0.3, 0.3, 0.3), margin=0.0).lambda_
    distance = mechanics.solve(Robot(), (0.3, 0.3, 0.3),
                               margin=0.0).singularity_distance
    strict = core(singularity_margin=min(0.99, distance + 0.05))
    with pytest.raises(Rejected):
        solved_joints(strict, list(NAMES), lam, [], 0.0)
    loose = core(singularity_margin=max(0.0, distance - 0.05))
    assert solved_joints(loose, list(NAMES), lam, [], 0.0)


def test_configure_takes_new_names():
    c = core()
    c.configure(PARAMETERS.parse({'joint_names': ['p', 'q', 'r']}))
    with pytest.raises(Rejected):
        solved_joints(c, list(NAMES), [0.0] * 3, [], 0.0)
    names = solved_joints(c, ['p', 'q', 'r'], [0.0] * 3, [], 0.0).names
    assert names[0] == 'p'


def test_status_rules():
    c = core()
    assert c.status(1.0).level == OK
    assert c.status(1.0).message == 'waiting for joint states'
    solved_joints(c, list(NAMES), [0.0] * 3, [], 1.5)
    status = c.status(2.0)
    assert (status.level, status.message) == (OK, 'ok')
    values = dict(status.values)
    assert values['joint states published'] == 1
    assert values['publish rate (Hz)'] == pytest.approx(1.0)
    with pytest.raises(Rejected):
        solved_joints(c, ['x'], [0.0], [], 2.5)
    status = c.status(3.0)
    assert status.level == WARN and 'missing_joint' in status.message
    assert dict(status.values)['rejected missing_joint'] == 1
    assert c.status(4.0).level == OK        # a new period without rejections
    assert c.status(5.0, internal_errors=2).level == ERROR
    assert dict(c.status(6.0).values)['legs'] == 'as drawn'


def test_status_says_a_robot_as_built():
    """The installed URDF is the drawing's: the value says which robot."""
    c = core(**{f'robot.{name}': list(value) for name, value in BUILT.items()})
    assert dict(c.status(1.0).values)['legs'] == 'as built'
    c.configure(PARAMETERS.parse({}))
    assert dict(c.status(2.0).values)['legs'] == 'as drawn'


def test_rejected_before_reading_counts():
    c = core()
    assert c.reject('joint_states', Rejected('oversize', 'too long')) is None
    assert c.rejected['oversize'] == 1 and c.received == {'joint_states': 1}
