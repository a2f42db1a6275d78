"""
A step the engine cannot integrate is reported, never shown as physics.

Masses of 1e-6 kg and drives of 1e6 N (``max_effort``) under +-1e6 N
commands make MuJoCo flag ``Nan, Inf or huge value in QACC``, reset its
own state to qpos0 and write ``MUJOCO_LOG.TXT`` into the working
directory, every step.
The rule (one for both engines, doc/simulator.md): a plant raises
:class:`plant.Diverged` (MuJoCo: any warning of the step in
``mjData.warning``; the builtin: a stage or end state that is not finite),
its state unchanged, and the simulator goes ``diverged``: ERROR with the
engine's reason, nothing published, commands ignored, until
``~/reset``. Pure and fast: no DDS (``test_simulator_node.py`` plays the
same against the node process).
"""

import math
import os

import pytest

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.parameters import joint_limit_values
from orthoglide_ros.cores.simulator import (DIVERGED, HELD, PARAMETERS,
                                            RUNNING, Simulator)
from orthoglide_ros.cores.status import ERROR
from orthoglide_ros.model import mechanics, mjcf
from orthoglide_ros.model.plant import Diverged, Plant, rk4_step
from orthoglide_ros.model.robot import Robot

ZERO = (0.0, 0.0, 0.0)
DT = 1e-3
# Every body 1e-6 kg, the drives 1e6 N.
LIGHT = {f'm{i}': 1e-6 for i in range(1, 7)}
PUSH = (1e6, -1e6, 1e6)
# A velocity whose squares overflow inside the step (not at its start).
WILD = (1e153, 0.0, 0.0)


def needs_mujoco():
    """Return MuJoCo, or skip the test."""
    return pytest.importorskip('mujoco')


def state(plant):
    """Return everything a refused step must leave as it was."""
    return (plant.position, plant.velocity, plant.time, plant.joint_state())


# MuJoCo itself ---------------------------------------------------------------
def test_mujoco_alone_flags_the_step_and_hides_it_as_a_state_at_home(
        tmp_path, monkeypatch):
    """
    The defect, in MuJoCo without this package's plant.

    One step of the MJCF under the push: MuJoCo counts mjWARN_BADQACC,
    resets its state (qpos0, home) and advances its time: a state that
    looks valid, which is why a check of the state alone cannot see it.
    With MuJoCo's own handler it writes MUJOCO_LOG.TXT in the working
    directory.
    """
    mujoco = needs_mujoco()
    monkeypatch.chdir(tmp_path)
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(None)   # MuJoCo's own handler
    try:
        model = mujoco.MjModel.from_xml_string(mjcf.mjcf(Robot(**LIGHT)))
        data = mujoco.MjData(model)
        data.ctrl[:] = PUSH
        mujoco.mj_step(model, data)
    finally:
        mujoco.set_mju_user_warning(previous)
    assert data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number >= 1
    assert data.time == DT
    assert max(abs(q) for q in data.qpos) < 1e-4    # about home
    assert os.listdir(tmp_path) == ['MUJOCO_LOG.TXT']


# The plants -------------------------------------------------------------------
def test_mujoco_plant_raises_the_divergence_state_unchanged_no_file(
        tmp_path, monkeypatch, capfd):
    """
    MujocoPlant: Diverged with MuJoCo's reason; nothing written anywhere.

    Its state stays the last good one (home at rest, time 0), MuJoCo's
    text names the slider, no MUJOCO_LOG.TXT in the working directory and
    nothing on standard output or error (MuJoCo's handler printed the
    warning at every step); the same plant then steps a sane command.
    """
    mujoco = needs_mujoco()
    from orthoglide_ros.model.mujoco_plant import MujocoPlant
    monkeypatch.chdir(tmp_path)
    mujoco.set_mju_user_warning(None)   # the plant must take it over
    robot = Robot(**LIGHT)
    plant = MujocoPlant(robot, force_limit=1e6)
    before = state(plant)
    for _ in range(3):          # MuJoCo resets and warns at every step
        with pytest.raises(Diverged) as diverged:
            plant.step(PUSH, DT)
        assert state(plant) == before
    message = str(diverged.value)
    assert diverged.value.reason == 'diverged'
    assert message.startswith('MuJoCo: ')
    assert 'Nan, Inf or huge value in QACC' in message
    assert '(joint slider_' in message
    assert os.listdir(tmp_path) == []
    assert capfd.readouterr() == ('', '')
    # Still a plant: the weight held at home, one step.
    hold = mechanics.solve(robot, ZERO).force
    plant.step(hold, DT)
    assert plant.time == DT


def test_the_light_robot_is_a_valid_simulation_under_its_own_forces():
    """
    Masses of 1e-6 kg are a robot, not a divergence: why none is refused.

    Under forces of its own scale (1e-6 N beyond the weight on slider A)
    both engines step 0.2 s without a divergence and agree on the motion
    to 1 % (the same law on both: nothing about the masses is meaningless;
    only forces too large for them are, which a run-time rule sees).
    """
    needs_mujoco()
    from orthoglide_ros.model.mujoco_plant import MujocoPlant
    robot = Robot(**LIGHT)
    hold = mechanics.solve(robot, ZERO).force
    push = (hold[0] + 1e-6, hold[1], hold[2])
    ends = []
    for engine in (Plant, MujocoPlant):
        plant = engine(robot, force_limit=1e6)
        for _ in range(200):
            plant.step(push, DT)
        ends.append(plant.position[0])
    # x = a t^2 / 2 with a of order 1e-6 N / 1e-5 kg: millimetres.
    assert 1e-3 < ends[0] < 1e-2, ends
    assert ends[1] == pytest.approx(ends[0], rel=0.01)


def test_builtin_plant_raises_the_same_on_a_state_that_is_not_finite():
    """
    The builtin engine: a stage that overflows is a divergence too.

    From 1e153 m/s (finite; its squares are not) RK4's stage
    accelerations are not finite: Diverged, not a workspace refusal,
    state unchanged. Non-finite inputs stay a refusal (``non_finite``).
    """
    robot = Robot()
    plant = Plant(robot, ZERO, WILD)
    before = state(plant)
    with pytest.raises(Diverged) as diverged:
        plant.step(ZERO, DT)
    assert state(plant) == before
    assert str(diverged.value).startswith('RK4: ')
    assert 'not finite' in str(diverged.value)
    with pytest.raises(Diverged):
        rk4_step(robot, ZERO, WILD, ZERO, DT)
    with pytest.raises(mechanics.WorkspaceError) as refused:
        rk4_step(robot, ZERO, (math.nan, 0.0, 0.0), ZERO, DT)
    assert refused.value.reason == 'non_finite'


# The simulator's one rule ---------------------------------------------------
def diverging(engine):
    """Return a Simulator whose next step diverges on ``engine``."""
    if engine == 'mujoco':
        needs_mujoco()
        changes = {f'robot.{k}': v for k, v in LIGHT.items()}
        sim = Simulator(PARAMETERS.parse(
            {'engine': 'mujoco', **joint_limit_values('max_effort', 1e6),
             **changes}))
        return sim, PUSH
    sim = Simulator(PARAMETERS.parse({}))
    sim.plant.velocity = WILD
    return sim, ZERO


@pytest.mark.parametrize('engine, why', [
    ('mujoco', 'Nan, Inf or huge value in QACC'),
    ('builtin', 'is not finite'),
])
def test_simulator_diverged_reports_publishes_nothing_until_reset(
        engine, why, tmp_path, monkeypatch):
    """
    Both engines: ``diverged``, ERROR with the reason, nothing published.

    The step that diverged is not counted and its state is not
    published, nor any later one; commands are ignored (counted) until
    reset, which starts over at home, held, and the plant runs again.
    """
    monkeypatch.chdir(tmp_path)
    sim, force = diverging(engine)
    sim.command(force, 0.0)
    assert sim.state == RUNNING
    tick = sim.tick(DT)
    assert (tick.state, tick.event) == (DIVERGED, 'diverged')
    assert sim.publish_due(tick, DT) is False
    assert sim.steps == 0 and sim.divergences == 1
    assert sim.plant.time == 0.0
    for k in range(2, 6):
        with pytest.raises(Rejected) as refused:
            sim.command(force, k * DT)
        assert refused.value.reason == 'diverged'
        tick = sim.tick(k * DT)
        assert (tick.state, tick.event) == (DIVERGED, None)
        assert sim.publish_due(tick, k * DT) is False
    assert sim.ignored == 4 and sim.steps == 0 and sim.published == 0
    status = sim.status(1.0)
    assert status.level == ERROR
    assert status.message.startswith(f'diverged: the {engine} engine '
                                     'diverged after time 0 s')
    assert why in status.message and '~/reset' in status.message
    values = dict(status.values)
    assert (values['state'], values['divergences']) == (DIVERGED, 1)
    assert values['commands ignored (stopped)'] == 4
    # The way out: ~/reset.
    sim.reset()
    assert (sim.state, sim.plant.velocity, sim.plant.time) == (
        HELD, ZERO, 0.0)
    assert max(map(abs, sim.plant.position)) < 1e-12   # home (MuJoCo: 1e-17)
    assert sim.stop_message is None
    hold = mechanics.solve(sim.plant.robot, ZERO).force
    sim.command(hold, 1.0)
    tick = sim.tick(1.0 + DT)
    assert (tick.state, tick.event) == (RUNNING, None)
    assert sim.publish_due(tick, 1.0 + DT) and sim.steps == 1
    assert sim.status(2.0).level != ERROR
    assert os.listdir(tmp_path) == []
