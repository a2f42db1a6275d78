"""
Invariant 2 (constraints): eqs. (14), (15)-(16), (13) and (18) hold.

The package's lambda must satisfy the three sphere constraints (14); its
lambdadot must satisfy ``J1 lambdadot = J2 rdot_G`` with J1, J2 of eq. (16)
written here; and the relative rates of every leg (lambdadot, omega21,
omega32 and their derivatives) must satisfy the connectivity conditions
(13) and (18) as doc/model.md corrects them, written here with numpy matrices
from the rotations ``a_k0`` that ``elements`` returns:

(13) ``v10 a10^T u3 - l3 w21 a20^T u3~ a32^T u2 - l3 w32 a30^T u3~ u2
= rdot_G`` and ``w21 a20^T u3 + w54 a50^T u3 = 0`` with ``w54 = w21``;

(18) its time derivative,
``g10 a10^T u3 - l3 [e21 a20^T u3~ a32^T u2 + e32 a30^T u3~ u2
+ w21^2 a20^T u3~ u3~ a32^T u2 + w32^2 a30^T u3~ u3~ u2
+ 2 w21 w32 a20^T u3~ a32^T u3~ u2] = rddot_G``.
"""

from hypothesis import given, settings
from hypothesis_profiles import examples
from mechanics_reference import (
    cube_points, LEGS, skew, U2, U3, vectors)
import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.mechanics import solve
from orthoglide_ros.model.robot import Robot

U3_SKEW = skew(U3)
# Rounding of sums of a few terms of order 1 (relative).
ROUNDING = 1e-12


def jacobians_eq16(robot, position, lam):
    """J1 and J2 of eq. (16) with the alpha_i of eq. (17)."""
    x, y, z = position
    alpha = (x + robot.l3 - lam[0], y + robot.l3 - lam[1],
             z + robot.l3 - lam[2])
    j1 = np.diag(alpha)
    j2 = np.array([[alpha[0], y, z], [x, alpha[1], z], [x, y, alpha[2]]])
    return j1, j2


def connectivity_terms(robot, leg):
    """Return the vectors of eqs. (13) and (18) for one leg's elements."""
    bodies = leg['bodies']
    a10, a20, a30 = (bodies[k]['rotation'] for k in (1, 2, 3))
    a32 = a30 @ a20.T
    l3 = robot.l3
    slider = a10.T @ U3
    turn21 = -l3 * a20.T @ U3_SKEW @ a32.T @ U2
    turn32 = -l3 * a30.T @ U3_SKEW @ U2
    quad21 = -l3 * a20.T @ U3_SKEW @ U3_SKEW @ a32.T @ U2
    quad32 = -l3 * a30.T @ U3_SKEW @ U3_SKEW @ U2
    cross = -2.0 * l3 * a20.T @ U3_SKEW @ a32.T @ U3_SKEW @ U2
    return slider, turn21, turn32, quad21, quad32, cross


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points())
def test_spheres_eq14_hold(robot, position):
    lam = solve(robot, position).lambda_
    x, y, z = position
    l3 = robot.l3
    residuals = (z * z + y * y + (x + l3 - lam[0]) ** 2 - l3 * l3,
                 x * x + z * z + (y + l3 - lam[1]) ** 2 - l3 * l3,
                 y * y + x * x + (z + l3 - lam[2]) ** 2 - l3 * l3)
    assert np.abs(residuals).max() <= ROUNDING


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), velocity=vectors(3.0))
def test_j1_lambdadot_equals_j2_rdot(robot, position, velocity):
    s = solve(robot, position, velocity)
    j1, j2 = jacobians_eq16(robot, position, s.lambda_)
    lhs = j1 @ np.array(s.lambdadot)
    rhs = j2 @ velocity
    scale = np.abs(j2).max() * np.abs(velocity).sum() + 1e-300
    assert np.abs(lhs - rhs).max() <= ROUNDING * scale


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0))
def test_connectivity_eq13_and_eq18_hold_for_every_leg(
        robot, position, velocity, acceleration):
    legs = elements(robot, position, velocity, acceleration)
    for leg_name in LEGS:
        leg = legs[leg_name]
        slider, turn21, turn32, quad21, quad32, cross = \
            connectivity_terms(robot, leg)
        w21, w32 = leg['omega21'], leg['omega32']
        e21, e32 = leg['epsilon21'], leg['epsilon32']
        # Eq. (13), position part: the platform velocity.
        terms = (leg['lambdadot'] * slider, w21 * turn21, w32 * turn32)
        scale = sum(np.abs(t).max() for t in terms) + np.abs(velocity).max()
        assert np.abs(sum(terms) - velocity).max() <= ROUNDING * scale
        # Eq. (13), orientation part: the platform does not turn.
        a20, a50 = leg['bodies'][2]['rotation'], leg['bodies'][5]['rotation']
        spin = w21 * a20.T @ U3 + w21 * a50.T @ U3
        assert np.abs(spin).max() <= ROUNDING * (abs(w21) + 1e-300)
        # Eq. (18): the platform acceleration.
        terms = (leg['lambdaddot'] * slider, e21 * turn21, e32 * turn32,
                 w21 * w21 * quad21, w32 * w32 * quad32, w21 * w32 * cross)
        scale = sum(np.abs(t).max() for t in terms) \
            + np.abs(acceleration).max()
        assert np.abs(sum(terms) - acceleration).max() <= ROUNDING * scale
        spin = e21 * a20.T @ U3 + e21 * a50.T @ U3
        assert np.abs(spin).max() <= ROUNDING * (abs(e21) + 1e-300)


def test_printed_signs_of_eq18_would_be_caught():
    """The check above is sharp: the paper's printed signs violate it."""
    robot = Robot()
    position = np.array([0.1, -0.2, 0.15])
    velocity = np.array([1.0, 2.0, -1.5])
    acceleration = np.array([3.0, -4.0, 5.0])
    leg = elements(robot, position, velocity, acceleration)['A']
    slider, turn21, turn32, quad21, quad32, cross = \
        connectivity_terms(robot, leg)
    w21, w32 = leg['omega21'], leg['omega32']
    e21, e32 = leg['epsilon21'], leg['epsilon32']
    # As printed: + signs on the l3 terms of the left, and the quadratic
    # terms moved to the right with a minus sign (i.e. the same sign).
    printed = (leg['lambdaddot'] * slider - e21 * turn21 - e32 * turn32
               - w21 * w21 * quad21 - w32 * w32 * quad32
               - w21 * w32 * cross)
    assert np.abs(printed - acceleration).max() > 0.01 * np.abs(
        acceleration).max()
