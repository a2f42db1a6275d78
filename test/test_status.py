"""
The status rules of each node's core, without DDS.

Every node publishes ``core.status(now, internal_errors)`` on
``/diagnostics`` once a second (one DDS test per node checks that wiring).
Here each core is driven with its own clock and its status rules are
checked one by one: an internal error is ERROR before anything else; each node's
WARN conditions hold for the period in which they happened and clear in
the next; rates are per period; the per-period maxima restart.
"""

import math

import pytest

from orthoglide_ros.cores import (
    feedforward,
    simulator,
    status,
    tracking_controller,
)
from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import joint_limit_values
from orthoglide_ros.cores.status import ERROR, OK, WARN
from orthoglide_ros.model.trajectory import paper_sample

IDENTITY = (0.0, 0.0, 0.0, 1.0)
STAMP = (1, 0)     # a joint state's stamp (the controller does not read it)
NAMES = ['slider_a', 'slider_b', 'slider_c']
HOLD_C = 256.5315       # N: about the static force of actuator C at home


def values(s):
    """Return a Status's values as a dict."""
    return dict(s.values)


def test_period_reports_growth_and_restarts():
    period = status.Period(10.0, a=5, b=0)
    seconds, increases = period.advance(12.0, a=9, b=3)
    assert (seconds, increases) == (2.0, {'a': 4, 'b': 3})
    seconds, increases = period.advance(12.0, a=9, b=3)
    assert seconds == 1e-9 and increases == {'a': 0, 'b': 0}


def test_the_first_rule_that_holds_wins_after_internal_errors():
    rules = ((False, WARN, 'w1'), (True, WARN, 'w2'), (True, OK, 'o'))
    assert status.first_rule_that_holds(0, *rules) == (WARN, 'w2')
    assert status.first_rule_that_holds(0, (False, WARN, 'w')) == (OK, 'ok')
    level, message = status.first_rule_that_holds(2, *rules)
    assert level == ERROR and message.startswith('2 internal error')


# Feedforward -----------------------------------------------------------------
def ff_core(**changes):
    values_ = feedforward.PARAMETERS.defaults()
    values_.update(changes)
    return feedforward.Feedforward(feedforward.PARAMETERS.parse(values_),
                                   now=0.0)


def trajectory_point(ff, stamp, t, now):
    p, v, a = paper_sample(t)
    return ff.trajectory_point(stamp, '', p, IDENTITY, v, a, now)


def test_feedforward_waits_then_ok_then_stale():
    ff = ff_core()
    first = ff.status(1.0)
    assert first[:2] == (OK, 'waiting for the first setpoint')
    assert values(first)['stale'] is True
    assert math.isnan(values(first)['singularity distance'])
    for k in range(10):
        trajectory_point(ff, (5, k), 0.1 * k, 1.0 + 0.01 * k)
    ok = ff.status(1.125)       # last setpoint at 1.09 s: still fresh
    assert (ok.level, ok.message) == (OK, 'ok')
    v = values(ok)
    assert v['tick rate (Hz)'] == pytest.approx(10 / 0.125)
    assert v['setpoints computed'] == 10 and v['outputs published'] == 10
    assert v['stale'] is False and v['compute time max (us)'] > 0.0
    assert 0.0 < v['singularity distance'] <= 1.0
    stale = ff.status(2.0)      # last setpoint at 1.09 s, timeout 0.1 s
    assert stale.level == WARN and stale.message.startswith('stale: ')
    v = values(stale)
    assert v['stale'] is True and v['tick rate (Hz)'] == 0.0
    assert v['compute time max (us)'] == 0.0    # restarts each period
    assert v['time since last setpoint (s)'] == pytest.approx(0.91)


def test_feedforward_rejections_warn_for_one_period():
    ff = ff_core(setpoint_timeout=10.0)
    trajectory_point(ff, (5, 0), 0.2, 0.0)
    with pytest.raises(Rejected):
        ff.trajectory_point((5, 1), '', (0.9, 0.0, 0.0), IDENTITY,
                            (0.0,) * 3, (0.0,) * 3, 0.1)
    warned = ff.status(1.0)
    assert warned.level == WARN
    assert warned.message == '1 setpoint(s) rejected in the last period'
    assert values(warned)['rejected unreachable'] == 1
    assert ff.status(2.0).level == OK       # nothing new in this period


def test_feedforward_internal_error_is_error_first():
    ff = ff_core()
    s = ff.status(1.0, internal_errors=3)
    assert s.level == ERROR and '3 internal error' in s.message
    assert values(s)['internal errors'] == 3


# Simulator -------------------------------------------------------------------
def sim_core(**changes):
    return simulator.Simulator(simulator.PARAMETERS.parse(changes), now=0.0)


def test_simulator_held_running_timed_out():
    sim = sim_core()
    assert sim.status(0.5)[:2] == (OK, 'held: waiting for a command')
    sim.command([0.0, 0.0, HOLD_C], 1.0)
    for k in range(1, 101):
        sim.tick(1.0 + k * 1e-3 * 0.5)     # within command_timeout
    running = sim.status(1.5)
    assert running[:2] == (OK, 'running')
    v = values(running)
    assert v['state'] == 'running' and v['steps'] == 100
    assert v['step rate (Hz)'] == pytest.approx(100 / 1.0)
    assert v['sim time (s)'] == pytest.approx(0.1)
    sim.tick(2.0)               # 1 s without a command: brake
    held = sim.status(2.5)
    assert held.level == WARN and held.message.startswith('held: no valid')
    assert values(held)['timeouts'] == 1
    sim.command([0.0, 0.0, HOLD_C], 3.0)
    assert sim.status(3.5)[:2] == (OK, 'running')


def test_simulator_stopped_is_error_until_reset():
    sim = sim_core(**joint_limit_values('max_effort', 1.0e6))
    sim.command([0.0, 0.0, 1.0e6], 0.0)
    for k in range(1, 2000):
        if sim.tick(k * 1e-4).event == 'stopped':
            break
    stopped = sim.status(1.0)
    assert stopped.level == ERROR and stopped.message.startswith('stopped:')
    sim.reset()
    assert sim.status(2.0)[:2] == (OK, 'held: waiting for a command')


def test_simulator_rejected_commands_warn_for_one_period():
    sim = sim_core()
    with pytest.raises(Rejected):
        sim.command([1.0, 2.0], 0.0)
    warned = sim.status(1.0)
    assert warned[:2] == (WARN, '1 command(s) rejected in the last period')
    assert values(warned)['rejected length'] == 1
    assert sim.status(2.0).level == OK
    assert sim.status(3.0, internal_errors=1).level == ERROR


# Tracking controller ---------------------------------------------------------
def tracking_core(**changes):
    values_ = tracking_controller.PARAMETERS.defaults()
    values_.update(changes)
    return tracking_controller.Tracking(tracking_controller.PARAMETERS.parse(values_), now=0.0)


def test_tracking_waits_then_ok():
    ctl = tracking_core()
    assert ctl.status(0.5)[:2] == (OK, 'waiting for desired states')
    ctl.measured(STAMP, '', NAMES, [0.0] * 3, [0.0] * 3, [], 1.0)
    for k in range(5):
        ctl.desired(STAMP, '', NAMES, [0.001] * 3, [0.0] * 3, [1.0] * 3, 1.0 + k * 1e-3)
    ok = ctl.status(1.5)
    assert ok[:2] == (OK, 'ok')
    v = values(ok)
    assert v['command rate (Hz)'] == pytest.approx(5 / 1.0)
    assert v['tracking error slider_a (m)'] == 0.001
    assert v['measurement fresh'] is False      # 0.5 s old by now


def test_tracking_skips_and_rejections_warn():
    ctl = tracking_core()
    assert ctl.desired(STAMP, '', NAMES, [0.0] * 3, [0.0] * 3, [0.0] * 3, 0.1) is None
    skipped = ctl.status(1.0)
    assert skipped.level == WARN and 'no measurement yet' in skipped.message
    with pytest.raises(Rejected):
        ctl.measured(STAMP, '', ['x', 'y', 'z'], [0.0] * 3, [0.0] * 3, [], 1.5)
    rejected = ctl.status(2.0)
    assert rejected[:2] == (WARN,
                            '1 joint state(s) rejected in the last period')
    assert values(rejected)['rejected measured missing_joint'] == 1
    assert ctl.status(3.0)[:2] == (OK, 'ok')
    assert ctl.status(4.0, internal_errors=1).level == ERROR
