"""
Tests of the tracking controller's ROS-free logic (orthoglide_ros.cores.tracking_controller).

Time is driven by hand: every call takes ``now`` (s, monotonic). The law is
checked against an independent computation (math.fsum of the three terms,
then clipping) to floating-point rounding: a few ulps of the terms' sizes.
"""

import math

from hypothesis import given, settings as hypothesis_settings, strategies as st
from hypothesis_profiles import examples
import numpy as np
import pytest

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import joint_limit, joint_limit_values
from orthoglide_ros.cores.tracking_controller import (
    Command, control_law, INPUTS, JointValues, PARAMETERS,
    read_joint_state, REASONS, SKIPS, Tracking)
from orthoglide_ros.planning.limits import LIMIT_BOUND

CONTROLLER_SPECS = PARAMETERS.specs
controller_settings_from_parameters = PARAMETERS.parse
default_controller_parameters = PARAMETERS.defaults

NAMES = ('slider_a', 'slider_b', 'slider_c')
STAMP = (1, 0)     # a joint state's stamp (the controller does not read it)
ZERO3 = (0.0, 0.0, 0.0)
NAN = float('nan')
INF = float('inf')
EPS = 2.0 ** -52
EFFORT = 'joint_limits.slider_a.max_effort'


def limits(value):
    """Return the parameters of an effort limit: ``value`` N on A, B, C."""
    return joint_limit_values('max_effort', value)


def settings(**changes):
    """
    Return validated settings: the defaults with ``changes``.

    The path tolerance and the stall rule are off unless given: the law's
    tests use errors far beyond the one and pauses beyond the other (their
    own tests below set them).
    """
    values = default_controller_parameters()
    values['path_tolerance'] = [0.0] * 3
    values['stall_timeout'] = 0.0
    values.update(changes)
    return controller_settings_from_parameters(values)


def expected_force(s, desired, measured):
    """Return (forces, bounds): the law computed apart, with its rounding."""
    forces, bounds = [], []
    for i, limit in enumerate(joint_limit(s, 'max_effort')):
        terms = [s.kp[i] * (desired.position[i] - measured.position[i]),
                 s.kd[i] * (desired.velocity[i] - measured.velocity[i])]
        if s.feedforward:
            terms.append(desired.effort[i])
        f = math.fsum(terms)
        forces.append(min(max(f, -limit), limit))
        # Rounding of the products and of two additions, with margin.
        bounds.append(8 * EPS * sum(abs(t) for t in terms) + 1e-300)
    return forces, bounds


def assert_law(s, desired, measured, command):
    """Check the command against the independent law, to rounding."""
    forces, bounds = expected_force(s, desired, measured)
    for got, want, bound, limit in zip(command.force, forces, bounds,
                                       joint_limit(s, 'max_effort')):
        assert abs(got - want) <= bound, (got, want, bound)
        assert abs(got) <= limit
    assert command.error == tuple(
        d - m for d, m in zip(desired.position, measured.position))


# Parameters ------------------------------------------------------------------
def test_specs_defaults_and_names():
    """The table's names, types and defaults are the documented ones."""
    specs = {s.name: s for s in PARAMETERS.own_specs}
    assert list(specs) == ['kp', 'kd', 'feedforward'] + [
        f'joint_limits.{joint}.{key}' for joint in NAMES
        for key in ('has_effort_limits', 'max_effort')] + [
                           'joint_names', 'measurement_timeout',
                           'rate_hz', 'path_tolerance', 'stall_timeout',
                           'max_position', 'max_velocity', 'thread_priority',
                           'cpu_affinity', 'lock_memory']
    assert specs['kp'].type == specs['kd'].type == 'double_array'
    assert specs['kp'].default == [20000.0] * 3
    assert specs['kd'].default == [1200.0] * 3
    assert specs['feedforward'].default is True
    for joint in NAMES:
        assert specs[f'joint_limits.{joint}.has_effort_limits'].default
        assert specs[f'joint_limits.{joint}.max_effort'].default == 1000.0
    assert specs['joint_names'].default == list(NAMES)
    assert specs['measurement_timeout'].default == 0.05
    assert specs['path_tolerance'].default == [0.05] * 3
    assert specs['rate_hz'].default == 250.0
    assert specs['stall_timeout'].default == 0.1
    for spec in CONTROLLER_SPECS:
        assert spec.description
    s = settings()
    assert s.kp == (20000.0,) * 3 and s.kd == (1200.0,) * 3
    assert s.joint_names == NAMES
    assert (s.feedforward, joint_limit(s, 'max_effort'),
            s.measurement_timeout) == (True, (1000.0,) * 3, 0.05)


def test_default_gains_about_critically_damped():
    """Default kd = 1200 N s/m: ~0.95 of critical, 2 sqrt(kp m), m = 20 kg."""
    s = settings()
    for kp, kd in zip(s.kp, s.kd):
        zeta = kd / (2.0 * math.sqrt(kp * 20.0))
        assert 0.9 < zeta < 1.0, zeta


def test_actuator_mass_at_home_and_damping_ratio():
    """
    The paper robot's actuator-space mass at home: 24.5 kg, zeta 0.86.

    Mass matrix column j = f(lambdaddot = e_j) - f(0) at home, at rest,
    from mechanics.solve (platform acceleration J_lambda^-1 e_j). The
    doc/tracking_controller.md quotes these figures.
    """
    robot = Robot()
    home = (0.0, 0.0, 0.0)
    rest = mechanics.solve(robot, home).force
    j1, j2 = mechanics.jacobians(robot, home)
    j_lambda = np.linalg.solve(j1, j2)
    mass = np.column_stack([
        np.array(mechanics.solve(robot, home, (0.0, 0.0, 0.0),
                                 tuple(np.linalg.solve(j_lambda, e))).force)
        - rest for e in np.eye(3)])
    assert np.allclose(mass, np.diag(np.diag(mass)), atol=1e-9)
    assert np.allclose(np.diag(mass), 24.48, atol=0.01)
    s = settings()
    zeta = s.kd[0] / (2.0 * math.sqrt(s.kp[0] * mass[0, 0]))
    assert zeta == pytest.approx(0.857, abs=0.001)


@pytest.mark.parametrize('name, value', [
    ('kp', [1.0]),
    ('kp', [1.0, 2.0, 3.0, 4.0]),
    ('kp', [1.0, -2.0, 3.0]),
    ('kp', [1.0, NAN, 3.0]),
    ('kp', [1, 2, 3]),
    ('kp', 5.0),
    ('kd', [1.0, 2.0, INF]),
    ('kd', [-0.5, 2.0, 3.0]),
    ('feedforward', 'yes'),
    ('feedforward', 1),
    (EFFORT, 0.0),
    (EFFORT, -1.0),
    (EFFORT, 1000),
    (EFFORT, INF),
    (EFFORT, LIMIT_BOUND * 2),
    ('force_limit', 1000.0),
    ('joint_names', ['a', 'b']),
    ('joint_names', ['a', 'a', 'c']),
    ('joint_names', ['a', '', 'c']),
    ('joint_names', 'abc'),
    ('measurement_timeout', 0.0),
    ('measurement_timeout', NAN),
])
def test_invalid_parameters_named(name, value):
    """Each invalid value raises ValueError naming its parameter."""
    with pytest.raises(ValueError, match=name):
        settings(**{name: value})


def test_valid_parameter_edges():
    """Zero gains, the range ends and any names are accepted."""
    s = settings(kp=[0.0, 0.0, 0.0], kd=[0.0, 1e9, 0.0],
                 **limits(LIMIT_BOUND), joint_names=['x', 'y', 'z'],
                 measurement_timeout=0.0001, feedforward=False)
    assert s.kd == (0.0, 1e9, 0.0) and s.joint_names == ('x', 'y', 'z')
    assert joint_limit(settings(**limits(0.001)), 'max_effort') == \
        (0.001,) * 3
    # Off: no limit, 0.0 then not a limit.
    assert joint_limit(settings(**limits(INF)), 'max_effort') == (INF,) * 3


# The law ---------------------------------------------------------------------
def test_law_worked_example():
    """Law f = f_ff + Kp e + Kd edot per actuator, by hand."""
    s = settings(kp=[100.0, 200.0, 300.0], kd=[10.0, 20.0, 30.0])
    desired = JointValues((0.5, 0.25, -0.125), (1.0, 0.0, -2.0),
                          (5.0, -6.0, 7.0))
    measured = JointValues((0.25, 0.5, -0.125), (0.5, 1.0, -1.0), None)
    command = control_law(s, desired, measured)
    # A: 5 + 100*0.25 + 10*0.5; B: -6 + 200*(-0.25) + 20*(-1);
    # C: 7 + 0 + 30*(-1).
    assert command == Command((35.0, -76.0, -23.0), (0.25, -0.25, 0.0), 0)
    off = control_law(s._replace(feedforward=False), desired, measured)
    assert off.force == (30.0, -70.0, -30.0)


def test_law_clips_to_limit_and_counts():
    """Beyond +-max_effort of its actuator: clipped; at it: not counted."""
    s = settings(kp=[1000.0] * 3, kd=[0.0] * 3, **limits(100.0))
    zero = (0.0, 0.0, 0.0)
    desired = JointValues((1.0, -1.0, 0.1), zero, zero)
    measured = JointValues(zero, zero, None)
    command = control_law(s, desired, measured)
    assert command.force == (100.0, -100.0, 100.0)
    assert command.clipped == 2
    assert command.error == (1.0, -1.0, 0.1)
    # Each actuator its own limit; none where its flag is off.
    s = settings(kp=[1000.0] * 3, kd=[0.0] * 3,
                 **limits([100.0, 50.0, INF]))
    command = control_law(s, JointValues((1.0, -1.0, 5.0), zero, zero),
                          measured)
    assert command.force == (100.0, -50.0, 5000.0) and command.clipped == 2


def test_an_effort_limit_flagged_without_its_value_is_refused():
    with pytest.raises(ValueError, match=EFFORT + ': must be above 0 where '
                       'has_effort_limits is true'):
        settings(**{EFFORT: 0.0})


def test_law_overflow_refused():
    """A force that is not finite before clipping refuses the command."""
    s = settings(kp=[1e300] * 3)
    zero = (0.0, 0.0, 0.0)
    with pytest.raises(Rejected) as info:
        control_law(s, JointValues((1e10, 0.0, 0.0), zero, zero),
                    JointValues(zero, zero, None))
    assert info.value.reason == 'overflow'


finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
triple = st.tuples(finite, finite, finite)
gain = st.floats(0.0, 1e6, allow_nan=False, allow_infinity=False)
gains = st.lists(gain, min_size=3, max_size=3)


@hypothesis_settings(max_examples=examples(300), deadline=None)
@given(kp=gains, kd=gains, feedforward=st.booleans(),
       limit=st.floats(0.001, 1e6),
       lam_d=triple, dlam_d=triple, f_ff=triple, lam=triple, dlam=triple)
def test_law_property(kp, kd, feedforward, limit, lam_d, dlam_d, f_ff, lam,
                      dlam):
    """The output is f_ff + Kp e + Kd edot clipped to the limit."""
    s = settings(kp=kp, kd=kd, feedforward=feedforward, **limits(limit))
    desired = JointValues(lam_d, dlam_d, f_ff if feedforward else None)
    measured = JointValues(lam, dlam, None)
    command = control_law(s, desired, measured)
    assert_law(s, desired, measured, command)
    # Clipped: the forces beyond the limit, give or take rounding at it.
    raw = [math.fsum([ff if feedforward else 0.0, p * (a - b), d * (c - e)])
           for ff, p, a, b, d, c, e in zip(f_ff, kp, lam_d, lam, kd, dlam_d,
                                           dlam)]
    surely = sum(abs(f) > limit * (1 + 1e-9) for f in raw)
    maybe = sum(abs(f) > limit * (1 - 1e-9) for f in raw)
    assert surely <= command.clipped <= maybe


# Reading joint states --------------------------------------------------------
def test_read_matches_names_in_any_order_and_ignores_extras():
    """Values come out in joint_names order whatever the message order."""
    values = read_joint_state(
        NAMES, ['other', 'slider_c', 'slider_a', 'slider_b'],
        [NAN, 3.0, 1.0, 2.0], [INF, 30.0, 10.0, 20.0],
        [NAN, 300.0, 100.0, 200.0], True)
    assert values == JointValues((1.0, 2.0, 3.0), (10.0, 20.0, 30.0),
                                 (100.0, 200.0, 300.0))


@pytest.mark.parametrize('names, position, velocity, effort, need, reason', [
    (['slider_a', 'slider_b'], [1.0, 2.0], [1.0, 2.0], [1.0, 2.0], True,
     'missing_joint'),
    (['slider_a', 'slider_b', 'slider_c', 'slider_a'], [0.0] * 4, [0.0] * 4,
     [0.0] * 4, True, 'malformed'),
    (list(NAMES), [0.0, 0.0], [0.0] * 3, [0.0] * 3, True, 'malformed'),
    (list(NAMES), [0.0] * 3, [0.0] * 4, [0.0] * 3, True, 'malformed'),
    (list(NAMES), [], [0.0] * 3, [0.0] * 3, True, 'missing_position'),
    (list(NAMES), [0.0] * 3, [], [0.0] * 3, True, 'missing_velocity'),
    (list(NAMES), [0.0] * 3, [0.0] * 3, [], True, 'missing_effort'),
    (list(NAMES), [0.0, NAN, 0.0], [0.0] * 3, [0.0] * 3, True, 'non_finite'),
    (list(NAMES), [0.0] * 3, [0.0, 0.0, -INF], [0.0] * 3, False,
     'non_finite'),
    (list(NAMES), [0.0] * 3, [0.0] * 3, [INF, 0.0, 0.0], True, 'non_finite'),
    (list(NAMES), [1e308] * 3, [0.0] * 3, [0.0] * 3, True, None),
], ids=['missing_joint', 'repeated_name', 'short_position', 'long_velocity',
        'no_position', 'no_velocity', 'no_effort', 'nan_position',
        'inf_velocity', 'inf_effort', 'huge_but_finite'])
def test_read_rejections(names, position, velocity, effort, need, reason):
    """Each rule of the module refuses with its reason (or accepts)."""
    if reason is None:
        read_joint_state(NAMES, names, position, velocity, effort, need)
        return
    with pytest.raises(Rejected) as info:
        read_joint_state(NAMES, names, position, velocity, effort, need)
    assert info.value.reason == reason
    assert info.value.reason in REASONS


def test_read_effort_not_needed():
    """Without the need, efforts may be absent, NaN or of another length."""
    for effort in ([], [NAN, NAN, NAN], [1.0]):
        values = read_joint_state(NAMES, list(NAMES), [1.0, 2.0, 3.0],
                                  [0.0] * 3, effort, False)
        assert values.effort is None


# Within the default plausibility bounds (max_position, max_velocity, the
# max_effort of each actuator).
positions = st.tuples(*[st.floats(-1.0, 1.0)] * 3)
velocities = st.tuples(*[st.floats(-2.0, 2.0)] * 3)


@hypothesis_settings(max_examples=examples(100), deadline=None)
@given(order=st.permutations(range(3)), lam_d=positions, dlam_d=velocities,
       f_ff=triple, lam=positions, dlam=velocities)
def test_name_order_does_not_matter(order, lam_d, dlam_d, f_ff, lam, dlam):
    """Permuting a message's joints leaves the command unchanged."""
    def shuffled(values):
        return [values[i] for i in order]

    reference = Tracking(settings(measurement_timeout=1.0))
    reference.measured(STAMP, '', NAMES, lam, dlam, [], 0.0)
    expected = reference.desired(STAMP, '', NAMES, lam_d, dlam_d, f_ff, 0.0)
    core = Tracking(settings(measurement_timeout=1.0))
    core.measured(STAMP, '', shuffled(NAMES), shuffled(lam), shuffled(dlam), [], 0.0)
    got = core.desired(STAMP, '', shuffled(NAMES), shuffled(lam_d), shuffled(dlam_d),
                       shuffled(f_ff), 0.0)
    assert got == expected


# The core: timing and counters -----------------------------------------------
def send_measured(core, position, now, velocity=(0.0, 0.0, 0.0)):
    """Send a measurement in joint_names order."""
    core.measured(STAMP, '', core.settings.joint_names, position, velocity, [], now)


def send_desired(core, position, now, velocity=(0.0, 0.0, 0.0),
                 effort=(0.0, 0.0, 0.0)):
    """Send a desired state in joint_names order; return the command."""
    return core.desired(STAMP, '', core.settings.joint_names, position, velocity,
                        effort, now)


def test_no_measurement_skips():
    """Before any measurement a desired state is skipped and counted."""
    core = Tracking(settings())
    assert send_desired(core, (0.0, 0.0, 0.0), 1.0) is None
    assert core.skipped == {'no_measurement': 1, 'stale_measurement': 0,
                            'trajectory_active': 0, 'inactive': 0}
    assert core.commands == 0 and core.latest is None
    assert core.received == {'desired': 1, 'measured': 0, 'trajectory': 0}


def test_stale_measurement_skips_until_a_fresh_one():
    """Older than measurement_timeout by arrival time: skipped."""
    core = Tracking(settings(measurement_timeout=0.0625))   # exact in binary
    send_measured(core, (0.0, 0.0, 0.0), 10.0)
    assert send_desired(core, (0.001, 0.0, 0.0), 10.0625) is not None
    assert core.fresh(10.0625) and not core.fresh(10.0626)
    assert send_desired(core, (0.001, 0.0, 0.0), 10.0626) is None
    assert core.skipped == {'no_measurement': 0, 'stale_measurement': 1,
                            'trajectory_active': 0, 'inactive': 0}
    send_measured(core, (0.0, 0.0, 0.0), 11.0)
    command = send_desired(core, (0.001, 0.0, 0.0), 11.01)
    assert command.force[0] == pytest.approx(20.0)
    assert core.commands == 2


def test_newest_measurement_used():
    """Each command uses the newest accepted measurement."""
    core = Tracking(settings(kp=[1.0] * 3, kd=[0.0] * 3, feedforward=False))
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    send_measured(core, (0.5, 0.25, 0.125), 0.01)
    command = send_desired(core, (1.0, 1.0, 1.0), 0.02)
    assert command.force == (0.5, 0.75, 0.875)


def test_rejected_inputs_counted_and_change_nothing():
    """A refused measurement keeps the previous one; counts by input."""
    core = Tracking(settings(kp=[1.0] * 3, kd=[0.0] * 3, feedforward=False))
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    with pytest.raises(Rejected):
        send_measured(core, (NAN, 0.0, 0.0), 0.01)
    with pytest.raises(Rejected):
        core.measured(STAMP, '', ['slider_a'], [1.0], [0.0], [], 0.01)
    with pytest.raises(Rejected):
        core.desired(STAMP, '', NAMES, [1.0] * 3, [], [], 0.02)
    assert core.measurement_arrival == 0.0
    assert core.rejected['measured', 'non_finite'] == 1
    assert core.rejected['measured', 'missing_joint'] == 1
    assert core.rejected['desired', 'missing_velocity'] == 1
    assert sum(core.rejected.values()) == 3
    assert core.received == {'desired': 1, 'measured': 3, 'trajectory': 0}
    command = send_desired(core, (1.0, 1.0, 1.0), 0.03)
    assert command.force == (1.0, 1.0, 1.0)
    assert set(i for i, _ in core.rejected) == set(INPUTS)
    assert set(core.skipped) == set(SKIPS)


def test_feedforward_on_needs_effort_off_does_not():
    """Missing desired efforts: rejected with feedforward, fine without."""
    core = Tracking(settings())
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    with pytest.raises(Rejected) as info:
        core.desired(STAMP, '', NAMES, [0.0] * 3, [0.0] * 3, [], 0.01)
    assert info.value.reason == 'missing_effort'
    core.configure(settings(feedforward=False))
    command = core.desired(STAMP, '', NAMES, [0.001] * 3, [0.0] * 3, [], 0.01)
    assert command.force == pytest.approx((20.0, 20.0, 20.0))


def test_clipped_counted_and_configure_applies():
    """Clipped forces add up; new settings apply from the next message."""
    core = Tracking(settings(**limits(10.0)))
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    command = send_desired(core, (1.0, -1.0, 0.0), 0.01)
    assert command.force == (10.0, -10.0, 0.0)
    assert core.clipped == 2
    core.configure(settings(**limits(50000.0), joint_names=['a', 'b', 'c']))
    # New names: the measurement read by the old ones is forgotten.
    assert core.desired(STAMP, '', ['a', 'b', 'c'], [0.0] * 3, [0.0] * 3, [0.0] * 3,
                        0.02) is None
    assert core.skipped['no_measurement'] == 1
    core.measured(STAMP, '', ['b', 'c', 'a'], [0.0] * 3, [0.0] * 3, [], 0.02)
    command = core.desired(STAMP, '', ['c', 'b', 'a'], [0.0, -1.0, 1.0], [0.0] * 3,
                           [0.0] * 3, 0.02)
    assert command.force == (20000.0, -20000.0, 0.0)
    assert core.clipped == 2 and core.commands == 2


# Path tolerance --------------------------------------------------------------
def test_path_tolerance_trips_holds_and_re_arms():
    """
    Beyond path_tolerance: hold the measured position with the last bias.

    The bias is the last command sent while following; the hold law is
    f = b + Kp (lambda_hold - lambda) - Kd lambdadot; ERROR meanwhile; a
    desired state within half the tolerance and at the measured speed
    re-arms (one passing by does not).
    """
    s = settings(path_tolerance=[0.05, 0.05, 0.05], kp=[100.0] * 3,
                 kd=[10.0] * 3)
    core = Tracking(s)
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    following = send_desired(core, (0.01, 0.0, -0.01), 0.01,
                             effort=(1.0, 2.0, 250.0))
    assert core.mode == 'following'
    assert following.force == (2.0, 2.0, 249.0)      # ff + kp e
    # The stream moved on while the robot stood: 0.2 m away on B.
    send_measured(core, (0.005, 0.0, 0.0), 0.02, velocity=(0.1, 0.0, 0.0))
    held = send_desired(core, (0.01, 0.2, 0.0), 0.03,
                        effort=(9.0, 9.0, 9.0))
    assert core.mode == 'holding' and core.trips == 1
    # b = (2, 2, 249); hold = (0.005, 0, 0); here e = 0, v = 0.1 on A.
    assert held.force == pytest.approx((2.0 - 10.0 * 0.1, 2.0, 249.0))
    status = core.status(0.5)
    assert status.level == 2 and "'slider_b'" in status.message
    assert dict(status.values)['path tolerance trips'] == 1
    # Still beyond half the tolerance (0.03 > 0.025): still holding.
    send_measured(core, (0.0, 0.0, 0.0), 0.04)
    again = send_desired(core, (0.0, 0.03, 0.0), 0.05)
    assert core.mode == 'holding'
    assert again.force == pytest.approx((2.0 + 100.0 * 0.005, 2.0, 249.0))
    # Within half of it but passing by at speed: still holding.
    send_desired(core, (0.0, 0.02, 0.0), 0.055, velocity=(0.0, 0.1, 0.0))
    assert core.mode == 'holding'
    # Within half of it, at rest: following again, with its law.
    rearmed = send_desired(core, (0.0, 0.02, 0.0), 0.06,
                           effort=(1.0, 1.0, 1.0))
    assert core.mode == 'following' and core.trips == 1
    assert rearmed.force == pytest.approx((1.0, 1.0 + 100.0 * 0.02, 1.0))
    assert core.status(1.0).level == 0


def test_stall_holds_unless_the_stream_starts_where_the_robot_is():
    """
    A pause of more than stall_timeout between commands: a new goal.

    Within the path tolerance (0.03 m < 0.05 m) a stream that moved on
    while the loop stalled would be chased with Kp x 0.03 m; it is held
    (counted, ERROR) until a desired state starts where the robot is.
    """
    s = settings(path_tolerance=[0.05] * 3, stall_timeout=0.1,
                 kp=[20000.0] * 3, kd=[0.0] * 3)
    core = Tracking(s)
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    first = send_desired(core, (0.0, 0.0, 0.0), 0.01,
                         effort=(1.0, 2.0, 3.0))
    assert first.force == (1.0, 2.0, 3.0)
    # A pause of 0.1 s is no stall; the robot stands, the stream moves on.
    send_measured(core, (0.0, 0.0, 0.0), 0.11)
    assert send_desired(core, (0.001, 0.0, 0.0), 0.11).force[0] == 20.0
    assert core.mode == 'following' and core.stalls == 0
    # 2 s without a command (the controller stopped), measurements fresh
    # again: the stream is 0.03 m on and moving at 0.2 m/s.
    send_measured(core, (0.0, 0.0, 0.0), 2.2)
    held = send_desired(core, (0.03, 0.0, 0.0), 2.2,
                        velocity=(0.2, 0.0, 0.0), effort=(5.0, 5.0, 5.0))
    assert core.mode == 'holding' and core.stalls == 1 and core.trips == 0
    assert held.force == (20.0, 0.0, 0.0)    # b: the last command sent
    status = core.status(2.5)
    assert status.level == 2 and 'no command for 2.09 s' in status.message
    assert dict(status.values)['stall holds'] == 1
    # A desired state where the robot is, at rest: following again.
    rearmed = send_desired(core, (0.01, 0.0, 0.0), 2.21)
    assert core.mode == 'following' and rearmed.force[0] == 200.0


def test_stall_after_skips_and_resumption_in_place():
    """Skipped desired states (stale measurements) are a pause too."""
    s = settings(path_tolerance=[0.05] * 3, stall_timeout=0.1)
    core = Tracking(s)
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    send_desired(core, (0.0, 0.0, 0.0), 0.01)
    assert send_desired(core, (0.02, 0.0, 0.0), 0.5,
                        velocity=(0.2, 0.0, 0.0)) is None    # stale
    send_measured(core, (0.0, 0.0, 0.0), 0.6)
    send_desired(core, (0.02, 0.0, 0.0), 0.6, velocity=(0.2, 0.0, 0.0))
    assert core.mode == 'holding' and core.stalls == 1
    # A stream that starts again where the robot is after a pause (a new
    # pass from home) is followed at once: no hold, nothing counted.
    resumed = Tracking(s)
    send_measured(resumed, (0.0, 0.0, 0.0), 0.0)
    send_desired(resumed, (0.0, 0.0, 0.0), 0.01)
    send_measured(resumed, (0.0, 0.0, 0.0), 5.0)
    send_desired(resumed, (0.001, 0.0, 0.0), 5.0, velocity=(0.005, 0.0, 0.0))
    assert resumed.mode == 'following' and resumed.stalls == 0
    # 0.0: off.
    off = Tracking(settings(path_tolerance=[0.05] * 3, stall_timeout=0.0))
    send_measured(off, (0.0, 0.0, 0.0), 0.0)
    send_desired(off, (0.0, 0.0, 0.0), 0.01)
    send_measured(off, (0.0, 0.0, 0.0), 5.0)
    send_desired(off, (0.02, 0.0, 0.0), 5.0, velocity=(0.2, 0.0, 0.0))
    assert off.mode == 'following' and off.stalls == 0


def test_path_tolerance_zero_disables_an_actuator():
    """0.0: no limit on that actuator, the others still trip."""
    core = Tracking(settings(path_tolerance=[0.0, 0.05, 0.05]))
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    send_desired(core, (1.0, 0.0, 0.0), 0.01)
    assert core.mode == 'following'
    send_desired(core, (1.0, 0.06, 0.0), 0.02)
    assert core.mode == 'holding'


def test_hold_bias_before_any_command():
    """A trip on the first desired state holds with its effort (ff on)."""
    core = Tracking(settings(path_tolerance=[0.05] * 3))
    send_measured(core, (0.0, 0.0, 0.0), 0.0)
    held = send_desired(core, (0.0, 0.0, 0.3), 0.01,
                        effort=(0.0, 0.0, 256.5))
    assert core.mode == 'holding' and held.force == (0.0, 0.0, 256.5)
    off = Tracking(settings(path_tolerance=[0.05] * 3, feedforward=False))
    send_measured(off, (0.0, 0.0, 0.0), 0.0)
    assert send_desired(off, (0.0, 0.0, 0.3), 0.01).force == (0.0,) * 3


# Plausibility bounds and the hold's bias -------------------------------------
@pytest.mark.parametrize('source, position, velocity, effort, reason', [
    ('measured', (0.0, 5.0, 0.0), ZERO3, ZERO3, 'position_limit'),
    ('measured', ZERO3, (0.0, 0.0, 1e300), ZERO3, 'velocity_limit'),
    ('desired', (0.0, 0.0, -1.6), ZERO3, ZERO3, 'position_limit'),
    ('desired', ZERO3, (2.5, 0.0, 0.0), ZERO3, 'velocity_limit'),
    ('desired', ZERO3, ZERO3, (0.0, 1e300, 0.0), 'effort_limit'),
])
def test_implausible_joint_states_are_refused_and_change_nothing(
        source, position, velocity, effort, reason):
    """A spoofed 5 m or 1e300 is refused by reason, never used."""
    core = Tracking(settings())
    send_measured(core, ZERO3, 0.0)
    call = core.measured if source == 'measured' else core.desired
    with pytest.raises(Rejected) as info:
        call(STAMP, '', NAMES, position, velocity, effort, 0.001)
    assert info.value.reason == reason
    assert core.rejected[source, reason] == 1
    assert core.measurement.position == ZERO3 and core.commands == 0
    # The bound is the parameter: raised, the same value passes.
    looser = Tracking(settings(max_position=10.0, max_velocity=1e3,
                               **limits(1e6)))
    send_measured(looser, ZERO3, 0.0)
    if max(map(abs, velocity + effort)) < 1e3:
        call = looser.measured if source == 'measured' else looser.desired
        call(STAMP, '', NAMES, position, velocity, effort, 0.001)


def test_a_saturated_command_is_never_the_hold_bias():
    """The bias is the last command that clipped nothing."""
    core = Tracking(settings(path_tolerance=[0.05] * 3, kp=[1e4] * 3,
                             kd=[0.0] * 3, **limits(1000.0)))
    send_measured(core, ZERO3, 0.0)
    calm = send_desired(core, (0.001, 0.0, 0.0), 0.001,
                        effort=(10.0, 20.0, 30.0))
    assert calm.clipped == 0
    saturated = send_desired(core, (0.049, 0.0, 0.0), 0.002,
                             effort=(900.0, 20.0, 30.0))
    assert saturated.clipped == 1 and saturated.force[0] == 1000.0
    held = send_desired(core, (0.2, 0.0, 0.0), 0.003)
    assert core.mode == 'holding'
    assert held.force == pytest.approx(calm.force)
