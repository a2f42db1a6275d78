"""
The MJCF (orthoglide_ros.model.mjcf) against MuJoCo, an engine no one here wrote.

On the paper's robot and on two robots as built (``robots_as_built``:
every leg's axis, offset, bars and attachment off the drawing):

- The committed ``mjcf/orthoglide.xml`` is what ``orthoglide mjcf`` writes
  for the paper's robot; it loads; its names, actuators and total mass are
  the contract's (doc/mujoco.md); qpos0 is home (the platform at the
  origin), closed, each joint at its value there (0 on the drawing's).
- Kinematics: with the joints of the closed form (eqs. 9, 5) the
  constraints hold to 1e-12 m and the platform body is at G.
- Dynamics, rigid: MuJoCo's mass matrix, bias and constraint Jacobian,
  projected (``M qacc + c - passive = J^T mu + B f``, solved for the
  actuator forces ``f`` with the qacc of the closed form), give the
  package's forces (eq. 25, viscous friction included) to 1e-6 relative at
  random states of several robots.
- Forward dynamics, rigid: the platform's acceleration under random
  forces at random states from MuJoCo's own mass matrix, bias and loop
  Jacobian with the loops held rigidly is the package's
  (``mechanics.forward_dynamics``) to 1e-8 relative.
- Dynamics, simulated: the package's forces applied open loop from home at
  rest keep the platform on eq. (6) within 0.05 mm after 1 s, and the
  loops stay closed to 1e-5 m over the whole motion (the robot is open-loop
  unstable: errors grow about e-fold every 0.28 s, so this is strict).
- A model file the simulator is given (``mjcf_file``) must have the legs
  of its ``robot.*``, which its workspace checks use: one of another
  robot's legs is refused, one of other masses or lengths taken.
- Friction MuJoCo's joints cannot hold (a Coulomb level per direction, a
  Stribeck excess): the sliders' ``frictionloss`` is the mean Coulomb
  level, and ``MujocoPlant`` applies the rest as forces, so that its
  acceleration differs from that of the same MJCF without them by what
  the package's forward dynamics says the rest does.
"""

import subprocess
import sys

import numpy as np
import pytest

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.mjcf import joint_values, mjcf
from orthoglide_ros.model.robot import JOINT_NAMES, Robot
from orthoglide_ros.model.trajectory import PAPER_DURATION, paper_sample
from orthoglide_testing.robots_as_built import BUILT, FAR

mujoco = pytest.importorskip('mujoco')

ROOT = __import__('pathlib').Path(__file__).resolve().parents[1]
COMMITTED = ROOT / 'mjcf' / 'orthoglide.xml'
PAPER = Robot()
# Each leg's geometry: the drawing's, and two robots as built.
GEOMETRIES = {'drawing': {}, 'built': BUILT, 'far': FAR}
ROBOTS = {name: Robot(**rows) for name, rows in GEOMETRIES.items()}
OPEN_LOOP_BOUND = 5e-5      # m after 1 s (0.05 mm)
CLOSURE_BOUND = 1e-5        # m over the simulated motion
FORWARD_DYNAMICS_BOUND = 1e-8  # relative


def load(robot=PAPER, **kwargs):
    model = mujoco.MjModel.from_xml_string(mjcf(robot, **kwargs))
    return model, mujoco.MjData(model)


def set_state(model, data, robot, position, velocity=(0.0,) * 3,
              acceleration=(0.0,) * 3):
    """Set qpos and qvel from the closed form; return qacc."""
    qacc = np.zeros(model.nv)
    for name, (q, qd, qdd) in joint_values(robot, position, velocity,
                                           acceleration).items():
        joint = model.joint(name)
        data.qpos[joint.qposadr[0]] = q
        data.qvel[joint.dofadr[0]] = qd
        qacc[joint.dofadr[0]] = qdd
    mujoco.mj_forward(model, data)
    return qacc


def closure(data):
    return float(np.abs(data.efc_pos[data.efc_type == 0]).max())


def test_committed_mjcf_is_what_the_generator_writes():
    assert COMMITTED.read_text() == mjcf(PAPER), (
        'mjcf/orthoglide.xml is stale: run orthoglide mjcf --output '
        'mjcf/orthoglide.xml')


def test_the_contract_names_and_mass():
    model = mujoco.MjModel.from_xml_path(str(COMMITTED))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert [model.actuator(i).name for i in range(model.nu)] == \
        list(JOINT_NAMES)
    for i, name in enumerate(JOINT_NAMES):
        assert model.actuator(i).trntype == mujoco.mjtTrn.mjTRN_JOINT
        assert model.actuator_trnid[i, 0] == model.joint(name).id
        assert model.actuator_gear[i, 0] == 1.0
        assert model.jnt_type[model.joint(name).id] == \
            mujoco.mjtJoint.mjJNT_SLIDE
        assert not model.actuator_ctrllimited[i]
    masses = PAPER
    total = 3 * (masses.m1 + masses.m2 + masses.m3 + masses.m4
                 + masses.m6) + masses.m5
    assert model.body_mass.sum() == pytest.approx(total, rel=1e-12)
    assert np.allclose(model.opt.gravity, PAPER.gravity)
    assert closure(data) < 1e-12
    assert np.abs(data.body('platform').xpos).max() < 1e-12
    limited, _ = load(force_limit=500.0)
    assert limited.actuator_ctrllimited.all()
    assert np.allclose(limited.actuator_ctrlrange, [[-500.0, 500.0]] * 3)


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_qpos0_is_home_closed_each_joint_at_its_value_there(geometry):
    """The bodies as written: G at the origin, qpos0 the model's joints."""
    robot = ROBOTS[geometry]
    model, data = load(robot)
    mujoco.mj_forward(model, data)
    assert closure(data) < 1e-12
    assert np.abs(data.body('platform').xpos).max() < 1e-12
    home = joint_values(robot, (0.0, 0.0, 0.0))
    assert {name: float(model.qpos0[model.joint(name).qposadr[0]])
            for name in home} == {name: q for name, (q, _, _)
                                  in home.items()}
    if geometry == 'drawing':
        assert not model.qpos0.any()
    else:
        assert np.abs(model.qpos0).min() > 0.0


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_closed_form_joints_close_the_loops_and_place_the_platform(geometry):
    robot = ROBOTS[geometry]
    model, data = load(robot)
    for t in np.linspace(0.0, PAPER_DURATION, 21):
        position = paper_sample(t)[0]
        set_state(model, data, robot, position)
        assert closure(data) < 1e-12
        assert np.allclose(data.body('platform').xpos, position,
                           rtol=0.0, atol=1e-12)


def robots(rng, count, geometry=None):
    """
    Random robots; with a ``geometry``'s rows, as built (its bars).

    Then ``l3`` within 0.1 m of its bars (0.84-0.86 m), as a robot takes.
    """
    lengths = (0.7, 1.0) if geometry is None else (0.77, 0.94)
    for _ in range(count):
        yield Robot(m1=rng.uniform(0.1, 1.0), m2=rng.uniform(0.05, 0.5),
                    m3=rng.uniform(1.0, 4.0), m4=rng.uniform(0.05, 0.5),
                    m5=rng.uniform(5.0, 30.0), m6=rng.uniform(1.0, 4.0),
                    l=rng.uniform(0.1, 0.3), l3=rng.uniform(*lengths),
                    friction_viscous=tuple(rng.uniform(0.0, 50.0, 3)),
                    armature=tuple(rng.uniform(0.0, 4.0, 3)),
                    payload=rng.uniform(0.0, 10.0), **(geometry or {}))


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_mujoco_rigid_projection_gives_the_package_forces(geometry):
    rng = np.random.default_rng(7)
    worst = 0.0
    for robot in robots(rng, 4, GEOMETRIES[geometry]):
        model, data = load(robot)
        actuated = np.zeros((model.nv, 3))
        for column, name in enumerate(JOINT_NAMES):
            actuated[model.joint(name).dofadr[0], column] = 1.0
        mass = np.zeros((model.nv, model.nv))
        for _ in range(6):
            position = rng.uniform(-0.12, 0.12, 3)
            velocity = rng.uniform(-0.5, 0.5, 3)
            acceleration = rng.uniform(-5.0, 5.0, 3)
            qacc = set_state(model, data, robot, position, velocity,
                             acceleration)
            mujoco.mj_fullM(model, data, mass)
            rhs = mass @ qacc + data.qfrc_bias - data.qfrc_passive
            jacobian = data.efc_J.reshape(-1, model.nv)[data.efc_type == 0]
            solution = np.linalg.lstsq(np.hstack((jacobian.T, actuated)),
                                       rhs, rcond=None)[0]
            force = np.array(mechanics.solve(robot, position, velocity,
                                             acceleration).force)
            worst = max(worst, np.abs(solution[-3:] - force).max()
                        / np.abs(force).max())
    print(f'largest relative difference: {worst:.3g}')
    assert worst < 1e-6


def equality_jacobian(model, data):
    """Return the rows of MuJoCo's constraint Jacobian of the connects."""
    return data.efc_J.reshape(-1, model.nv)[data.efc_type == 0].copy()


def rigid_platform_acceleration(model, data, force, step=1e-6):
    """
    Return the platform's acceleration with the loops held rigid (m/s^2).

    MuJoCo's own mass matrix ``M``, bias ``c``, passive forces and loop
    Jacobian ``J`` at the state set: ``M qacc - J^T mu = B f + passive - c``
    with ``J qacc = -Jdot qvel`` (``Jdot qvel`` by central differences of
    ``J qvel`` along ``qvel``, ``step`` s), solved by least squares (legs B
    and C meet the platform in two connects: redundant rows); the platform
    body's acceleration from that ``qacc`` by MuJoCo
    (``mj_rnePostConstraint``, less its world's -gravity).
    """
    qpos, qvel = data.qpos.copy(), data.qvel.copy()
    moved = []
    for sign in (1.0, -1.0):
        data.qpos[:] = qpos
        mujoco.mj_integratePos(model, data.qpos, qvel, sign * step)
        mujoco.mj_forward(model, data)
        moved.append(equality_jacobian(model, data) @ qvel)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    jacobian = equality_jacobian(model, data)
    applied = np.zeros(model.nv)
    for name, f in zip(JOINT_NAMES, force):
        applied[model.joint(name).dofadr[0]] = f
    rows = len(jacobian)
    solution = np.linalg.lstsq(
        np.block([[mass, -jacobian.T], [jacobian, np.zeros((rows, rows))]]),
        np.concatenate((applied + data.qfrc_passive - data.qfrc_bias,
                        -(moved[0] - moved[1]) / (2.0 * step))),
        rcond=None)[0]
    data.qacc[:] = solution[:model.nv]
    mujoco.mj_rnePostConstraint(model, data)
    acceleration = np.zeros(6)
    mujoco.mj_objectAcceleration(model, data, mujoco.mjtObj.mjOBJ_BODY,
                                 model.body('platform').id, acceleration, 0)
    return acceleration[3:] + model.opt.gravity


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_mujoco_forward_dynamics_is_the_packages(geometry):
    """The platform's acceleration under random forces at random states."""
    rng = np.random.default_rng(5)
    worst = 0.0
    for robot in robots(rng, 3, GEOMETRIES[geometry]):
        model, data = load(robot)
        for _ in range(5):
            position = rng.uniform(-0.12, 0.12, 3)
            velocity = rng.uniform(-0.5, 0.5, 3)
            force = rng.uniform(-300.0, 300.0, 3)
            set_state(model, data, robot, position, velocity)
            got = rigid_platform_acceleration(model, data, force)
            expected = np.array(mechanics.forward_dynamics(
                robot, position, velocity, force))
            worst = max(worst, np.abs(got - expected).max()
                        / np.abs(expected).max())
    print(f'{geometry}: largest relative difference {worst:.3g}')
    assert worst < FORWARD_DYNAMICS_BOUND


def open_loop(robot=PAPER, plant=None, duration=PAPER_DURATION):
    """Apply the package's forces (midpoint of each step); return errors."""
    model, data = load(plant or robot)
    mujoco.mj_forward(model, data)
    step = model.opt.timestep
    times, errors, closures = [], [], []
    for k in range(round(duration / step)):
        data.ctrl[:] = mechanics.solve(robot,
                                       *paper_sample((k + 0.5) * step)).force
        mujoco.mj_step(model, data)
        times.append((k + 1) * step)
        errors.append(np.linalg.norm(data.body('platform').xpos
                                     - paper_sample(times[-1])[0]))
        closures.append(closure(data))
    return np.array(times), np.array(errors), max(closures)


@pytest.mark.parametrize('geometry', list(GEOMETRIES))
def test_the_package_forces_drive_mujoco_along_eq_6(geometry):
    times, errors, worst_closure = open_loop(ROBOTS[geometry])
    at = {t: errors[np.argmin(np.abs(times - t))] for t in (0.5, 1.0, 2.0)}
    figures = ', '.join(f'{e * 1e6:.2f} um at {t:g} s'
                        for t, e in at.items())
    print(f'{geometry}, open loop: {figures}; loops closed to '
          f'{worst_closure:.2g} m')
    assert errors[times <= 1.0].max() <= OPEN_LOOP_BOUND
    assert worst_closure <= CLOSURE_BOUND


def test_a_two_percent_heavier_platform_leaves_it():
    """The open-loop bound is tight: MuJoCo's robot 2 % off the model."""
    times, errors, _ = open_loop(plant=PAPER.replace(m5=PAPER.m5 * 1.02),
                                 duration=1.0)
    assert errors[times <= 1.0].max() > OPEN_LOOP_BOUND


def test_cli_writes_a_model_mujoco_loads(tmp_path):
    params = tmp_path / 'robot.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    robot.m5: 20.0\n')
    out = tmp_path / 'robot.xml'
    done = subprocess.run(
        [sys.executable, '-m', 'orthoglide_ros.tools.cli', 'mjcf',
         '--params', str(params), '--joint-names', 'ja', 'jb', 'jc',
         '--output', str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.actuator(0).name == 'ja'
    assert model.body('platform').mass[0] == 20.0


def test_the_armature_is_each_slide_joints_and_the_payload_the_platforms(
        tmp_path):
    """robot.armature into MuJoCo's slide joints; --armature sets it."""
    params = tmp_path / 'drives.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    robot.armature: [3.2, 1.1, 0.45]\n'
                      '    robot.payload: 5.0\n')
    out = tmp_path / 'drives.xml'
    for extra, armature in (((), (3.2, 1.1, 0.45)),
                            (('--armature', '0.5', '0', '2'),
                             (0.5, 0.0, 2.0))):
        done = run_cli('mjcf', '--params', str(params), '--output', str(out),
                       *extra)
        assert done.returncode == 0, done.stderr
        model = mujoco.MjModel.from_xml_path(str(out))
        assert [model.dof_armature[model.joint(name).dofadr[0]]
                for name in JOINT_NAMES] == list(armature)
        assert model.body('platform').mass[0] == PAPER.m5 + 5.0
        hinges = [model.dof_armature[model.jnt_dofadr[i]]
                  for i in range(model.njnt) if model.joint(i).name
                  not in JOINT_NAMES]
        assert not any(hinges)


def run_cli(*args, env=None):
    import os
    return subprocess.run([sys.executable, '-m', 'orthoglide_ros.tools.cli',
                           *args], capture_output=True, text=True,
                          env=dict(os.environ, **(env or {})))


def test_render_writes_a_picture_of_the_robot(tmp_path):
    """Through the offscreen renderer (EGL), or one line and exit 2."""
    out = tmp_path / 'robot.png'
    done = run_cli('render', '--position', '0.1', '0.05', '-0.1',
                   '--size', '320', '240', '--output', str(out))
    if done.returncode == 2 and 'no OpenGL backend' in done.stderr:
        pytest.skip(done.stderr.strip())
    assert done.returncode == 0, done.stderr
    from PIL import Image
    image = np.asarray(Image.open(out).convert('RGB'), dtype=float)
    assert image.shape == (240, 320, 3)
    # The robot, not an empty sky: many pixels far from the background's.
    assert (np.abs(image - np.median(image, axis=(0, 1))).sum(-1)
            > 60).mean() > 0.02


def test_render_without_a_backend_is_one_line_and_exit_2(tmp_path):
    done = run_cli('render', '--position', '0', '0', '0', '--output',
                   str(tmp_path / 'x.png'), env={'MUJOCO_GL': 'no-such-gl'})
    assert done.returncode == 2, done.stderr
    assert done.stderr.count('\n') == 1 and 'Traceback' not in done.stderr
    assert not (tmp_path / 'x.png').exists()


def test_render_refuses_an_unreachable_point(tmp_path):
    done = run_cli('render', '--position', '5', '0', '0', '--output',
                   str(tmp_path / 'x.png'))
    assert done.returncode == 2 and 'Traceback' not in done.stderr


def test_render_animates_the_paper_trajectory(tmp_path):
    """A .gif output: one frame per sample of eq. (6), the robot moving."""
    out = tmp_path / 'robot.gif'
    done = run_cli('render', '--frames', '5', '--size', '160', '120',
                   '--output', str(out))
    if done.returncode == 2 and 'no OpenGL backend' in done.stderr:
        pytest.skip(done.stderr.strip())
    assert done.returncode == 0, done.stderr
    from PIL import Image, ImageSequence
    frames = [np.asarray(f.convert('RGB'), dtype=float)
              for f in ImageSequence.Iterator(Image.open(out))]
    assert len(frames) == 5
    assert np.abs(frames[0] - frames[2]).mean() > 0.1     # it moved


@pytest.mark.parametrize('model_rows, robot_rows, accepted', [
    (BUILT, BUILT, True),
    (BUILT, {}, False),
    ({}, BUILT, False),
    # A tilt alone moves nothing at home: seen away from it.
    ({'axis_direction_b': FAR['axis_direction_b']}, {}, False),
    # The other lengths and the masses are the file's own.
    ({'l': 0.13, 'l1': 0.21, 'l2': 0.11, 'alpha': 0.61, 'm5': 20.0}, {},
     True),
])
def test_a_model_file_must_have_the_robots_legs(tmp_path, model_rows,
                                                robot_rows, accepted):
    """The simulator's mjcf_file: its legs those of its robot.*."""
    from orthoglide_ros.cores import simulator
    path = tmp_path / 'model.xml'
    path.write_text(mjcf(Robot(**model_rows)))
    values = {'engine': 'mujoco', 'mjcf_file': str(path),
              **{f'robot.{k}': list(v) for k, v in robot_rows.items()}}
    if accepted:
        simulator.PARAMETERS.parse(values)
    else:
        with pytest.raises(ValueError, match='^mjcf_file: its legs are not '
                           'those of robot'):
            simulator.PARAMETERS.parse(values)


def test_friction_mujoco_cannot_hold_is_applied_by_the_plant():
    from orthoglide_ros.model.mujoco_plant import MujocoPlant
    robot = Robot(friction_viscous=(20.0, 30.0, 10.0),
                  friction_coulomb=(6.0, 9.0, 3.5),
                  friction_coulomb_negative=(2.0, 12.0, 7.0),
                  friction_stribeck=(8.0, 5.0, 6.0),
                  friction_stribeck_velocity=0.05)
    model, _ = load(robot)
    assert [float(model.joint(n).frictionloss[0]) for n in JOINT_NAMES] \
        == pytest.approx([4.0, 10.5, 5.25], rel=1e-12)
    mean = (4.0, 10.5, 5.25)      # N: each slider's two levels' mean
    plain = robot.replace(friction_coulomb=mean,
                          friction_coulomb_negative=mean,
                          friction_stribeck=(0.0,) * 3)
    rng = np.random.default_rng(1)
    position = (0.05, -0.03, 0.02)
    for _ in range(5):
        velocity = tuple(rng.uniform(-0.1, 0.1, 3))
        force = tuple(rng.uniform(-30.0, 30.0, 3))
        with_rest = MujocoPlant(robot, position, velocity).step(force, 2e-4)
        without = MujocoPlant(robot, position, velocity,
                              model_text=mjcf(robot)).step(force, 2e-4)
        got = np.subtract(with_rest.acceleration, without.acceleration)
        expected = np.subtract(
            mechanics.forward_dynamics(robot, position, velocity, force),
            mechanics.forward_dynamics(plain, position, velocity, force))
        assert np.abs(got - expected).max() <= 0.01 * np.abs(expected).max()
