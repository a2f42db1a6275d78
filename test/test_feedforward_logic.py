"""
Tests of the feedforward's ROS-free logic (orthoglide_ros.cores.feedforward).

Time is driven by hand: every call takes ``now`` (s, monotonic). Every
output is compared with :func:`mechanics.solve` exactly (``==``), since the
core must hand over the mechanics' numbers untouched.
"""

import itertools
import math

import pytest

from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.feedforward import (Feedforward, INPUTS, MAX_PENDING,
                                              PARAMETERS, REASONS)
from orthoglide_ros.cores.setpoint_rules import ORIENTATION_TOLERANCE
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import (field, joint_limit_values,
                                             ROBOT_SPECS)
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import paper_sample


IDENTITY = (0.0, 0.0, 0.0, 1.0)
ZERO = (0.0, 0.0, 0.0)
NAN = float('nan')
INF = float('inf')
# Three setpoints of eq. (6), distinct in every component.
SAMPLES = [paper_sample(t) for t in (0.4, 1.1, 1.7)]
UNREACHABLE = (0.9, 0.0, 0.0)       # leg B: z^2 + x^2 >= l3^2
NEAR_SINGULAR = (0.84, 0.0, 0.0)    # leg B: alpha/l3 = 0.153 < 0.2
HUGE = {1: (1e160, 1e160, 1e160),   # velocity: its squares overflow
        2: (1e308, 1e308, 1e308)}   # acceleration: times the masses
NEAR_J2 = (0.8, 0.0, 0.0)           # 1/kappa_F(J_lambda) = 0.162


def settings(**changes):
    """Return validated settings: the defaults with ``changes`` (by name)."""
    values = PARAMETERS.defaults()
    values.update(changes)
    return PARAMETERS.parse(values)


def core(**changes):
    """Return a Feedforward on the default settings with ``changes``."""
    return Feedforward(settings(**changes))


def expected(ff, position, velocity=ZERO, acceleration=ZERO):
    """Return mechanics.solve of this setpoint with ff's settings."""
    s = ff.settings
    return mechanics.solve(s.robot, position, velocity, acceleration,
                           s.singularity_margin)


def send(ff, stamp, position, velocity, acceleration, now, frame='',
         orientation=IDENTITY, order='pta'):
    """Send one setpoint as pose/twist/accel in ``order``; return outputs."""
    outputs = []
    for part in order:
        if part == 'p':
            out = ff.pose(stamp, frame, position, orientation, now)
        elif part == 't':
            out = ff.twist(stamp, frame, velocity, now)
        else:
            out = ff.accel(stamp, frame, acceleration, now)
        outputs.append(out)
    return outputs


def complete(ff, stamp, sample, now, **kwargs):
    """Send a full setpoint; return the one output (the last message's)."""
    outputs = send(ff, stamp, *sample, now, **kwargs)
    assert outputs[:-1] == [None] * (len(outputs) - 1)
    return outputs[-1]


def rejected(ff, reason, call):
    """Run ``call``; assert it raises Rejected(reason), counted once."""
    before = dict(ff.rejected)
    latest, arrival = ff.latest, ff.latest_arrival
    with pytest.raises(Rejected) as info:
        call()
    assert info.value.reason == reason
    before[reason] += 1
    assert ff.rejected == before
    assert ff.latest is latest and ff.latest_arrival == arrival
    return info.value


# Pairing ---------------------------------------------------------------------
@pytest.mark.parametrize('order', [''.join(p) for p in
                                   itertools.permutations('pta')])
def test_pairs_by_exact_stamp_in_any_order(order):
    ff = core()
    position, velocity, acceleration = SAMPLES[1]
    outputs = send(ff, (7, 250), position, velocity, acceleration, 3.0,
                   order=order)
    assert outputs[:2] == [None, None]
    out = outputs[2]
    assert out.stamp == (7, 250)
    assert out.solution == expected(ff, position, velocity, acceleration)
    assert ff.latest is out and ff.latest_arrival == 3.0
    assert ff.pending == 0 and ff.computed == 1
    assert ff.received == {'pose': 1, 'twist': 1, 'accel': 1,
                           'trajectory': 0, 'cartesian_trajectory': 0}
    assert not any(ff.rejected.values())


def test_interleaved_stamps_are_never_mixed():
    ff = core()
    (p1, v1, a1), (p2, v2, a2) = SAMPLES[:2]
    s1, s2 = (1, 0), (1, 1)     # one nanosecond apart: still distinct
    assert ff.pose(s1, '', p1, IDENTITY, 0.0) is None
    assert ff.twist(s2, '', v2, 0.001) is None
    assert ff.accel(s1, '', a1, 0.002) is None
    assert ff.pose(s2, '', p2, IDENTITY, 0.003) is None
    assert ff.pending == 2
    out1 = ff.twist(s1, '', v1, 0.004)
    assert out1.stamp == s1
    assert out1.solution == expected(ff, p1, v1, a1)
    assert ff.pending == 1      # s2 is newer: it keeps waiting
    out2 = ff.accel(s2, '', a2, 0.005)
    assert out2.stamp == s2
    assert out2.solution == expected(ff, p2, v2, a2)
    assert ff.pending == 0 and ff.rejected['unpaired'] == 0


def test_older_partials_dropped_when_newer_completes():
    ff = core()
    (p1, v1, a1), (p2, v2, a2), (p3, _, _) = SAMPLES
    ff.pose((1, 0), '', p1, IDENTITY, 0.0)
    ff.twist((1, 0), '', v1, 0.0)
    ff.pose((3, 0), '', p3, IDENTITY, 0.0)     # newer than s2: stays
    out = complete(ff, (2, 0), (p2, v2, a2), 0.001)
    assert out.stamp == (2, 0)
    assert ff.pending == 1 and ff.rejected['unpaired'] == 1
    # The dropped setpoint's last part arrives late: it cannot complete.
    assert ff.accel((1, 0), '', a1, 0.002) is None
    assert ff.latest is out


def test_partial_dropped_after_pairing_timeout():
    ff = core(pairing_timeout=0.05)
    p, v, a = SAMPLES[0]
    ff.pose((1, 0), '', p, IDENTITY, 10.0)
    assert ff.expire(10.04) == 0 and ff.pending == 1
    assert ff.expire(10.06) == 1
    assert ff.pending == 0 and ff.rejected['unpaired'] == 1
    assert ff.expire(20.0) == 0 and ff.rejected['unpaired'] == 1
    # A new stamp also expires the old partials (no timer needed).
    ff.twist((2, 0), '', v, 30.0)
    ff.pose((3, 0), '', p, IDENTITY, 30.1)
    assert ff.pending == 1 and ff.rejected['unpaired'] == 2


def test_partner_after_pairing_timeout_does_not_complete():
    """
    The rule: a partial waits at most pairing_timeout for its partners.

    Its partners arriving later must not complete it, even if nothing else
    (a newer stamp, the diagnostics timer) called expire() in between.
    """
    ff = core(pairing_timeout=0.05)
    p, v, a = SAMPLES[0]
    assert ff.pose((1, 0), '', p, IDENTITY, 0.0) is None
    assert ff.twist((1, 0), '', v, 1.0) is None
    assert ff.accel((1, 0), '', a, 1.0) is None
    assert ff.latest is None
    assert ff.rejected['unpaired'] == 1


def test_pending_is_bounded():
    ff = core()
    p = SAMPLES[0][0]
    for k in range(MAX_PENDING + 1):
        ff.pose((1, k), '', p, IDENTITY, 0.0)
    assert ff.pending == MAX_PENDING
    assert ff.rejected['unpaired'] == 1


def test_duplicate_part_keeps_the_newest():
    ff = core()
    (p1, v1, a1), (p2, _, _) = SAMPLES[:2]
    ff.pose((1, 0), '', p2, IDENTITY, 0.0)
    ff.pose((1, 0), '', p1, IDENTITY, 0.0)
    out = complete(ff, (1, 0), (p1, v1, a1), 0.0, order='ta')
    assert out.solution == expected(ff, p1, v1, a1)


# Stamps and frames -------------------------------------------------------------
@pytest.mark.parametrize('part', 'pta')
def test_zero_stamp_rejected(part):
    ff = core()
    error = rejected(ff, 'stamp',
                     lambda: send(ff, (0, 0), *SAMPLES[0], 0.0, order=part))
    assert 'stamp' in str(error)
    assert ff.pending == 0


def test_negative_stamp_rejected():
    ff = core()
    rejected(ff, 'stamp', lambda: ff.pose((-1, 5), '', ZERO, IDENTITY, 0.0))


def test_zero_stamp_rejected_with_pose_only():
    ff = core(pose_only=True)
    rejected(ff, 'stamp', lambda: ff.pose((0, 0), '', ZERO, IDENTITY, 0.0))


@pytest.mark.parametrize('part', 'pta')
def test_frame_mismatch_rejected(part):
    ff = core()
    good = complete(ff, (1, 0), SAMPLES[0], 0.0, frame='base_link')
    position, velocity, acceleration = SAMPLES[1]
    ff.pose((2, 0), 'world' if part == 'p' else '', position, IDENTITY, 0.1)
    ff.twist((2, 0), 'world' if part == 't' else 'base_link', velocity, 0.1)
    error = rejected(ff, 'frame', lambda: ff.accel(
        (2, 0), 'world' if part == 'a' else '', acceleration, 0.1))
    assert 'world' in str(error) and 'base_link' in str(error)
    assert ff.latest is good and ff.pending == 0


def test_empty_frame_and_custom_base_frame_accepted():
    ff = core(base_frame='orthoglide_base')
    out = complete(ff, (1, 0), SAMPLES[0], 0.0, frame='')
    assert out.solution == expected(ff, *SAMPLES[0])
    out = complete(ff, (2, 0), SAMPLES[1], 0.0, frame='orthoglide_base')
    assert out.solution == expected(ff, *SAMPLES[1])
    rejected(ff, 'frame', lambda: complete(ff, (3, 0), SAMPLES[2], 0.0,
                                           frame='base_link'))


# Orientation -----------------------------------------------------------------
def quaternion(angle, axis=(0.0, 0.0, 1.0)):
    """Rotation of ``angle`` rad about the unit ``axis``: (x, y, z, w)."""
    s = math.sin(angle / 2.0)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2.0))


AXIS = (1.0 / math.sqrt(3.0),) * 3


@pytest.mark.parametrize('q', [
    IDENTITY, (0.0, 0.0, 0.0, -1.0), (0.0, 0.0, 0.0, 2.5),
    quaternion(0.9e-3), quaternion(0.9e-3, AXIS),
    tuple(-c for c in quaternion(0.9e-3, AXIS)),
    quaternion(-0.9e-3, (1.0, 0.0, 0.0)),
], ids=['identity', 'minus_identity', 'unnormalised', 'tiny_z', 'tiny_axis',
        'tiny_minus_q', 'tiny_negative_x'])
def test_orientation_near_identity_accepted(q):
    ff = core()
    out = complete(ff, (1, 0), SAMPLES[1], 0.0, orientation=q)
    assert out.solution == expected(ff, *SAMPLES[1])


@pytest.mark.parametrize('q', [
    quaternion(1.1e-3), quaternion(1.1e-3, AXIS),
    tuple(-c for c in quaternion(1.1e-3, AXIS)),
    quaternion(math.pi / 2, (0.0, 1.0, 0.0)), quaternion(math.pi),
    (0.0, 0.0, 0.0, 0.0),
], ids=['above_z', 'above_axis', 'above_minus_q', 'quarter_turn',
        'half_turn', 'zero'])
def test_orientation_turned_rejected(q):
    ff = core()
    good = complete(ff, (1, 0), SAMPLES[0], 0.0)
    rejected(ff, 'orientation', lambda: complete(
        ff, (2, 0), SAMPLES[1], 0.0, orientation=q))
    assert ff.latest is good
    assert ORIENTATION_TOLERANCE == 1e-3


@pytest.mark.parametrize('q', [(NAN, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, NAN),
                               (0.0, INF, 0.0, 1.0), (0.0, 0.0, 0.0, -INF)])
def test_orientation_not_finite_rejected(q):
    ff = core()
    rejected(ff, 'non_finite', lambda: complete(
        ff, (1, 0), SAMPLES[0], 0.0, orientation=q))


# Mechanics refusals ----------------------------------------------------------
@pytest.mark.parametrize('which', range(3), ids=['position', 'velocity',
                                                 'acceleration'])
@pytest.mark.parametrize('bad', [NAN, INF, -INF], ids=['nan', 'inf', '-inf'])
@pytest.mark.parametrize('axis', range(3), ids='xyz')
def test_non_finite_rejected(which, bad, axis):
    ff = core()
    good = complete(ff, (1, 0), SAMPLES[0], 0.0)
    sample = [list(v) for v in SAMPLES[1]]
    sample[which][axis] = bad
    sample = [tuple(v) for v in sample]
    rejected(ff, 'non_finite', lambda: complete(ff, (2, 0), sample, 0.0))
    assert ff.latest is good and ff.computed == 1


@pytest.mark.parametrize('position, reason', [
    (UNREACHABLE, 'unreachable'), ((0.0, 0.0, -2.0), 'unreachable'),
    (NEAR_SINGULAR, 'singular'), ((0.0, 0.6, 0.6), 'singular')])
def test_workspace_refusals(position, reason):
    ff = core()
    good = complete(ff, (1, 0), SAMPLES[0], 0.0)
    rejected(ff, reason, lambda: complete(ff, (2, 0), (position, ZERO, ZERO),
                                          0.0))
    assert ff.latest is good


def test_singularity_margin_setting_used():
    ff = core(singularity_margin=0.1)
    out = complete(ff, (1, 0), (NEAR_J2, ZERO, ZERO), 0.0)
    assert out.solution == mechanics.solve(ff.settings.robot, NEAR_J2,
                                           ZERO, ZERO, 0.1)
    assert 0.1 <= out.solution.singularity_distance < 0.2
    ff.configure(settings(singularity_margin=0.2))
    rejected(ff, 'singular', lambda: complete(
        ff, (2, 0), (NEAR_J2, ZERO, ZERO), 0.0))
    assert ff.latest is out


@pytest.mark.parametrize('which, reason', [(1, 'speed_limit'),
                                           (2, 'acceleration_limit')],
                         ids=['velocity', 'acceleration'])
def test_absurd_motion_refused_before_the_mechanics(which, reason):
    """Finite but absurd (1e160, 1e200) is refused by its bound."""
    ff = core()
    sample = [SAMPLES[0][0], ZERO, ZERO]
    sample[which] = HUGE[which]
    error = rejected(ff, reason, lambda: complete(ff, (1, 0), sample, 0.0))
    assert ('max_speed' if which == 1 else 'max_acceleration') in str(error)
    assert ff.latest is None and ff.computed == 0


@pytest.mark.parametrize('which, bound', [(1, 'max_speed'),
                                          (2, 'max_acceleration')])
def test_motion_bounds_are_the_parameters(which, bound):
    """Just within the bound passes, just beyond it is refused."""
    ff = core(**{bound: 2.0})
    sample = [SAMPLES[0][0], ZERO, ZERO]
    sample[which] = (0.0, 1.2, 1.6)         # norm 2.0
    assert complete(ff, (1, 0), sample, 0.0) is not None
    sample[which] = (0.0, 1.2, 1.61)
    rejected(ff, 'speed_limit' if which == 1 else 'acceleration_limit',
             lambda: complete(ff, (2, 0), sample, 0.0))


def test_no_force_beyond_max_effort_is_computed():
    """A setpoint whose force exceeds max_effort is refused, not published."""
    position = SAMPLES[0][0]
    largest = max(abs(f) for f in mechanics.solve(Robot(), position).force)
    ff = core(**joint_limit_values('max_effort', largest * 1.001))
    assert complete(ff, (1, 0), (position, ZERO, ZERO), 0.0) is not None
    error = rejected(ff, 'force_limit', lambda: complete(
        ff, (2, 0), (position, ZERO, (0.0, 0.0, 5.0)), 0.0))
    assert 'max_effort' in str(error) and ff.computed == 1


def test_no_slider_faster_than_max_velocity_is_computed():
    """A setpoint whose |lambdadot| exceeds max_velocity is refused."""
    position = SAMPLES[0][0]
    velocity = (0.1, 0.0, 0.0)
    speeds = mechanics.solve(Robot(), position, velocity).lambdadot
    ff = core(**joint_limit_values('max_velocity', [
        abs(speeds[0]) * 1.001, None, None]))
    assert complete(ff, (1, 0), (position, velocity, ZERO), 0.0) is not None
    error = rejected(ff, 'velocity_limit', lambda: complete(
        ff, (2, 0), (position, (0.11, 0.0, 0.0), ZERO), 0.0))
    assert 'joint_limits.slider_a.max_velocity' in str(error)
    assert ff.rejected['velocity_limit'] == 1 and ff.computed == 1


def test_the_retired_limits_name_their_new_key():
    for old, new in (('velocity_limit', 'max_velocity'),
                     ('force_limit', 'max_effort'),
                     ('max_force', 'max_effort')):
        with pytest.raises(ValueError, match=(
                f'^{old}: no longer a parameter; use joint_limits.<joint>.'
                f'{new} ')):
            settings(**{old: [1.0] * 3 if old != 'max_force' else 1.0})


def test_rejection_order_frame_then_orientation_then_mechanics():
    ff = core()
    bad_q = quaternion(0.5)
    rejected(ff, 'frame', lambda: complete(
        ff, (1, 0), (UNREACHABLE, ZERO, ZERO), 0.0, frame='world',
        orientation=bad_q))
    rejected(ff, 'orientation', lambda: complete(
        ff, (2, 0), (UNREACHABLE, ZERO, ZERO), 0.0, orientation=bad_q))
    rejected(ff, 'unreachable', lambda: complete(
        ff, (3, 0), (UNREACHABLE, ZERO, ZERO), 0.0))
    assert ff.pending == 0


# pose_only and trajectory points ---------------------------------------------
def test_pose_only_serves_pose_alone():
    ff = core(pose_only=True)
    position = SAMPLES[1][0]
    assert ff.twist((1, 0), '', SAMPLES[1][1], 0.0) is None
    assert ff.accel((1, 0), '', SAMPLES[1][2], 0.0) is None
    assert ff.pending == 0
    out = ff.pose((1, 0), '', position, IDENTITY, 0.0)
    assert out.stamp == (1, 0)
    assert out.solution == expected(ff, position, ZERO, ZERO)
    assert out.solution.lambdadot == ZERO
    assert ff.received == {'pose': 1, 'twist': 1, 'accel': 1,
                           'trajectory': 0, 'cartesian_trajectory': 0}
    # Checks still apply.
    rejected(ff, 'frame', lambda: ff.pose((2, 0), 'map', position, IDENTITY,
                                          0.0))
    rejected(ff, 'orientation', lambda: ff.pose(
        (3, 0), '', position, quaternion(0.1), 0.0))
    rejected(ff, 'unreachable', lambda: ff.pose(
        (4, 0), '', UNREACHABLE, IDENTITY, 0.0))


def test_trajectory_point_is_one_setpoint():
    ff = core()
    p, v, a = SAMPLES[2]
    out = ff.trajectory_point((4, 5), 'base_link', p, IDENTITY, v, a, 1.0)
    assert out.stamp == (4, 5)
    assert out.solution == expected(ff, p, v, a)
    assert ff.latest is out and ff.received['trajectory'] == 1
    rejected(ff, 'frame', lambda: ff.trajectory_point(
        (5, 0), 'odom', p, IDENTITY, v, a, 1.0))
    rejected(ff, 'orientation', lambda: ff.trajectory_point(
        (5, 0), '', p, quaternion(0.01, (0.0, 1.0, 0.0)), v, a, 1.0))
    rejected(ff, 'non_finite', lambda: ff.trajectory_point(
        (5, 0), '', p, IDENTITY, (NAN, 0.0, 0.0), a, 1.0))


@pytest.mark.parametrize('missing', ['velocity', 'acceleration', 'both'])
def test_trajectory_point_without_velocities_malformed(missing):
    p, v, a = SAMPLES[2]
    v = None if missing in ('velocity', 'both') else v
    a = None if missing in ('acceleration', 'both') else a
    ff = core()
    error = rejected(ff, 'malformed', lambda: ff.trajectory_point(
        (1, 0), '', p, IDENTITY, v, a, 0.0))
    assert 'pose_only' in str(error)
    ff = core(pose_only=True)
    out = ff.trajectory_point((1, 0), '', p, IDENTITY, v, a, 0.0)
    assert out.solution == expected(ff, p, v or ZERO, a or ZERO)


def test_reject_malformed_counts():
    """A message refused before it was read: counted, nothing raised."""
    ff = core()
    assert ff.reject('trajectory', Rejected('malformed', 'empty')) is None
    assert ff.rejected['malformed'] == 1 and ff.received['trajectory'] == 1


# Freshness -------------------------------------------------------------------
def test_fresh_tick_stale_by_arrival_time():
    ff = core(setpoint_timeout=0.5, pairing_timeout=0.05, rate_hz=100.0)
    assert not ff.fresh(0.0) and ff.tick(0.0) is None
    # The stamp is far in the past: freshness ignores it. At a fixed rate
    # a setpoint is published by the ticks, not as it completes.
    assert complete(ff, (1, 0), SAMPLES[0], 100.0) is None
    out = ff.latest
    assert ff.fresh(100.0) and ff.tick(100.0) is out
    assert ff.tick(100.49) is out
    assert ff.tick(100.51) is None and not ff.fresh(100.51)
    # A rejected setpoint does not refresh.
    rejected(ff, 'unreachable', lambda: complete(
        ff, (2, 0), (UNREACHABLE, ZERO, ZERO), 100.6))
    assert ff.tick(100.6) is None
    # A fresh one resumes, with its own stamp, even if older than the last.
    complete(ff, (0, 5), SAMPLES[1], 101.0)
    out2 = ff.latest
    assert ff.tick(101.2) is out2 and out2.stamp == (0, 5)
    assert ff.published == 3     # the ticks that found a fresh result


def test_rejected_setpoint_leaves_latest_unchanged():
    ff = core()
    out = complete(ff, (1, 0), SAMPLES[0], 5.0)
    for stamp, sample, kwargs in [
            ((2, 0), (UNREACHABLE, ZERO, ZERO), {}),
            ((3, 0), SAMPLES[1], {'frame': 'x'}),
            ((4, 0), SAMPLES[1], {'orientation': quaternion(0.2)}),
            ((5, 0), ((NAN, 0.0, 0.0), ZERO, ZERO), {})]:
        with pytest.raises(Rejected):
            complete(ff, stamp, sample, 6.0, **kwargs)
        assert ff.latest is out and ff.latest_arrival == 5.0
    assert ff.computed == 1
    assert sum(ff.rejected.values()) == 4


def test_counters_and_compute_time():
    ff = core()
    for k, t in enumerate((0.1, 0.5, 1.0, 1.5, 2.0)):
        out = complete(ff, (1, k), paper_sample(t), 0.0)
        assert out.solution == expected(ff, *paper_sample(t))
    assert ff.computed == 5
    assert ff.compute_ns_total >= ff.compute_ns_max > 0
    assert set(ff.rejected) == set(REASONS)
    assert set(ff.received) == set(INPUTS)


def test_configure_takes_effect_for_next_setpoint():
    ff = core()
    first = complete(ff, (1, 0), SAMPLES[0], 0.0)
    robot = Robot(m5=18.0, gravity=(0.0, 0.0, -9.0))
    ff.configure(settings(**{'robot.m5': 18.0,
                             'robot.gravity': [0.0, 0.0, -9.0]}))
    assert ff.settings.robot == robot
    assert ff.latest is first
    out = complete(ff, (2, 0), SAMPLES[0], 0.0)
    assert out.solution == mechanics.solve(robot, *SAMPLES[0])
    assert out.solution.force != first.solution.force


def test_a_payload_set_at_run_time_is_a_heavier_platform_next_setpoint():
    ff = core()
    first = complete(ff, (1, 0), SAMPLES[0], 0.0)
    ff.configure(settings(**{'robot.payload': 5.0}))
    out = complete(ff, (2, 0), SAMPLES[0], 0.0)
    assert out.solution == mechanics.solve(Robot(m5=Robot().m5 + 5.0),
                                           *SAMPLES[0])
    assert first.solution == mechanics.solve(Robot(), *SAMPLES[0])
    shown = dict(ff.status(1.0).values)
    assert shown['payload (kg)'] == 5.0


# Settings --------------------------------------------------------------------
def test_default_settings():
    s = PARAMETERS.parse(PARAMETERS.defaults())
    limits = {}
    for joint in ('slider_a', 'slider_b', 'slider_c'):
        limits.update({f'joint_limits__{joint}__has_velocity_limits': False,
                       f'joint_limits__{joint}__max_velocity': 0.0,
                       f'joint_limits__{joint}__has_effort_limits': True,
                       f'joint_limits__{joint}__max_effort': 10000.0})
    assert s == PARAMETERS.Settings(
        robot=Robot(), joint_names=('slider_a', 'slider_b', 'slider_c'),
        base_frame='base_link', rate_hz=0.0, setpoint_timeout=0.1,
        pairing_timeout=0.05,
        singularity_margin=mechanics.DEFAULT_SINGULARITY_MARGIN,
        pose_only=False, max_speed=5.0, max_acceleration=100.0, **limits,
        thread_priority=0, cpu_affinity=(), lock_memory=False)
    assert PARAMETERS.parse({}) == s
    assert s.robot.m4 == s.robot.m2 and s.robot.m6 == s.robot.m3


def test_spec_table():
    names = [spec.name for spec in PARAMETERS.specs]
    assert len(names) == len(set(names))
    assert [s.name for s in ROBOT_SPECS] == [
        'robot.' + n for n in Robot.parameter_names()]
    assert {field(s.name) for s in PARAMETERS.own_specs} == \
        set(PARAMETERS.Settings._fields) - {'robot'}
    for spec in PARAMETERS.specs:
        assert spec.type in ('double', 'double_array', 'integer',
                             'integer_array', 'string', 'string_array',
                             'bool')
        assert spec.description
    assert 'robot.m4' not in PARAMETERS.defaults()
    assert 'robot.m6' not in PARAMETERS.defaults()


def test_robot_parameters_used():
    s = settings(**{'robot.l3': 0.9, 'robot.m4': 0.3, 'robot.m6': None,
                    'robot.gravity': [0.0, -9.81, 0.0]})
    assert s.robot == Robot(l3=0.9, m4=0.3, gravity=(0.0, -9.81, 0.0))


def test_friction_parameters_reach_the_forces_and_powers():
    """robot.friction_*: the law of doc/model.md on every output."""
    friction = {'robot.friction_viscous': [30.0, 40.0, 50.0],
                'robot.friction_coulomb': [5.0, 3.0, 4.0],
                'robot.friction_velocity': 0.002}
    ff = core(**friction)
    assert ff.settings.robot == Robot(friction_viscous=(30.0, 40.0, 50.0),
                                      friction_coulomb=(5.0, 3.0, 4.0),
                                      friction_velocity=0.002)
    out = complete(ff, (7, 250), SAMPLES[1], 3.0)
    rigid = mechanics.solve(Robot(), *SAMPLES[1])
    for j in range(3):
        law = (friction['robot.friction_viscous'][j] * rigid.lambdadot[j]
               + friction['robot.friction_coulomb'][j] * math.tanh(
                   rigid.lambdadot[j] / 0.002))
        assert out.solution.force[j] == pytest.approx(
            rigid.force[j] + law, rel=1e-12, abs=1e-9)
        assert out.solution.power[j] == pytest.approx(
            rigid.lambdadot[j] * (rigid.force[j] + law), rel=1e-12)
    assert PARAMETERS.defaults()['robot.friction_velocity'] == 0.001


def test_direction_and_stribeck_parameters_reach_the_forces():
    """robot.friction_coulomb_negative and the Stribeck term: the law."""
    friction = {'robot.friction_coulomb': [5.0, 3.0, 4.0],
                'robot.friction_coulomb_negative': [8.0, 1.0, 6.0],
                'robot.friction_stribeck': [2.0, 4.0, 0.0],
                'robot.friction_stribeck_velocity': 0.05}
    ff = core(**friction)
    assert ff.settings.robot.friction_coulomb_negative == (8.0, 1.0, 6.0)
    out = complete(ff, (7, 250), SAMPLES[1], 3.0)
    rigid = mechanics.solve(Robot(), *SAMPLES[1])
    for j, v in enumerate(rigid.lambdadot):
        level = friction['robot.friction_coulomb' if v > 0
                         else 'robot.friction_coulomb_negative'][j]
        law = (level + friction['robot.friction_stribeck'][j]
               * math.exp(-(v / 0.05) ** 2)) * math.tanh(v / 0.001)
        assert out.solution.force[j] == pytest.approx(
            rigid.force[j] + law, rel=1e-12, abs=1e-9)
    assert 'robot.friction_coulomb_negative' not in PARAMETERS.defaults()
    assert PARAMETERS.defaults()['robot.friction_stribeck'] == [0.0] * 3


@pytest.mark.parametrize('changes', [
    {'rate_hz': 0.0}, {'rate_hz': 10000.0}, {'setpoint_timeout': 0.001,
                                             'pairing_timeout': 0.001},
    {'setpoint_timeout': 3600.0, 'pairing_timeout': 3600.0},
    {'pairing_timeout': 0.0001}, {'singularity_margin': 0.0},
    {'singularity_margin': 0.99}, {'pose_only': True},
    {'joint_names': ('a', 'b', 'c')}, {'base_frame': ''},
], ids=lambda c: '-'.join(f'{k}={v}' for k, v in c.items()))
def test_valid_settings(changes):
    s = settings(**changes)
    for name, value in changes.items():
        got = getattr(s, name)
        assert got == (tuple(value) if name == 'joint_names' else value)


@pytest.mark.parametrize('name, value, words', [
    ('rate_hz', 0, 'must be a double'),
    ('rate_hz', -1.0, 'must lie in'),
    ('rate_hz', 10000.5, 'must lie in'),
    ('rate_hz', NAN, 'must lie in'),
    ('rate_hz', INF, 'must lie in'),
    ('setpoint_timeout', 0.0, 'must lie in'),
    ('setpoint_timeout', 3600.5, 'must lie in'),
    ('setpoint_timeout', '0.1', 'must be a double'),
    ('pairing_timeout', 0.0, 'must lie in'),
    ('pairing_timeout', 1, 'must be a double'),
    ('singularity_margin', -0.01, 'must lie in'),
    ('singularity_margin', 1.0, 'must lie in'),
    ('singularity_margin', NAN, 'must lie in'),
    ('pose_only', 1, 'must be a bool'),
    ('pose_only', 'true', 'must be a bool'),
    ('base_frame', 5, 'must be a string'),
    ('base_frame', None, 'must be a string'),
    ('joint_names', 'abc', 'array of strings'),
    ('joint_names', [1, 2, 3], 'array of strings'),
    ('joint_names', ['a', 'b'], 'three distinct non-empty'),
    ('joint_names', ['a', 'b', 'c', 'd'], 'three distinct non-empty'),
    ('joint_names', ['a', 'a', 'b'], 'three distinct non-empty'),
    ('joint_names', ['a', '', 'b'], 'three distinct non-empty'),
    ('joint_names', [], 'three distinct non-empty'),
])
def test_invalid_node_settings(name, value, words):
    with pytest.raises(ValueError) as info:
        settings(**{name: value})
    assert str(info.value).startswith(f'{name}: ')
    assert words in str(info.value)


def test_pairing_timeout_must_not_exceed_setpoint_timeout():
    with pytest.raises(ValueError, match='^pairing_timeout: .*setpoint'):
        settings(pairing_timeout=0.2, setpoint_timeout=0.1)
    with pytest.raises(ValueError, match='^pairing_timeout: '):
        settings(setpoint_timeout=0.01)     # default pairing 0.05
    assert settings(pairing_timeout=0.1, setpoint_timeout=0.1)


@pytest.mark.parametrize('name, value', [
    ('m5', -1.0), ('m5', 0.0), ('m1', NAN), ('m4', 0.0), ('m6', -2.5),
    ('l3', 1), ('l', True), ('l1', INF), ('l2', '0.08'), ('alpha', 2.0),
    ('alpha', 0.0), ('gravity', [0, 0, -9.81]), ('gravity', [0.0, 0.0]),
    ('gravity', [0.0, 0.0, NAN]), ('gravity', 9.81), ('unknown', 1.0),
])
def test_invalid_robot_settings_name_the_parameter(name, value):
    with pytest.raises(ValueError) as info:
        settings(**{f'robot.{name}': value})
    assert str(info.value).startswith(f'robot.{name}: ')
