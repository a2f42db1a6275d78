"""
The drives' screw ripple: a force periodic in each slider's position.

The law (doc/model.md#drives-and-payload), written here again: on actuator
j with a screw of lead ``p_j`` (``robot.screw_lead``, 0.0 for none),
``f_j += s_j sin(2 pi lambda_j / p_j) + c_j cos(2 pi lambda_j / p_j)``
(``robot.ripple_sine``, ``robot.ripple_cosine``), lambda the slider's
position (the joint reading, 0 at home). Checked:

- ``solve`` and ``solve_batch``: the forces are the same robot's without
  the ripple plus the law; against the independent Lagrange model, which
  holds the ripple as a potential of the sliders (differentiated by
  complex step), to its error bound;
- the forward dynamics inverts them (one sample and a batch); the plant
  simulates a robot with the ripple: fed its forces open loop along eq.
  (6) it stays on the path (0.1 um after 1 s), fed the forces of the same
  robot without the ripple it leaves it by centimetres (an open-loop
  unstable robot pushed by the ripple);
- MuJoCo: the MJCF records the ripple (custom numeric data); MuJoCo's own
  mass matrix, bias and constraint Jacobian, with the plant's applied
  force, give the package's forces; the MuJoCo plant follows the path
  open loop as the builtin one does; a model given as text without the
  data has no ripple;
- identification recovers the amplitudes from a synthetic log when the
  nominal robot has the lead, tries no ripple law without one, finds
  only the actuators with a lead, and validation says what ripple is
  left;
- refusals: a negative or too short lead, a NaN amplitude, an amplitude
  without a lead (by the robot, a parameters file and the CLI), a law
  with the ripple asked for a robot without a lead.
"""

import math

from cli_runs import assert_bad_input, run
from mechanics_reference import (DRIVES_ROBOT_VALUES, force_tolerance,
                                 lagrange_forces, OTHER_ROBOT_VALUES)
import numpy as np
from orthoglide_ros.model import mechanics, mjcf
from orthoglide_ros.model.plant import Plant
from orthoglide_ros.model.robot import JOINT_NAMES, ParameterError, Robot
from orthoglide_ros.model.trajectory import paper_sample
from orthoglide_ros.tools import identification
import pytest
from synthetic_logs import synthetic_log, TRUE, write_csv

LEAD = (0.005, 0.004, 0.006)    # m: unequal, so a mix-up shows
RIPPLE = {'screw_lead': LEAD, 'ripple_sine': (2.0, 1.5, -1.0),
          'ripple_cosine': (1.0, -2.0, 1.5)}
NONE = {'ripple_sine': (0.0,) * 3, 'ripple_cosine': (0.0,) * 3}
ROBOTS = {'paper': {}, 'other': {**OTHER_ROBOT_VALUES,
                                 **DRIVES_ROBOT_VALUES}}
ROUNDING = 1e-12
OPEN_LOOP_BOUND = 1e-6      # m after 1 s, the ripple's forces fed
LEFT_BOUND = 0.01           # m after 1 s, the forces without the ripple


def law(robot, lam):
    """Return the ripple of the module docstring (N) per actuator."""
    lam = np.asarray(lam)
    phase = 2.0 * math.pi * lam / np.array(robot.screw_lead)
    return (np.array(robot.ripple_sine) * np.sin(phase)
            + np.array(robot.ripple_cosine) * np.cos(phase))


def states(count, seed=3):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.2, 0.2, (count, 3)),
            rng.uniform(-0.5, 0.5, (count, 3)),
            rng.uniform(-5.0, 5.0, (count, 3)))


@pytest.mark.parametrize('name', sorted(ROBOTS))
def test_the_forces_are_the_robots_without_it_plus_the_law(name):
    robot = Robot(**ROBOTS[name], **RIPPLE)
    without = robot.replace(**NONE)
    p, v, a = states(300)
    batch = mechanics.solve_batch(robot, p, v, a)
    plain = mechanics.solve_batch(without, p, v, a)
    ripple = law(robot, batch.lambda_)
    assert np.abs(batch.force - plain.force - ripple).max() <= ROUNDING
    assert np.abs(ripple).max() > 2.0       # the law is not zero here
    assert np.array_equal(batch.power, batch.lambdadot * batch.force)
    for i in (0, 137, 299):
        single = mechanics.solve(robot, p[i], v[i], a[i])
        assert np.abs(np.subtract(single.force, batch.force[i])).max() \
            <= ROUNDING


@pytest.mark.parametrize('name', sorted(ROBOTS))
def test_the_forces_are_the_lagrange_models(name):
    robot = Robot(**ROBOTS[name], **RIPPLE)
    p, v, a = states(6, seed=11)
    for position, velocity, acceleration in zip(p, v, a):
        ref = lagrange_forces(robot, position, velocity, acceleration)
        force = mechanics.solve(robot, position, velocity,
                                acceleration).force
        assert np.abs(force - ref.force).max() <= force_tolerance(
            ref, velocity, acceleration) + 1e-9


def test_a_sign_or_phase_error_is_seen_by_the_lagrange_model():
    """The check above can fail: a cosine read as a sine is off by N."""
    robot = Robot(**RIPPLE)
    swapped = robot.replace(ripple_sine=robot.ripple_cosine,
                            ripple_cosine=robot.ripple_sine)
    position = (0.05, -0.03, 0.02)
    ref = lagrange_forces(robot, position, np.zeros(3), np.zeros(3))
    force = mechanics.solve(swapped, position).force
    assert np.abs(force - ref.force).max() > 0.5


def test_no_lead_no_ripple_bit_for_bit():
    p, v, a = states(50)
    plain = mechanics.solve_batch(Robot(), p, v, a)
    leads = mechanics.solve_batch(Robot(screw_lead=LEAD), p, v, a)
    assert np.array_equal(plain.force, leads.force)
    assert Robot(screw_lead=LEAD).active_terms == ()


def test_forward_dynamics_inverts_solve_with_the_ripple():
    robot = Robot(**ROBOTS['other'], **RIPPLE)
    p, v, a = states(40, seed=5)
    forces = mechanics.solve_batch(robot, p, v, a).force
    found = mechanics.forward_dynamics_batch(robot, p, v, forces)
    assert np.abs(found - a).max() <= 1e-9 * np.abs(a).max()
    single = mechanics.forward_dynamics(robot, p[0], v[0], forces[0])
    assert np.abs(np.subtract(single, a[0])).max() <= 1e-9 * np.abs(
        a[0]).max()
    # The ripple is part of the bias: the same forces on the robot
    # without it give another acceleration.
    other = mechanics.forward_dynamics_batch(robot.replace(**NONE), p, v,
                                             forces)
    assert np.abs(other - a).max() > 0.01


def open_loop(plant_type, robot, model, seconds=1.0, dt=1e-3):
    """Feed ``model``'s forces along eq. (6) to ``robot``'s plant: errors."""
    plant = plant_type(robot)
    errors = []
    for k in range(round(seconds / dt)):
        plant.step(mechanics.solve(model, *paper_sample(
            (k + 0.5) * dt)).force, dt)
        errors.append(np.linalg.norm(np.subtract(
            plant.position, paper_sample((k + 1) * dt)[0])))
    return max(errors)


def test_the_plant_simulates_a_robot_with_the_ripple():
    robot = Robot(screw_lead=(0.005,) * 3, ripple_sine=(2.0, 1.5, -1.0),
                  ripple_cosine=(1.0, -2.0, 1.5))
    held = open_loop(Plant, robot, robot)
    left = open_loop(Plant, robot, robot.replace(**NONE))
    print(f'builtin plant, 1 s open loop: {held:.3g} m with the ripple\'s '
          f'forces, {left:.3g} m without')
    assert held <= OPEN_LOOP_BOUND
    assert left >= LEFT_BOUND


# --- MuJoCo ---

def test_the_mjcf_records_the_ripple_and_mujoco_gives_the_forces():
    mujoco = pytest.importorskip('mujoco')
    from orthoglide_ros.model.mujoco_plant import numeric_data
    robot = Robot(**ROBOTS['other'], **RIPPLE)
    model = mujoco.MjModel.from_xml_string(mjcf.mjcf(robot))
    data = mujoco.MjData(model)
    recorded = mjcf.recorded(Robot(), numeric_data(model))
    assert (recorded.screw_lead, recorded.ripple_sine,
            recorded.ripple_cosine) == (robot.screw_lead, robot.ripple_sine,
                                        robot.ripple_cosine)
    assert '<custom>' not in mjcf.mjcf(Robot())
    actuated = np.zeros((model.nv, 3))
    for column, name in enumerate(JOINT_NAMES):
        actuated[model.joint(name).dofadr[0], column] = 1.0
    slots = [model.joint(name).dofadr[0] for name in JOINT_NAMES]
    mass = np.zeros((model.nv, model.nv))
    p, v, a = states(6, seed=7)
    worst = 0.0
    for position, velocity, acceleration in zip(p, v, a):
        qacc = np.zeros(model.nv)
        for name, (q, qd, qdd) in mjcf.joint_values(
                robot, position, velocity, acceleration).items():
            joint = model.joint(name)
            data.qpos[joint.qposadr[0]] = q
            data.qvel[joint.dofadr[0]] = qd
            qacc[joint.dofadr[0]] = qdd
        # What the plant applies: the recorded ripple at the sliders.
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[slots] = np.negative(mjcf.recorded_forces(
            recorded, data.qpos[slots], data.qvel[slots]))
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, mass)
        rhs = mass @ qacc + data.qfrc_bias - data.qfrc_passive \
            - data.qfrc_applied
        jacobian = data.efc_J.reshape(-1, model.nv)[data.efc_type == 0]
        solution = np.linalg.lstsq(np.hstack((jacobian.T, actuated)), rhs,
                                   rcond=None)[0]
        force = np.array(mechanics.solve(robot, position, velocity,
                                         acceleration).force)
        worst = max(worst, np.abs(solution[-3:] - force).max()
                    / np.abs(force).max())
    print(f'largest relative difference: {worst:.3g}')
    assert worst < 1e-6


def test_the_mujoco_plant_simulates_the_ripple_it_records():
    pytest.importorskip('mujoco')
    from orthoglide_ros.model.mujoco_plant import MujocoPlant
    robot = Robot(screw_lead=(0.005,) * 3, ripple_sine=(2.0, 1.5, -1.0),
                  ripple_cosine=(1.0, -2.0, 1.5))
    held = open_loop(MujocoPlant, robot, robot)
    left = open_loop(MujocoPlant, robot, robot.replace(**NONE))
    print(f'MuJoCo plant, 1 s open loop: {held:.3g} m with the ripple\'s '
          f'forces, {left:.3g} m without')
    assert held <= OPEN_LOOP_BOUND
    assert left >= LEFT_BOUND
    # A model given as text holds its own ripple: none without the data.
    plain = mjcf.mjcf(robot.replace(**NONE, screw_lead=(0.0,) * 3))
    position, velocity, force = (0.05, -0.03, 0.02), (0.0,) * 3, (
        10.0, -20.0, 300.0)
    given = MujocoPlant(robot, position, velocity, model_text=plain)
    own = MujocoPlant(robot.replace(**NONE), position, velocity)
    assert given.step(force, 1e-3).acceleration == pytest.approx(
        own.step(force, 1e-3).acceleration, abs=1e-12)


def test_a_model_recording_an_impossible_ripple_is_refused():
    pytest.importorskip('mujoco')
    from orthoglide_ros.model.mujoco_plant import check_model
    text = mjcf.mjcf(Robot(**RIPPLE)).replace(
        f'"{LEAD[0]!r} {LEAD[1]!r} {LEAD[2]!r}"', '"-0.005 0.004 0.006"')
    with pytest.raises(ValueError, match='robot.screw_lead'):
        check_model(text)


# --- identification ---

NOMINAL = Robot(screw_lead=(0.005,) * 3)
AMPLITUDES = {'ripple_sine': (0.5, -0.3, 0.2),
              'ripple_cosine': (0.2, 0.4, -0.6)}


def ripple_log(noise, robot=None):
    true = robot or TRUE.replace(screw_lead=(0.005,) * 3, **AMPLITUDES)
    return synthetic_log(true, 0, 6.0, 1, noise=noise)


def test_identify_recovers_the_amplitudes_of_a_synthetic_log():
    clean = identification.identify(
        NOMINAL, ripple_log(0.0), friction=identification.parse_law(
            'coulomb+ripple'), force_lag=0.0)
    for name, values in AMPLITUDES.items():
        assert getattr(clean.robot, name) == pytest.approx(values,
                                                           abs=2e-3)
    noisy = identification.identify(NOMINAL, ripple_log(0.5))
    assert 'ripple' in identification.law_name(noisy.law)
    for name, values in AMPLITUDES.items():
        assert getattr(noisy.robot, name) == pytest.approx(values, abs=0.05)
    assert any(name.startswith('ripple_cosine_c')
               for name in noisy.base.names)


def test_without_a_lead_no_ripple_law_is_tried_or_asked():
    log = ripple_log(0.5)
    found = identification.identify(Robot(), log)
    assert all('ripple' not in identification.law_name(c.law)
               for c in found.candidates)
    with pytest.raises(identification.IdentificationError,
                       match='robot.screw_lead'):
        identification.identify(Robot(), log, friction=(
            identification.parse_law('coulomb+ripple')))


def test_only_the_actuators_with_a_lead_have_ripple_parameters():
    nominal = Robot(screw_lead=(0.005, 0.0, 0.0))
    true = TRUE.replace(screw_lead=(0.005, 0.0, 0.0),
                        ripple_sine=(0.5, 0.0, 0.0),
                        ripple_cosine=(0.2, 0.0, 0.0))
    base = identification.base_parameters(
        nominal, identification.parse_law('coulomb+ripple'))
    ripple = [name for name in base.names if name.startswith('ripple')]
    assert ripple == ['ripple_sine_a', 'ripple_cosine_a']
    found = identification.identify(nominal, ripple_log(0.0, true),
                                    base=base, force_lag=0.0)
    assert found.robot.ripple_sine == pytest.approx((0.5, 0.0, 0.0),
                                                    abs=2e-3)


def test_validation_measures_the_ripple_left():
    """The nominal robot's misses it whole, the identified one's hardly."""
    log, other = ripple_log(0.5), synthetic_log(TRUE.replace(
        screw_lead=(0.005,) * 3, **AMPLITUDES), 1, 6.0, 2, duration=12.0)
    found = identification.identify(NOMINAL, log)
    nominal = identification.validate(NOMINAL, other, force_lag=0.0)
    fitted = identification.validate(found.robot, other, force_lag=0.0)
    print(f'ripple left: nominal {nominal.ripple_left}, identified '
          f'{fitted.ripple_left}')
    amplitude = np.hypot(AMPLITUDES['ripple_sine'],
                         AMPLITUDES['ripple_cosine'])
    assert nominal.ripple_left == pytest.approx(amplitude, rel=0.1)
    assert (fitted.ripple_left < 0.1 * amplitude).all()
    assert identification.validate(Robot(), other).ripple_left is None


def test_a_ripple_not_chosen_is_held_at_nominal_and_said():
    """A robot without ripple, a nominal one with a lead: none chosen."""
    found = identification.identify(NOMINAL, synthetic_log(TRUE, 0, 6.0, 1))
    assert 'ripple' not in identification.law_name(found.law)
    said = [s for s in found.held if 'screw ripple' in s]
    assert len(said) == 2 and all('kept at the nominal' in s for s in said)
    assert found.robot.ripple_sine == (0.0,) * 3


def test_the_cli_identifies_and_validates_the_ripple(capsys, tmp_path):
    params = tmp_path / 'nominal.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    robot.screw_lead: [0.005, 0.005, 0.005]\n')
    source = write_csv(tmp_path / 'log.csv', ripple_log(0.5))
    out = tmp_path / 'robot.yaml'
    code, stdout, err = run(capsys, 'identify', '--input', source,
                            '--params', params, '--output', out)
    assert code == 0, err
    assert 'screw ripple found, amplitude' in stdout
    from orthoglide_ros.formats import params_file
    robot = params_file.load_robot(out)
    assert robot.screw_lead == (0.005,) * 3
    assert robot.ripple_cosine == pytest.approx(
        AMPLITUDES['ripple_cosine'], abs=0.05)
    code, stdout, err = run(capsys, 'validate', '--input', source,
                            '--params', out)
    assert code == 0, err
    (line,) = [li for li in stdout.splitlines()
               if li.startswith('screw ripple left')]
    assert all(float(v) < 0.05 for v in line.split()[-3:])


# --- refusals ---

@pytest.mark.parametrize('values, name', [
    ({'screw_lead': (-0.005, 0.005, 0.005)}, 'screw_lead'),
    ({'screw_lead': (1e-5, 0.0, 0.0)}, 'screw_lead'),
    ({'screw_lead': (0.005, 0.005, math.inf)}, 'screw_lead'),
    ({'screw_lead': (0.005,) * 3, 'ripple_sine': (math.nan, 0.0, 0.0)},
     'ripple_sine'),
    ({'ripple_sine': (0.5, 0.0, 0.0)}, 'ripple_sine'),
    ({'screw_lead': (0.005, 0.0, 0.005), 'ripple_cosine': (0.1, 0.2, 0.3)},
     'ripple_cosine'),
], ids=['negative lead', 'lead too short', 'infinite lead', 'NaN amplitude',
        'amplitude without a lead', 'amplitude on an actuator without one'])
def test_a_ripple_no_robot_has_is_refused_naming_it(values, name):
    with pytest.raises(ParameterError) as error:
        Robot(**values)
    assert error.value.name == f'robot.{name}'


def test_the_cli_refuses_an_amplitude_without_a_lead(capsys, tmp_path):
    params = tmp_path / 'bad.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    robot.ripple_sine: [0.5, 0.0, 0.0]\n')
    code, out, err = run(capsys, 'mjcf', '--params', params, '--output',
                         tmp_path / 'x.xml')
    assert_bad_input(code, out, err, 'robot.ripple_sine', 'screw_lead')
    assert not (tmp_path / 'x.xml').exists()


def test_the_cli_refuses_a_ripple_law_without_a_lead(capsys, tmp_path):
    source = write_csv(tmp_path / 'log.csv', ripple_log(0.5))
    code, out, err = run(capsys, 'identify', '--input', source,
                         '--friction', 'coulomb+ripple', '--output',
                         tmp_path / 'x.yaml')
    assert_bad_input(code, out, err, 'robot.screw_lead')
    assert not (tmp_path / 'x.yaml').exists()
