"""
Whole Cartesian trajectories into joint trajectories, without DDS.

``feedforward.convert_trajectory`` turns every point of a
MultiDOFJointTrajectory into lambda, lambdadot, lambdaddot and f with
``mechanics.solve_batch``, all or nothing: each refusal names its reason
and the index of the first point at fault, and changes nothing.
"""

import math
import time

import numpy as np
import pytest

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.formats.cdr import Waypoints
from orthoglide_ros.cores.feedforward import (convert_trajectory, Feedforward,
                                              PARAMETERS, TRAJECTORY_REASONS)
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import joint_limit_values

INF = math.inf


def settings(**changes):
    values = PARAMETERS.defaults()
    values.update(changes)
    return PARAMETERS.parse(values)


def paper(n=201, stamp=(7, 5), frame='base_link'):
    """Return the paper's trajectory in n points over 2 s, as Waypoints."""
    times = trajectory.paper_times(n)
    p, v, a = trajectory.paper_batch(times)
    ns = np.round(times * 1e9).astype(np.int64)
    return Waypoints(stamp, frame, np.ones(n, bool), np.ones(n, bool),
                     np.ones(n, bool), p, np.tile([0.0, 0.0, 0.0, 1.0],
                                                  (n, 1)),
                     v, a, np.column_stack(divmod(ns, 10**9)))


def changed(w, **fields):
    """Return a copy of ``w`` with fields replaced (arrays copied)."""
    return w._replace(**{k: v for k, v in fields.items()})


def refused(reason, w, index=None, **changes):
    with pytest.raises(Rejected) as info:
        convert_trajectory(settings(**changes), w)
    assert info.value.reason == reason
    if index is not None:
        assert f'point {index}' in str(info.value), str(info.value)
    return info.value


def test_every_point_equals_solve_batch():
    w = paper()
    out = convert_trajectory(settings(), w)
    expected = mechanics.solve_batch(mechanics_robot(), w.position,
                                     w.linear_velocity,
                                     w.linear_acceleration)
    for got, want in zip(out.solution, expected):
        assert np.array_equal(got, want)
    assert out.stamp == (7, 5) and out.frame == 'base_link'
    assert np.array_equal(out.time, w.time)


def test_friction_is_in_the_effort():
    """
    With friction parameters the effort is the rigid force plus friction.

    Checked against the frictionless conversion plus c lambdadot + F
    tanh(lambdadot / v_s) computed here (the tanh law).
    """
    w = paper()
    c, f, vs = [30.0, 40.0, 50.0], [5.0, 3.0, 4.0], 0.002
    rough = convert_trajectory(settings(**{
        'robot.friction_viscous': c, 'robot.friction_coulomb': f,
        'robot.friction_velocity': vs}), w).solution
    rigid = convert_trajectory(settings(), w).solution
    rate = rigid.lambdadot
    expected = rigid.force + np.array(c) * rate + np.array(f) * np.tanh(
        rate / vs)
    assert np.allclose(rough.force, expected, rtol=1e-12, atol=1e-9)
    assert np.abs(rough.force - rigid.force).max() > 5.0
    for name in ('lambda_', 'lambdadot', 'lambdaddot'):
        assert np.array_equal(getattr(rough, name), getattr(rigid, name))


def mechanics_robot():
    return settings().robot


def test_one_point_and_zero_stamp_pass_unchanged():
    w = paper(2)
    one = w._replace(**{name: getattr(w, name)[:1] for name in (
        'transform', 'velocity', 'acceleration', 'position', 'orientation',
        'linear_velocity', 'linear_acceleration', 'time')}, stamp=(0, 0))
    out = convert_trajectory(settings(), one)
    assert out.stamp == (0, 0) and len(out.time) == 1


def test_refusals_name_the_reason_and_the_first_point():
    w = paper(10)
    empty = w._replace(**{name: getattr(w, name)[:0] for name in (
        'transform', 'velocity', 'acceleration', 'position', 'orientation',
        'linear_velocity', 'linear_acceleration', 'time')})
    refused('empty', empty)
    refused('frame', w._replace(frame='world'))
    refused('stamp', w._replace(stamp=(3, 10**9)))
    refused('stamp', w._replace(stamp=(-1, 0)))
    no_transform = w.transform.copy()
    no_transform[4] = False
    refused('malformed', w._replace(transform=no_transform), 4)
    no_velocity = w.velocity.copy()
    no_velocity[6] = False
    bad = w._replace(velocity=no_velocity,
                     linear_velocity=np.where(no_velocity[:, None],
                                              w.linear_velocity, np.nan))
    refused('malformed', bad, 6)
    times = w.time.copy()
    times[3] = times[2]
    refused('time', w._replace(time=times), 3)
    times = w.time.copy()
    times[5, 1] = 10**9
    refused('time', w._replace(time=times), 5)
    rotated = w.orientation.copy()
    rotated[7] = (math.sin(0.01), 0.0, 0.0, math.cos(0.01))
    refused('orientation', w._replace(orientation=rotated), 7)
    position = w.position.copy()
    position[8] = (0.9, 0.0, 0.0)
    refused('unreachable', w._replace(position=position), 8)
    position[8] = (0.84, 0.0, 0.0)
    refused('singular', w._replace(position=position), 8)
    position[8] = (math.nan, 0.0, 0.0)
    refused('non_finite', w._replace(position=position), 8)


def test_pose_only_takes_missing_rates_as_zero():
    w = paper(5)
    none = np.zeros(5, bool)
    bare = w._replace(velocity=none, acceleration=none,
                      linear_velocity=np.full((5, 3), np.nan),
                      linear_acceleration=np.full((5, 3), np.nan))
    out = convert_trajectory(settings(pose_only=True), bare)
    still = mechanics.solve_batch(mechanics_robot(), w.position)
    assert np.array_equal(out.solution.force, still.force)
    refused('malformed', bare, 0)


def limits(key, values):
    """Return the parameters of joint limit ``key``: ``values`` on A, B, C."""
    return joint_limit_values(key, [float(v) for v in values])


def test_limits_refuse_with_point_actuator_and_value():
    w = paper()
    out = convert_trajectory(settings(), w)
    speed = np.abs(out.solution.lambdadot).max(0)
    force = np.abs(out.solution.force).max(0)
    assert convert_trajectory(
        settings(**limits('max_velocity', speed * 1.01)), w)
    error = refused('velocity_limit', w, **limits(
        'max_velocity', [INF, INF, speed[2] * 0.99]))
    row = int(np.argmax(np.abs(out.solution.lambdadot[:, 2])
                        > speed[2] * 0.99))
    assert f'point {row}: actuator C' in str(error)
    assert 'joint_limits.slider_c.max_velocity' in str(error)
    error = refused('force_limit', w,
                    **limits('max_effort', [INF, INF, 200.0]))
    assert 'actuator C' in str(error)
    assert 'joint_limits.slider_c.max_effort 200 N' in str(error)
    assert convert_trajectory(settings(**limits('max_effort', force + 1.0)),
                              w)


def test_absurd_points_refused_and_no_force_beyond_max_effort():
    """
    A point accelerating at 1e200 m/s^2 (2.45e201 N) is refused.

    Refused by the plausibility bounds, naming the point; the default
    max_effort (10 kN) bounds every published effort.
    """
    w = paper()
    for field, reason in (('linear_acceleration', 'acceleration_limit'),
                          ('linear_velocity', 'speed_limit')):
        values = getattr(w, field).copy()
        values[17] = (0.0, 0.0, 1e200)
        error = refused(reason, changed(w, **{field: values}), 17)
        assert 'max_' in str(error)
    force = np.abs(convert_trajectory(settings(), w).solution.force).max()
    refused('force_limit', w, **limits('max_effort', [force * 0.99] * 3))
    assert convert_trajectory(
        settings(**limits('max_effort', [force * 1.01] * 3)), w)


def test_core_counts_trajectories_apart_from_setpoints():
    core = Feedforward(settings())
    conversion = convert_trajectory(settings(), paper(50))
    # Arrived 4 ms ago: the time to publication counts from the arrival.
    assert core.cartesian_trajectory(conversion, b'bytes',
                                     time.monotonic() - 0.004) == b'bytes'
    core.reject('cartesian_trajectory', Rejected('time', 'point 3 ...'))
    assert (core.trajectories, core.trajectory_points) == (1, 50)
    assert core.trajectory_rejected['time'] == 1
    assert not any(core.rejected.values())
    values = dict(core.status(1.0).values)
    assert values['rejected trajectory time'] == 1
    assert 4.0 <= values['trajectory receive to publish max (ms)'] < 1000.0
    assert dict(core.status(2.0).values)[
        'trajectory receive to publish max (ms)'] == 0.0
    assert set(TRAJECTORY_REASONS) <= {
        k.split()[-1] for k in values if k.startswith('rejected trajectory')}
