"""
Tests of the simulator's ROS-free logic (orthoglide_ros.cores.simulator).

Time is driven by hand: every call takes ``now`` (s, monotonic). Each step
is compared with :func:`plant.rk4_step` on the same state exactly
(``==``): the core must hand the plant's numbers over untouched.
"""

import doctest
import math

import pytest

from orthoglide_ros.cores import simulator
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import (joint_limit, joint_limit_values,
                                             ROBOT_SPECS)
from orthoglide_ros.model.plant import rk4_step
from orthoglide_ros.cores.simulator import (
    COMMAND_REASONS, HELD, PARAMETERS, RUNNING, Simulator, STOPPED)

SIMULATOR_SPECS = PARAMETERS.specs
simulator_settings_from_parameters = PARAMETERS.parse

ZERO = (0.0, 0.0, 0.0)
NAN = float('nan')
INF = float('inf')
DT = 1e-3           # s: one step at the default rate_hz
HOLD = mechanics.solve(Robot(), ZERO).force     # holds the weight at home
START = (0.05, -0.03, 0.02)     # m: an initial position off home
EFFORT = 'joint_limits.slider_a.max_effort'


def limits(value):
    """Return the parameters of the drives' limit: ``value`` N each."""
    return joint_limit_values('max_effort', value)


def settings(**changes):
    """Return validated settings: the defaults with ``changes`` (by name)."""
    return simulator_settings_from_parameters(changes)


def core(**changes):
    """Return a Simulator on the default settings with ``changes``."""
    return Simulator(settings(**changes))


def run_steps(sim, force, count, start=0.0):
    """
    Command ``force`` and tick ``count`` times, 1 ms apart from start.

    Once stopped, the commands are refused (``stopped``) and the ticks go
    on, as a node's do.
    """
    ticks = []
    for k in range(count):
        now = start + k * DT
        if sim.state != STOPPED:
            sim.command(force, now)
        ticks.append(sim.tick(now + DT / 2))
    return ticks


def joints(robot, position, velocity, margin=0.2):
    """Return (lambda, lambdadot) of a platform state."""
    s = mechanics.solve(robot, position, velocity, ZERO, margin)
    return s.lambda_, s.lambdadot


# Settings -------------------------------------------------------------------
def test_spec_table_is_the_robot_table_plus_the_simulator_contract():
    """Names are the node's contract; robot.* is the feedforward's table."""
    assert SIMULATOR_SPECS[:len(ROBOT_SPECS)] == ROBOT_SPECS
    own = [s.name for s in SIMULATOR_SPECS[len(ROBOT_SPECS):]]
    assert own == ['rate_hz', 'publish_rate_hz', 'initial_position',
                   'command_timeout'] + [
        f'joint_limits.{joint}.{key}'
        for joint in ('slider_a', 'slider_b', 'slider_c')
        for key in ('has_effort_limits', 'max_effort')] + [
                   'singularity_margin', 'joint_names',
                   'base_frame', 'engine', 'mjcf_file', 'thread_priority',
                   'cpu_affinity', 'lock_memory']
    for spec in SIMULATOR_SPECS:
        assert spec.description, spec.name
        if spec.type == 'double' and spec.default is not None:
            assert type(spec.default) is float, spec.name


def test_default_settings():
    """The defaults doc/decisions.md gives."""
    s = settings()
    assert s.robot == Robot()
    assert s.rate_hz == 1000.0
    assert s.publish_rate_hz == 0.0     # every step
    assert s.initial_position == ZERO
    assert s.command_timeout == 0.1
    assert joint_limit(s, 'max_effort') == (1000.0,) * 3
    assert s.singularity_margin == mechanics.DEFAULT_SINGULARITY_MARGIN
    assert s.joint_names == ('slider_a', 'slider_b', 'slider_c')
    assert s.base_frame == 'base_link'
    assert s.engine == 'builtin'


@pytest.mark.parametrize('name, value', [
    ('rate_hz', 0.5), ('rate_hz', -1.0), ('rate_hz', 20000.0),
    ('rate_hz', NAN), ('rate_hz', 1000),
    ('publish_rate_hz', -1.0), ('publish_rate_hz', NAN),
    ('publish_rate_hz', 250), ('publish_rate_hz', 2000.0),  # > rate_hz
    ('initial_position', [0.9, 0.0, 0.0]),      # out of reach
    ('initial_position', [0.8, 0.0, 0.0]),      # too near a singularity
    ('initial_position', [0.0, 0.0]), ('initial_position', [0, 0, 0]),
    ('initial_position', [NAN, 0.0, 0.0]), ('initial_position', 0.0),
    ('command_timeout', 0.0), ('command_timeout', -1.0),
    (EFFORT, 0.0), (EFFORT, -5.0), (EFFORT, INF), (EFFORT, 1000),
    ('force_limit', 1000.0),
    ('singularity_margin', 0.0), ('singularity_margin', 1.0),
    ('joint_names', ['a', 'a', 'b']), ('joint_names', ['a', 'b']),
    ('joint_names', ['a', 'b', '']), ('base_frame', 5),
    ('robot.m5', -1.0), ('robot.l3', 1), ('robot.gravity', [0, 0, -9.81]),
])
def test_invalid_settings_name_the_parameter(name, value):
    """Every invalid value raises ValueError naming its parameter."""
    with pytest.raises(ValueError, match=name.replace('.', r'\.')):
        settings(**{name: value})


def test_unknown_robot_parameter_named():
    """A robot.* name the robot does not have is refused by name."""
    with pytest.raises(ValueError, match='robot.foo'):
        simulator_settings_from_parameters({'robot.foo': 1.0})


def test_settings_checked_as_a_whole():
    """The initial position against the set's robot and margin; timeout."""
    settings(initial_position=[0.3, 0.3, 0.3])
    with pytest.raises(ValueError, match='initial_position'):
        settings(initial_position=[0.3, 0.3, 0.3], **{'robot.l3': 0.4})
    settings(initial_position=[0.7, 0.0, 0.0], singularity_margin=0.15)
    with pytest.raises(ValueError, match='initial_position'):
        settings(initial_position=[0.7, 0.0, 0.0], singularity_margin=0.5)
    settings(rate_hz=10.0, command_timeout=0.1)
    with pytest.raises(ValueError, match='command_timeout'):
        settings(rate_hz=10.0, command_timeout=0.05)
    settings(rate_hz=250.0, publish_rate_hz=250.0)
    with pytest.raises(ValueError, match='^publish_rate_hz: .*rate_hz'):
        settings(rate_hz=250.0, publish_rate_hz=250.5)


# States ---------------------------------------------------------------------
def test_held_until_the_first_command():
    """No command: held at the initial position at rest, time still."""
    sim = core(initial_position=list(START))
    lam, lamd = joints(Robot(), START, ZERO)
    for k in range(5):
        tick = sim.tick(k * DT)
        assert tick == (HELD, START, lam, lamd, ZERO, None)
    assert sim.plant.time == 0.0 and sim.steps == 0
    assert sim.command(HOLD, 1.0) is None and sim.state == RUNNING
    assert sim.tick(1.0).state == RUNNING
    assert sim.steps == 1 and sim.plant.time == DT


def test_step_is_rk4_with_the_latest_command_held():
    """Each tick = rk4_step of the same state under the held command."""
    sim = core(initial_position=list(START))
    robot = Robot()
    position, velocity = START, ZERO
    commands = [(10.0, -5.0, 260.0)] * 3 + [(-20.0, 15.0, 250.0)] * 4
    now = 0.0
    for k, force in enumerate(commands):
        if k in (0, 3):     # sent once, then held (zero-order hold)
            sim.command(force, now)
        now += DT
        tick = sim.tick(now)
        position, velocity, _ = rk4_step(robot, position, velocity, force,
                                         DT)
        lam, lamd = joints(robot, position, velocity)
        assert tick == (RUNNING, position, lam, lamd, force, None)
        assert (sim.plant.position, sim.plant.velocity) == (position,
                                                            velocity)
    assert sim.steps == len(commands)
    assert sim.plant.time == pytest.approx(len(commands) * DT, abs=1e-15)
    assert sim.step_ns_total > 0 and sim.step_ns_max > 0


def test_time_step_is_one_over_rate_however_late_the_tick():
    """A late tick is one step of 1/rate_hz, not a longer one."""
    sim = core(rate_hz=250.0)
    sim.command(HOLD, 0.0)
    sim.tick(0.09)      # 90 ms late, still within command_timeout
    position, velocity, _ = rk4_step(Robot(), ZERO, ZERO, HOLD, 1 / 250.0)
    assert (sim.plant.position, sim.plant.time) == (position, 1 / 250.0)


def test_timeout_brakes_to_held_with_zero_velocity():
    """No command for command_timeout: held, velocity 0; next resumes."""
    sim = core(command_timeout=0.05)
    force = (30.0, -10.0, 270.0)
    sim.command(force, 0.0)
    now = 0.0
    while now + DT <= 0.05:
        now += DT
        assert sim.tick(now).state == RUNNING
    moved = sim.plant.position
    assert moved != ZERO and sim.plant.velocity != ZERO
    steps = sim.steps
    tick = sim.tick(0.0501)
    assert (tick.state, tick.event, tick.effort) == (HELD, 'timeout', ZERO)
    assert tick.lambdadot == ZERO and sim.plant.velocity == ZERO
    assert tick.position == moved and sim.timed_out
    assert sim.timeouts == 1
    for k in range(3):      # held: no step, nothing moves
        assert sim.tick(0.06 + k * DT) == (HELD, moved, tick.lambda_, ZERO,
                                           ZERO, None)
    assert sim.steps == steps
    # The next valid command resumes from rest where it stopped.
    sim.command(force, 1.0)
    assert not sim.timed_out
    tick = sim.tick(1.0 + DT)
    position, velocity, _ = rk4_step(Robot(), moved, ZERO, force, DT)
    assert (tick.state, tick.position) == (RUNNING, position)


@pytest.mark.parametrize('limit, force', [
    (1000.0, (1000.0, 0.0, 0.0)),       # drives leg B towards its limit
    (1.0e6, (1.0e6, -1.0e6, 1.0e6)),    # far out in one step
])
def test_stopped_on_a_step_into_the_singular_region(limit, force):
    """A refused step freezes the last good state, velocity 0, says why."""
    sim = core(**limits(limit))
    sim.command(force, 0.0)
    previous = sim.plant.position
    for k in range(1, 2000):
        sim.command(force, k * DT)
        tick = sim.tick(k * DT)
        if tick.event == 'stopped':
            break
        previous = tick.position
    else:
        pytest.fail('the platform never left the workspace')
    assert tick.state == STOPPED == sim.state
    assert tick.position == previous == sim.plant.position
    assert tick.lambdadot == ZERO and sim.plant.velocity == ZERO
    assert tick.effort == ZERO
    assert sim.stop_reason in mechanics.REASONS
    assert f'({sim.stop_reason})' in sim.stop_message
    assert f'{previous[0]:.6g}' in sim.stop_message
    assert '~/reset' in sim.stop_message
    # The frozen state is a good one: inside the limits.
    assert mechanics.workspace_status(Robot(), previous).ok
    # Frozen: commands are ignored (counted), ticks step nothing.
    steps, time = sim.steps, sim.plant.time
    for j in range(3):
        with pytest.raises(Rejected) as refused:
            sim.command(HOLD, 10.0 + j)
        assert refused.value.reason == 'stopped' and sim.state == STOPPED
        assert sim.tick(10.0 + j) == (STOPPED, previous, tick.lambda_, ZERO,
                                      ZERO, None)
    assert sim.ignored == 3
    assert (sim.steps, sim.plant.time) == (steps, time)


def test_reset_starts_over_and_applies_the_pending_plant():
    """Reset: initial position, at rest, held, time 0; new plant settings."""
    sim = core()
    run_steps(sim, (1000.0, 0.0, 0.0), 400)
    assert sim.state == STOPPED
    message = sim.reset()
    assert 'initial_position' in message and 'applied' not in message
    assert (sim.state, sim.plant.position, sim.plant.velocity,
            sim.plant.time) == (HELD, ZERO, ZERO, 0.0)
    assert sim.stop_reason is None and sim.stop_message is None
    sim.command(HOLD, 100.0)
    assert sim.state == RUNNING
    # Plant parameters wait for the reset; the drives' limits at once.
    heavy = Robot(m5=20.0)
    new = settings(initial_position=list(START), **limits(100.0),
                   **{'robot.m5': 20.0})
    sim.configure(new)
    assert sim.pending_reset
    assert sim.plant.robot == Robot() and sim.plant.position == ZERO
    tick = sim.tick(100.0)
    assert tick.effort == (0.0, 0.0, 100.0) and sim.clipped == 1
    message = sim.reset()
    assert 'applied' in message and not sim.pending_reset
    assert sim.plant.robot == heavy and sim.plant.position == START
    assert sim.state == HELD
    sim.configure(settings(initial_position=list(START), **limits(50.0),
                           **{'robot.m5': 20.0}))
    assert not sim.pending_reset


def test_a_payload_is_picked_up_at_the_next_step_not_at_reset():
    """robot.payload changes the plant at once: a part picked up."""
    sim = core()
    sim.command(HOLD, 0.0)
    sim.tick(0.001)
    sim.configure(settings(**{'robot.payload': 5.0}))
    assert not sim.pending_reset
    assert sim.plant.robot == Robot(payload=5.0)
    position, velocity = sim.plant.position, sim.plant.velocity
    sim.tick(0.002)
    # The step is the heavier platform's: HOLD no longer holds it.
    expected = rk4_step(Robot(payload=5.0), position, velocity, HOLD, 0.001,
                        mechanics.DEFAULT_SINGULARITY_MARGIN)
    assert (sim.plant.position, sim.plant.velocity) == expected[:2]
    assert sim.plant.velocity[2] < -0.001
    assert dict(sim.status(1.0).values)['payload (kg)'] == 5.0
    sim.reset()
    assert sim.plant.robot == Robot(payload=5.0)


def test_clipping_applied_and_counted():
    """A force beyond max_effort is clipped per actuator; steps counted."""
    sim = core(**limits(200.0), initial_position=list(START))
    command = (-500.0, 150.0, 256.0)
    ticks = run_steps(sim, command, 3)
    clipped = (-200.0, 150.0, 200.0)
    position, velocity, _ = rk4_step(Robot(), START, ZERO, clipped, DT)
    assert ticks[0].effort == clipped and ticks[0].position == position
    assert sim.clipped == 3
    run_steps(sim, (1.0, 2.0, 199.0), 2, start=1.0)
    assert sim.clipped == 3


def test_each_drive_its_own_limit_or_none():
    """Per actuator: 100 N on A, 300 N on B, no limit on C (its flag off)."""
    sim = core(**limits([100.0, 300.0, INF]), initial_position=list(START))
    command = (-500.0, 500.0, 5000.0)
    ticks = run_steps(sim, command, 1)
    assert ticks[0].effort == (-100.0, 300.0, 5000.0) and sim.clipped == 1


@pytest.mark.parametrize('command, reason', [
    ([], 'length'), ([1.0, 2.0], 'length'), ([1.0, 2.0, 3.0, 4.0], 'length'),
    ([NAN, 0.0, 0.0], 'non_finite'), ([0.0, INF, 0.0], 'non_finite'),
    ([0.0, 0.0, -INF], 'non_finite'),
])
def test_bad_commands_counted_and_never_applied(command, reason):
    """Rejected by reason; held stays held, running keeps its command."""
    sim = core()
    with pytest.raises(Rejected) as caught:
        sim.command(command, 0.0)
    assert caught.value.reason == reason
    assert sim.rejected == {r: int(r == reason) for r in COMMAND_REASONS}
    assert sim.state == HELD and sim.valid == 0
    assert sim.tick(DT).effort == ZERO and sim.steps == 0
    # While running: the previous valid command stays the held one.
    force = (5.0, -5.0, 260.0)
    sim.command(force, 1.0)
    with pytest.raises(Rejected):
        sim.command(command, 1.0)
    assert sim.tick(1.0 + DT).effort == force
    assert sim.rejected[reason] == 2 and sim.valid == 1
    assert sim.received == {'commands': 3, 'joint_commands': 0}
    # A rejected command does not refresh the timeout either.
    with pytest.raises(Rejected):
        sim.command(command, 1.2)
    assert sim.tick(1.2).event == 'timeout'


def test_rejected_while_stopped_counts_as_rejected():
    """A bad command while stopped is rejected, not ignored."""
    sim = core()
    run_steps(sim, (1000.0, 0.0, 0.0), 400)
    assert sim.state == STOPPED
    ignored = sim.ignored
    with pytest.raises(Rejected):
        sim.command([NAN, 0.0, 0.0], 10.0)
    assert sim.rejected['non_finite'] == 1 and sim.ignored == ignored


def test_holding_force_at_home_stays_at_home():
    """The static weight compensation keeps the platform exactly at rest."""
    sim = core()
    ticks = run_steps(sim, HOLD, 500)
    assert all(t.position == ZERO and t.lambdadot == ZERO for t in ticks)
    assert ticks[-1].effort == HOLD


def test_module_examples():
    """The docstring examples of orthoglide_ros.cores.simulator hold."""
    failures, tried = doctest.testmod(simulator)
    assert tried > 0 and failures == 0


def test_infinite_rate_of_rejections_does_not_grow_state():
    """Counters only: a rejected command keeps nothing."""
    sim = core()
    for k in range(1000):
        with pytest.raises(Rejected):
            sim.command([math.nan] * 3, k * DT)
    assert sim.rejected['non_finite'] == 1000
    assert sim.latest_arrival is None
