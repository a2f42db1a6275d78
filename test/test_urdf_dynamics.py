"""
The URDF's masses and inertias proven by dynamics: Pinocchio's RNEA.

The URDF is loaded into Pinocchio (``pin``, an independent rigid-body
library). On the cut tree, with every joint's position, velocity and
acceleration from the model (``bodies.elements``: lambda, phi21, phi32
and their rates and accelerations), its RNEA gives the joint forces ``tau``
that the open tree needs. The cuts' constraint forces do no work on a motion
that keeps every loop closed, so the virtual work of ``tau`` over such a
motion is the actuators': ``J_lambda^T f = J_theta^T tau``, with
``J_theta = d theta / d r_G`` the Jacobian of every joint (sliders and
passive joints) with respect to the platform position, taken here by
complex step of eq. (9) in the independent reference model. The forces so
found equal ``mechanics.solve``'s to 1e-9 relative, on the paper's
trajectory (gravity) and on a fast one without gravity (inertia alone).
A robot with drives and a payload: its URDF's platform carries the
payload, and Pinocchio's ``Model.armature`` on the slider joints (URDF has
no place for it) gives the drives' forces. Two robots as built
(``robots_as_built``: every leg's axis, offset, bars and attachment off
the drawing): the URDF ``orthoglide urdf`` writes for each gives its
forces, to the same bound.
"""

from mechanics_reference import (
    COMPLEX_STEP, FAST_TRAJECTORIES, lambda_jacobian, leg_geometry)
import numpy as np
from orthoglide_ros.model import bodies, mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.urdf import moving_joints, urdf
from orthoglide_testing.robots_as_built import BUILT, FAR
import pytest
from urdf_harness import COMMITTED_URDF

pin = pytest.importorskip('pinocchio')

RELATIVE = 1e-9
# elements' keys of each LegJoints variable: value, rate, acceleration.
KEYS = {'lambda_': ('lambda', 'lambdadot', 'lambdaddot'),
        'phi21': ('phi21', 'omega21', 'epsilon21'),
        'phi32': ('phi32', 'omega32', 'epsilon32')}


@pytest.fixture(scope='module')
def model():
    return pin.buildModelFromXML(COMMITTED_URDF.read_text())


AS_BUILT = {'built': BUILT, 'far': FAR}


@pytest.fixture(scope='module')
def as_built():
    """``(robot, model)`` of AS_BUILT[which]: its URDF in Pinocchio."""
    made = {}

    def make(which):
        if which not in made:
            robot = Robot(**AS_BUILT[which])
            made[which] = robot, pin.buildModelFromXML(urdf(robot))
        return made[which]
    return make


def joint_index(model, name):
    return model.joints[model.getJointId(name)].idx_q


def joint_state(model, robot, position, velocity, acceleration):
    """q, v, a of every joint from the model's elements."""
    legs = bodies.elements(robot, position, velocity, acceleration)
    q, v, a = (np.zeros(model.nv) for _ in range(3))
    for name, leg, variable in moving_joints():
        i = joint_index(model, name)
        value, rate, accel = KEYS[variable]
        q[i], v[i], a[i] = (legs[leg][value], legs[leg][rate],
                            legs[leg][accel])
    return q, v, a


def joint_jacobian(model, robot, position):
    """J_theta = d theta / d r_G (nv x 3), complex step of eq. (9)."""
    jac = np.zeros((model.nv, 3))
    for column in range(3):
        shifted = np.asarray(position, complex)
        shifted[column] += 1j * COMPLEX_STEP
        for name, leg, variable in moving_joints():
            g = leg_geometry(robot, leg, shifted)
            value = {'lambda_': g.lam, 'phi21': np.arcsin(g.sin21),
                     'phi32': np.arcsin(g.sin32)}[variable]
            jac[joint_index(model, name), column] = value.imag / COMPLEX_STEP
    return jac


def urdf_forces(model, robot, position, velocity, acceleration):
    """Actuator forces (N) from Pinocchio's RNEA by virtual work."""
    model.gravity.linear = np.array(robot.gravity)
    q, v, a = joint_state(model, robot, position, velocity, acceleration)
    tau = pin.rnea(model, model.createData(), q, v, a)
    generalised = joint_jacobian(model, robot, position).T @ tau
    return np.linalg.solve(lambda_jacobian(robot, position).T, generalised)


def check(model, robot, samples):
    worst = 0.0
    for p, v, a in samples:
        expected = np.array(mechanics.solve(robot, p, v, a).force)
        got = urdf_forces(model, robot, p, v, a)
        worst = max(worst, np.abs(got - expected).max()
                    / np.abs(expected).max())
    print(f'RNEA vs mechanics.solve: worst {worst:.2g} relative')
    assert worst <= RELATIVE, worst


def test_tree_has_every_moving_joint(model):
    names = {model.names[i] for i in range(1, model.njoints)}
    assert names == {name for name, _, _ in moving_joints()}
    assert model.nq == model.nv == 18


def test_rnea_gives_the_models_forces_on_the_paper_trajectory(model):
    times = trajectory.paper_times(21)
    check(model, Robot(), zip(*trajectory.paper_batch(times)))


@pytest.mark.parametrize('target, omega', FAST_TRAJECTORIES)
def test_rnea_gives_the_models_forces_fast_without_gravity(model, target,
                                                           omega):
    robot = Robot(gravity=(0.0, 0.0, 0.0))
    times = np.linspace(0.0, 2.0 * np.pi / omega, 13)
    check(model, robot, zip(*trajectory.paper_batch(times, target, omega)))


@pytest.mark.slow     # its URDF: 6-9 s of CPU, one process, 2026-12-06
@pytest.mark.parametrize('which', list(AS_BUILT))
def test_rnea_gives_a_robot_as_builts_forces(as_built, which):
    """The paper's trajectory (gravity), then a fast one without gravity."""
    robot, model = as_built(which)
    times = trajectory.paper_times(21)
    check(model, robot, zip(*trajectory.paper_batch(times)))
    target, omega = FAST_TRAJECTORIES[2]
    times = np.linspace(0.0, 2.0 * np.pi / omega, 13)
    check(model, robot.replace(gravity=(0.0, 0.0, 0.0)),
          zip(*trajectory.paper_batch(times, target, omega)))


def test_rnea_statics_at_home(model):
    """At rest at home the URDF holds the model's hand statics (256.53 N)."""
    robot = Robot()
    force = urdf_forces(model, robot, (0.0, 0.0, 0.0), (0.0,) * 3, (0.0,) * 3)
    assert np.allclose(force, (0.0, 0.0, 256.5315), atol=1e-3)


def test_rnea_with_pinocchios_armature_gives_the_drives_forces():
    robot = Robot(armature=(3.2, 1.1, 0.45), payload=5.0)
    model = pin.buildModelFromXML(urdf(robot))
    armature = np.zeros(model.nv)
    for name, leg, variable in moving_joints():
        if variable == 'lambda_':
            armature[joint_index(model, name)] = robot.armature['ABC'.index(
                leg)]
    model.armature = armature
    target, omega = FAST_TRAJECTORIES[0]
    times = np.linspace(0.0, 2.0 * np.pi / omega, 13)
    check(model, robot, zip(*trajectory.paper_batch(times, target, omega)))
    # Without it the URDF alone is the robot without drives.
    model.armature = np.zeros(model.nv)
    p, v, a = (x[3] for x in trajectory.paper_batch(times, target, omega))
    assert np.abs(urdf_forces(model, robot, p, v, a) - np.array(
        mechanics.solve(robot.replace(armature=(0.0,) * 3), p, v, a).force)
    ).max() <= RELATIVE * 1e3
