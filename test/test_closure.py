"""
Invariant 1 (closure): every leg's chain (7) reaches the same G, a50 fixed.

``bodies.elements`` builds each leg's chain of eqs. (1)-(8) in frame 0;
its last point ``joints['G']`` must be the platform centre that was asked
for, for every leg, and the platform's orientation ``a50`` must not change
over the workspace (eq. 3), or the platform would not translate.
"""

from hypothesis import given, settings
from hypothesis_profiles import examples
from mechanics_reference import (
    CUBE, cube_points, leg_geometry, LEGS, U1)
import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.robot import Robot

# Closure tolerance (m) of doc/model.md: rounding of a chain of ~1 m vectors.
CLOSURE_TOLERANCE = 1e-12


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points())
def test_every_leg_chain_reaches_the_platform_centre(robot, position):
    legs = elements(robot, position)
    for leg in LEGS:
        reached = legs[leg]['joints']['G']
        assert np.abs(reached - position).max() <= CLOSURE_TOLERANCE, leg


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points())
def test_platform_orientation_a50_is_constant(robot, position):
    home = elements(robot, (0.0, 0.0, 0.0))
    here = elements(robot, position)
    for leg in LEGS:
        a50 = here[leg]['bodies'][5]['rotation']
        assert np.abs(a50 - home[leg]['bodies'][5]['rotation']).max() \
            <= 1e-12, leg
        assert np.abs(a50 @ a50.T - np.eye(3)).max() <= 1e-12, leg


def test_platform_orientation_of_leg_c_is_the_corrected_eq4():
    # doc/model.md (errata of eq. 4): leg C's own chain gives this c50.
    c50 = np.array([[-1, 0, 0], [0, 0, -1], [0, -1, 0]], dtype=float)
    for position in ((0.0, 0.0, 0.0), (0.2, -0.1, 0.25)):
        a50 = elements(Robot(), position)['C']['bodies'][5]['rotation']
        assert np.abs(a50 - c50).max() <= 1e-12


@settings(deadline=None, max_examples=examples(30))
@given(position=cube_points())
def test_parallelogram_and_rods_keep_their_lengths(robot, position):
    legs = elements(robot, position)
    for leg in LEGS:
        j = legs[leg]['joints']
        bodies = legs[leg]['bodies']

        def length(a, b):
            return np.linalg.norm(j[a] - j[b])
        assert abs(length('A1', 'A2') - robot.l1) <= 1e-12
        assert abs(length('A3', 'A6') - robot.l2) <= 1e-12
        assert abs(length('A3', 'A4') - robot.l3) <= 1e-12
        assert abs(length('A6', 'A7') - robot.l3) <= 1e-12
        # The parallelogram closes at A7 on body 4 (x4 axis, length l2,
        # A5 at its centre), so the cut at A7 is consistent.
        a40 = bodies[4]['rotation']
        on_body_4 = j['A4'] + robot.l2 * a40.T @ U1
        assert np.abs(on_body_4 - j['A7']).max() <= CLOSURE_TOLERANCE
        assert np.abs(j['A5'] - (j['A4'] + j['A7']) / 2).max() \
            <= CLOSURE_TOLERANCE
        # The slider A1 stays on its axis (the leg's own x0, y0 or z0).
        axis = 'ABC'.index(leg)
        off_axis = np.delete(j['A1'], axis)
        assert np.abs(off_axis).max() <= CLOSURE_TOLERANCE


@settings(deadline=None, max_examples=examples(30))
@given(position=cube_points(CUBE))
def test_joint_centres_and_rotations_match_an_independent_chain(robot,
                                                                position):
    legs = elements(robot, position)
    for leg in LEGS:
        geometry = leg_geometry(robot, leg, position)
        for joint, value in geometry.joints.items():
            assert np.abs(legs[leg]['joints'][joint] - value).max() \
                <= CLOSURE_TOLERANCE, (leg, joint)
        for k in range(1, 7):
            rotation = legs[leg]['bodies'][k]['rotation']
            assert np.abs(rotation - geometry.rotation[k]).max() <= 1e-12
            origin = legs[leg]['bodies'][k]['origin']
            assert np.abs(origin - geometry.joints[f'A{k}']).max() \
                <= CLOSURE_TOLERANCE
        assert abs(legs[leg]['lambda'] - geometry.lam) <= 1e-12
        assert abs(np.sin(legs[leg]['phi21']) - geometry.sin21) <= 1e-12
        assert abs(np.sin(legs[leg]['phi32']) - geometry.sin32) <= 1e-12
