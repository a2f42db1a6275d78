"""
Invariant 5 (cyclic symmetry): the legs are one design turned about x=y=z.

Turning the whole problem by the cyclic permutation ``S (x, y, z) =
(z, x, y)`` (position, velocity, acceleration and gravity alike) turns leg
C onto leg A, A onto B and B onto C. So the outputs ``(A, B, C)`` at the
turned input equal the outputs ``(C, A, B)`` at the original one, every
joint centre of leg A at the turned input is ``S`` times leg C's, and
every body orientation ``a_k0`` becomes ``a_k0 S^T``.

The package evaluates one leg function three times but puts the platform
in leg A's tree only and mixes the legs through ``J_lambda^-T``, so the
forces are a real test. Tolerance: rounding, 1e-12 of each output's
natural size (metres for lambda; the commanded speed, acceleration and
the weight of the whole robot for the rates and forces).
"""

from hypothesis import given, settings, strategies as st
from hypothesis_profiles import examples
from mechanics_reference import cube_points, OTHER_ROBOT_VALUES, vectors
import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.mechanics import solve
from orthoglide_ros.model.robot import Robot

TURN = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], dtype=float)
# (A, B, C) at the turned input come from (C, A, B) at the original.
FROM = {'A': 'C', 'B': 'A', 'C': 'B'}
ROUNDING = 1e-12
PER_ACTUATOR = ('lambda_', 'lambdadot', 'lambdaddot', 'force', 'power',
                'alpha_ratio')


def close(a, b, scale):
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= ROUNDING * scale


@settings(deadline=None, max_examples=examples(60))
@given(position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0), gravity=vectors(10.0),
       other=st.booleans())
def test_turned_input_gives_turned_outputs(position, velocity, acceleration,
                                           gravity, other):
    values = OTHER_ROBOT_VALUES if other else {}
    robot = Robot(**values, gravity=tuple(gravity))
    turned = robot.replace(gravity=list(TURN @ gravity))
    s = solve(robot, position, velocity, acceleration)
    t = solve(turned, TURN @ position, TURN @ velocity, TURN @ acceleration)
    speed = np.abs(velocity).max()
    mass = sum(robot.as_parameters()[m] for m in
               ('m1', 'm2', 'm3', 'm4', 'm5', 'm6'))
    force = mass * (np.abs(acceleration).max() + speed ** 2
                    + np.abs(gravity).max())
    scales = {'lambda_': 1.0, 'alpha_ratio': 1.0, 'lambdadot': speed,
              'lambdaddot': np.abs(acceleration).max() + speed ** 2,
              'force': force, 'power': force * np.abs(s.lambdadot).max()}
    for field in PER_ACTUATOR:
        expected = np.asarray(getattr(s, field))[[2, 0, 1]]   # (C, A, B)
        assert close(getattr(t, field), expected, scales[field]), field
    for field in ('conditioning', 'singularity_distance'):
        assert close(getattr(t, field), getattr(s, field), 1.0), field


@settings(deadline=None, max_examples=examples(30))
@given(position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0))
def test_turned_input_turns_every_element(position, velocity, acceleration):
    robot = Robot()
    e = elements(robot, position, velocity, acceleration)
    t = elements(robot, TURN @ position, TURN @ velocity,
                 TURN @ acceleration)
    for leg, source in FROM.items():
        for joint, value in e[source]['joints'].items():
            assert close(t[leg]['joints'][joint], TURN @ value, 1.0), joint
        for k in range(1, 7):
            body, body0 = t[leg]['bodies'][k], e[source]['bodies'][k]
            assert close(body['rotation'], body0['rotation'] @ TURN.T, 1.0)
            for key in ('origin', 'omega', 'epsilon', 'velocity',
                        'acceleration'):
                scale = np.abs(body0[key]).max() + 1.0
                assert close(body[key], TURN @ body0[key], scale), (k, key)
        for key in ('omega21', 'omega32', 'epsilon21', 'epsilon32',
                    'lambdaddot'):
            scale = abs(e[source][key]) + 1.0
            assert close(t[leg][key], e[source][key], scale), key
