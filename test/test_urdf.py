"""
The URDF (orthoglide_ros.model.urdf) read by an independent library, yourdfpy.

- The committed ``urdf/orthoglide.urdf`` is what ``orthoglide urdf`` writes
  for the paper's robot (so it cannot drift).
- Names and tree: the links and joints doc/mechanism_state_publisher.md
  fixes, a cut tree.
- Masses, centres and inertias equal doc/model.md's bodies table, written
  out here (each leg's bars of its own length); the total mass is the
  model's.
- Kinematics, on the paper's robot, another one and two robots as built
  (``robots_as_built``: every leg's geometry off the drawing): each slider
  runs on its leg's axis from where its reading is 0; with the joint
  state of ``mechanism_state_publisher.joint_state``, on random reachable
  configurations and on the paper's trajectory, yourdfpy's forward
  kinematics puts ``platform`` at G (``mechanics.forward_kinematics`` of
  the sliders) with frame 0's orientation, each ``x_leg_end`` on its
  ``x_platform_mount`` and the parallelogram's two A7 frames together, to
  1e-9 m and 1e-9 rad; every body's frame is where ``bodies.elements`` and
  the independent model of ``mechanics_reference`` put it.
- Joint limits, each leg's own, hold every state of the workspace within
  the margin, and are near its extremes.
"""

import math

from mechanics_reference import (
    CUBE, DRAWING_AXIS, leg_frame, leg_geometry, LEGS, OTHER_ROBOT_VALUES)
import numpy as np
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.bodies import elements, leg_joints
from orthoglide_ros.cores.mechanism_state_publisher import joint_state
from orthoglide_ros.cores.parameters import JOINT_NAMES
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.urdf import joint_limits, link_name, moving_joints, \
    rpy, urdf
from orthoglide_testing.robots_as_built import BUILT, FAR
import pytest
from urdf_harness import COMMITTED_URDF, cut_errors, load, TOLERANCE

PAPER = Robot()
OTHER = Robot(**OTHER_ROBOT_VALUES)
ROBOTS = {'paper': PAPER, 'other': OTHER, 'built': Robot(**BUILT),
          'far': Robot(**FAR)}
OTHER_NAMES = ('ja', 'jb', 'jc')
# Their URDFs take 6-9 s of CPU each (three legs' joint limits), one
# process, 2026-12-06: slow, whichever test asks first.
AS_BUILT = [pytest.param(which, marks=pytest.mark.slow)
            for which in ('built', 'far')]


def names_of(which):
    """Return the sliders' names of a robot's URDF here."""
    return OTHER_NAMES if which == 'other' else JOINT_NAMES


@pytest.fixture(scope='module')
def models():
    """``model(which)``: the URDF of ROBOTS[which], loaded once."""
    made = {}

    def model(which):
        if which not in made:
            made[which] = load(COMMITTED_URDF.read_text() if which == 'paper'
                               else urdf(ROBOTS[which], names_of(which)))
        return made[which]
    return model


@pytest.fixture(scope='module')
def paper_model(models):
    return models('paper')


@pytest.fixture(scope='module')
def other_model(models):
    return models('other')


def test_committed_urdf_is_what_the_generator_writes():
    assert COMMITTED_URDF.read_text() == urdf(PAPER), (
        'urdf/orthoglide.urdf is stale: run orthoglide urdf --output '
        'urdf/orthoglide.urdf')


# Names and tree ----------------------------------------------------------
def test_names_and_tree(paper_model):
    robot = paper_model.robot
    joints = {j.name: j for j in robot.joints}
    assert paper_model.base_link == 'base_link'
    assert {j.name for j in robot.joints if j.type != 'fixed'} == {
        name for name, _, _ in moving_joints()}
    for name, leg in zip(JOINT_NAMES, 'abc'):
        slider = joints[name]
        assert (slider.type, slider.parent, slider.child) == (
            'prismatic', 'base_link', f'{leg}_slider')
    for leg in 'abc':
        # x_leg_end: the child of the leg's last revolute joint.
        last = joints[f'{leg}_phi54']
        assert (last.type, last.child) == ('revolute', f'{leg}_leg_end')
        mount = joints[f'{leg}_platform_mount_joint']
        assert (mount.type, mount.parent, mount.child) == (
            'fixed', 'platform', f'{leg}_platform_mount')
        for side, body in (('bar', 'bar_a6a7'), ('rod', 'rod_a4a7')):
            cut = joints[f'{leg}_a7_{side}_joint']
            assert (cut.type, cut.parent) == ('fixed', f'{leg}_{body}')
    # Leg A carries the platform; legs B and C end at their cut.
    assert joints['platform_joint'].parent == 'a_leg_end'
    assert not [j for j in robot.joints
                if j.parent in ('b_leg_end', 'c_leg_end')]
    # A tree: every link but base_link is the child of exactly one joint.
    children = [j.child for j in robot.joints]
    assert sorted(children) == sorted(
        link.name for link in robot.links if link.name != 'base_link')


@pytest.mark.parametrize('which', ['paper', *AS_BUILT])
def test_each_slider_runs_on_its_axis_from_where_it_reads_zero(which,
                                                               models):
    """
    Joint value 0 is the reading 0, +lambda along the leg's direction.

    Every joint at 0: ``x_slider`` (A1) at ``a + (e - l1 cos(alpha) - L -
    l/2) u`` (eqs. 1-3 from the leg's axis point, the slider at its true
    position ``e``, written out from the rows); 0.1 further along ``u``
    for a reading of 0.1 m. On the paper's robot A1 lies on -x0, -y0, -z0
    and moves along +x0, +y0, +z0.
    """
    robot, model = ROBOTS[which], models(which)
    for name, leg in zip(JOINT_NAMES, LEGS):
        frame = leg_frame(robot, leg)
        axis = frame.rotation @ DRAWING_AXIS[leg]
        zero = frame.point + (frame.offset - robot.l1 * math.cos(robot.alpha)
                              - frame.length - robot.l / 2.0) * axis
        model.update_cfg({n: 0.0 for n in model.actuated_joint_names})
        at_zero = model.get_transform(f'{leg.lower()}_slider')[:3, 3]
        model.update_cfg({name: 0.1})
        moved = model.get_transform(f'{leg.lower()}_slider')[:3, 3]
        assert np.allclose(at_zero, zero, rtol=0, atol=1e-11)
        assert np.allclose(moved - at_zero, 0.1 * axis, rtol=0, atol=1e-12)
        if which == 'paper':
            assert np.array_equal(axis, DRAWING_AXIS[leg])


def test_joint_names_follow_the_parameter(other_model):
    names = other_model.actuated_joint_names
    assert {'ja', 'jb', 'jc'} <= set(names)
    assert not {'slider_a', 'slider_b', 'slider_c'} & set(names)


# Masses and inertias -----------------------------------------------------
def model_table(robot):
    """doc/model.md's bodies table: link -> (mass, centre, inertia)."""
    l2 = robot.l2
    sa, ca = math.sin(robot.alpha), math.cos(robot.alpha)
    rod2 = robot.m2 * l2 * l2 / 12.0
    rod4 = robot.m4 * l2 * l2 / 12.0
    table = {'platform': (robot.m5, (0, 0, 0),
                          np.eye(3) * robot.m5 * robot.l ** 2 / 6.0)}
    for leg, l3 in zip('abc', robot.bar_length):    # each leg's own bars
        bar3, bar6 = robot.m3 * l3 * l3 / 12.0, robot.m6 * l3 * l3 / 12.0
        table.update({
            # Body 1 translates: the model gives it no inertia (zero here).
            f'{leg}_slider': (robot.m1, (0, robot.l1 * sa / 2,
                                         robot.l1 * ca / 2), np.zeros((3, 3))),
            f'{leg}_rod_a3a6': (robot.m2, (0, 0, 0),
                                np.diag((rod2, rod2, 0.0))),
            f'{leg}_bar_a3a4': (robot.m3, (0, -l3 / 2, 0),
                                np.diag((bar3, 0.0, bar3))),
            f'{leg}_bar_a6a7': (robot.m6, (0, -l3 / 2, 0),
                                np.diag((bar6, 0.0, bar6))),
            f'{leg}_rod_a4a7': (robot.m4, (l2 / 2, 0, 0),
                                np.diag((0.0, rod4, rod4))),
        })
    return table


@pytest.mark.parametrize('which', ['paper', 'other', *AS_BUILT])
def test_masses_centres_and_inertias_are_the_models(which, models):
    robot, model = ROBOTS[which], models(which)
    table = model_table(robot)
    links = {link.name: link for link in model.robot.links}
    assert {name for name, link in links.items()
            if link.inertial is not None} == set(table)
    for name, (mass, centre, inertia) in table.items():
        inertial = links[name].inertial
        assert inertial.mass == pytest.approx(mass, rel=1e-11)
        assert np.allclose(inertial.origin[:3, 3], centre, rtol=0,
                           atol=1e-12)
        assert np.allclose(inertial.origin[:3, :3], np.eye(3))
        assert np.allclose(inertial.inertia, inertia, rtol=1e-11,
                           atol=1e-15)
    total = robot.m5 + 3 * (robot.m1 + robot.m2 + robot.m3 + robot.m4
                            + robot.m6)
    assert sum(link.inertial.mass for link in links.values()
               if link.inertial is not None) == pytest.approx(total,
                                                              rel=1e-12)


# Kinematics --------------------------------------------------------------
def on_home_branch(robot, points):
    """
    Whether each point lies within the margin where a robot from home goes.

    Those the forward kinematics gives back: the others lie beyond a
    singularity of J2 (another assembly mode of the same sliders).
    """
    inside = np.zeros(len(points), dtype=bool)
    ok = mechanics.workspace_status(robot, points).ok
    lam = mechanics.solve_batch(robot, points[ok], margin=0.0).lambda_
    back, found = mechanics.forward_kinematics_rows(robot, lam)
    inside[ok] = found & (np.abs(back - points[ok]).max(-1) < 1e-9)
    return inside


def home_branch(robot, points):
    """Keep the points :func:`on_home_branch`."""
    return points[on_home_branch(robot, points)]


def workspace_samples(robot, seed):
    """
    Points of the workspace within the margin, inside and on its edge.

    200000 uniform in the cube ``|x|, |y|, |z| < l3`` kept on the home
    branch, and the edge where 200 rays from each of 200 of them leave it
    (bisection to 1e-12 m): where the joint variables take their extremes.
    """
    rng = np.random.default_rng(seed)
    points = home_branch(robot, rng.uniform(-robot.l3, robot.l3,
                                            (200000, 3)))
    centres = np.repeat(points[rng.choice(len(points), 200, replace=False)],
                        200, 0)
    rays = rng.normal(size=centres.shape)
    rays /= np.linalg.norm(rays, axis=1)[:, None]
    inside = np.zeros(len(rays))
    outside = np.full(len(rays), 1.9 * robot.l3)    # beyond any reach
    for _ in range(40):
        middle = (inside + outside) / 2.0
        ok = on_home_branch(robot, centres + middle[:, None] * rays)
        inside, outside = (np.where(ok, middle, inside),
                           np.where(ok, outside, middle))
    return np.vstack((points, centres + inside[:, None] * rays))


def reachable_positions(robot, count, seed):
    """Random platform positions in the cube and beyond, within the margin."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-0.6 * robot.l3, 0.6 * robot.l3, (20 * count, 3))
    return home_branch(robot, points)[:count]


def check_state(model, robot, names, lam, lamd=None):
    """Solve the joint state of the sliders; check it closes every cut."""
    state = joint_state(robot, names, lam, lamd)
    centre = mechanics.forward_kinematics(robot, lam)
    phi32 = [leg_geometry(robot, leg, centre).sin32 for leg in LEGS]
    distance, angle = cut_errors(model, state.names, state.position, centre,
                                 np.arcsin(phi32))
    assert distance <= TOLERANCE and angle <= TOLERANCE, (lam, distance,
                                                          angle)
    return state, centre


@pytest.mark.parametrize('which', ['paper', 'other', *AS_BUILT])
def test_cuts_close_on_random_configurations(which, models):
    robot, model, names = ROBOTS[which], models(which), names_of(which)
    for position in reachable_positions(robot, 60, 12):
        lam = mechanics.solve(robot, position).lambda_
        _, centre = check_state(model, robot, names, lam)
        assert np.abs(centre - position).max() <= 1e-12


@pytest.mark.parametrize('which', ['paper', *AS_BUILT])
def test_cuts_close_on_the_paper_trajectory(which, models):
    robot, model = ROBOTS[which], models(which)
    times = trajectory.paper_times(41)
    for p, v, a in zip(*trajectory.paper_batch(times)):
        s = mechanics.solve(robot, p, v, a)
        check_state(model, robot, JOINT_NAMES, s.lambda_, s.lambdadot)


# Each body's origin joint (doc/model.md#bodies).
ORIGINS = {1: 'A1', 2: 'A2', 3: 'A3', 4: 'A4', 5: 'A5', 6: 'A6'}


@pytest.mark.parametrize('which', ['paper', *AS_BUILT])
def test_every_body_is_where_the_model_puts_it(which, models):
    """Where ``bodies.elements`` and the reference model put it, to 1e-10."""
    robot, model = ROBOTS[which], models(which)
    for position in reachable_positions(robot, 10, 5):
        lam = mechanics.solve(robot, position).lambda_
        state = joint_state(robot, JOINT_NAMES, lam)
        model.update_cfg(dict(zip(state.names, state.position)))
        legs = elements(robot, position)
        for leg in LEGS:
            bodies = legs[leg]['bodies']
            reference = leg_geometry(robot, leg, position)
            for body in (1, 2, 3, 4, 5, 6):
                frame = model.get_transform(link_name(leg, body))
                for origin, rotation in (
                        (bodies[body]['origin'], bodies[body]['rotation']),
                        (reference.joints[ORIGINS[body]],
                         reference.rotation[body])):
                    assert np.allclose(frame[:3, 3], origin, rtol=0,
                                       atol=1e-10)
                    assert np.allclose(frame[:3, :3], rotation.T, rtol=0,
                                       atol=1e-10)


# Joint limits ------------------------------------------------------------
@pytest.mark.parametrize('which', ['paper', *AS_BUILT])
def test_limits_hold_the_workspace_and_are_near_its_extremes(which, models):
    """
    Each leg's limits hold its variables over the workspace, near its edge.

    The drawing's three legs are one leg turned about the diagonal: the
    same limits.
    """
    robot, model = ROBOTS[which], models(which)
    limits = joint_limits(robot)
    joints = {j.name: j for j in model.robot.joints}
    for name, leg, variable in moving_joints():
        limit = joints[name].limit
        assert (limit.lower, limit.upper) == pytest.approx(
            limits[leg][variable], abs=1e-12)
    if which == 'paper':
        assert limits['A'] == limits['B'] == limits['C']
    legs = leg_joints(robot, workspace_samples(robot, 8), None, 0.0)
    cube = leg_joints(robot, np.array(
        [[x, y, z] for x in (-CUBE, CUBE) for y in (-CUBE, CUBE)
         for z in (-CUBE, CUBE)]))
    for leg in LEGS:
        for variable, (low, high) in limits[leg].items():
            values = getattr(legs[leg], variable)
            assert low <= values.min() and values.max() <= high, (
                leg, variable)
            # The edge's points come near the extremes, not beyond.
            assert values.min() - low < 0.05 and high - values.max() < 0.05, (
                leg, variable, values.min(), values.max(), low, high)
            # The paper's tested cube lies well inside.
            values = getattr(cube[leg], variable)
            assert low < values.min() and values.max() < high


# rpy ---------------------------------------------------------------------
def matrix_of_rpy(roll, pitch, yaw):
    """Return URDF's R = Rz(yaw) Ry(pitch) Rx(roll), written out."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def test_rpy_round_trip_including_gimbal_lock():
    rng = np.random.default_rng(2)
    rotations = [matrix_of_rpy(*rng.uniform(-3, 3, 3)) for _ in range(200)]
    rotations += [matrix_of_rpy(r, s * math.pi / 2, y)
                  for r in (0.0, 0.7, -2.0) for y in (0.0, 1.1)
                  for s in (1, -1)]
    # Every signed permutation matrix of determinant 1 (the model's a_k).
    for perm in ((0, 1, 2), (1, 2, 0), (2, 0, 1), (0, 2, 1), (2, 1, 0),
                 (1, 0, 2)):
        for signs in np.ndindex(2, 2, 2):
            m = np.zeros((3, 3))
            for row, col in enumerate(perm):
                m[row, col] = 1.0 - 2.0 * signs[row]
            if np.linalg.det(m) > 0:
                rotations.append(m)
    for r in rotations:
        assert np.allclose(matrix_of_rpy(*rpy(r)), r, rtol=0, atol=1e-12)


# RViz --------------------------------------------------------------------
def test_rviz_config_shows_the_model_and_existing_frames(paper_model):
    """config/orthoglide.rviz: RobotModel on /robot_description, TF."""
    import yaml
    path = COMMITTED_URDF.parents[1] / 'config' / 'orthoglide.rviz'
    config = yaml.safe_load(path.read_text())['Visualization Manager']
    assert config['Global Options']['Fixed Frame'] == 'base_link'
    displays = {d['Class']: d for d in config['Displays']}
    model = displays['rviz_default_plugins/RobotModel']
    assert model['Description Source'] == 'Topic'
    assert model['Description Topic']['Value'] == '/robot_description'
    assert model['Description Topic']['Durability Policy'] == 'Transient Local'
    frames = displays['rviz_default_plugins/TF']['Frames']
    links = {link.name for link in paper_model.robot.links}
    shown = {name for name in frames if name != 'All Enabled'}
    assert {'base_link', 'platform', 'a_leg_end', 'b_platform_mount'} <= shown
    assert shown <= links
