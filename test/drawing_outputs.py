"""
The drawing's robot's outputs as the code gave them before per-leg geometry.

:func:`outputs` evaluates every function of the math library whose
result the per-leg geometry could change (``solve``, ``solve_batch``,
the forward dynamics, ``forward_kinematics_rows``, ``workspace_status``,
``jacobians``, ``platform_velocity``, ``payload_force``, ``leg_joints``,
``elements``, ``rk4_step`` and the refusals' messages) at fixed states
of three robots, through the API that existed before the per-leg rows
(no new name), so that the code of that time can run it.
``drawing_outputs.json`` holds what that code gave, every float as
``float.hex``; ``test_drawing_unchanged.py`` checks that today's
code gives the same to the last bit, with the rows absent and given at
the drawing's values.

Written by the code before per-leg geometry (commit 7e432b9), from a
checkout of it with its own venv::

    git worktree add /tmp/before 7e432b9 && bash /tmp/before/scripts/setup_venv.sh
    /tmp/before/.venv/bin/python test/drawing_outputs.py --write

(never by the code under test: the file would then check nothing).
"""

import json
import math
from pathlib import Path
import subprocess
import sys

import numpy as np
from orthoglide_ros.model import bodies, mechanics, plant
from orthoglide_ros.model.robot import Robot

FILE = Path(__file__).with_name('drawing_outputs.json')

# The paper's robot, another in every length and mass, and one with every
# term (friction both ways, Stribeck, drives, a payload) and oblique gravity.
ROBOTS = {
    'paper': {},
    'other': {'l': 0.13, 'l1': 0.21, 'l2': 0.11, 'l3': 0.93, 'alpha': 0.61,
              'm1': 0.47, 'm2': 0.31, 'm3': 1.9, 'm4': 0.53, 'm5': 11.0,
              'm6': 3.1},
    'terms': {'friction_viscous': (30.0, 40.0, 50.0),
              'friction_coulomb': (5.0, 3.0, 4.0),
              'friction_coulomb_negative': (6.0, 2.0, 4.5),
              'friction_stribeck': (1.0, 2.0, 0.5),
              'armature': (3.2, 1.1, 0.45), 'payload': 5.0,
              'gravity': (2.0, -5.0, -7.5)},
}

# Platform states (m, m/s, m/s^2): home, the paper's target, two corners
# of the tested cube, and points written out from a seeded draw.
STATES = (
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
    ((0.05, 0.1, -0.2), (0.1, -0.2, 0.3), (1.0, -2.0, 0.5)),
    ((-0.3, -0.3, -0.3), (0.5, 0.5, -0.5), (-4.0, 3.0, 9.0)),
    ((0.3, 0.3, 0.3), (-1.5, 2.0, 0.7), (20.0, -15.0, 12.0)),
    ((0.21370, -0.05518, 0.12936), (2.3119, -0.7441, 1.0913),
     (-17.2288, 25.0174, -3.3902)),
    ((-0.11483, 0.27619, -0.24437), (-0.2246, -2.7706, 1.8851),
     (8.8172, -29.3338, 14.1197)),
    ((0.02851, -0.18770, 0.29416), (1.0001, 0.0003, -2.9997),
     (0.0, 12.5, -6.25)),
)

# Inputs refused, with the message each gives (m): out of reach of each
# leg, too near a singularity of J1, of J2, on one.
REFUSED = ((0.0, 0.9, 0.0), (0.0, 0.0, 0.9), (0.9, 0.0, 0.0),
           (0.0, 0.0, 0.82), (0.84, 0.0, 0.0), (0.45, 0.45, 0.45),
           (0.85 / math.sqrt(3.0),) * 3)

# Actuator displacements (m) for forward_kinematics_rows, found or not.
LAMBDAS = ((0.0, 0.0, 0.0), (0.02, -0.01, 0.03), (-0.2, 0.1, 0.05),
           (2.0, 0.0, 0.0), (0.85, 0.85, 0.85), (0.3, 0.3, -0.4))


def flat(value):
    """Return ``value`` (floats, bools, arrays, nests of them) as hex lists."""
    if isinstance(value, dict):
        return {str(key): flat(item) for key, item in sorted(value.items())}
    if isinstance(value, (tuple, list)) or (
            isinstance(value, np.ndarray) and value.ndim > 0):
        return [flat(item) for item in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if value is None or isinstance(value, str):
        return value
    return float(value).hex()


def refusal(call):
    """Return ``[reason, message]`` of the WorkspaceError ``call`` raises."""
    try:
        call()
    except mechanics.WorkspaceError as error:
        return [error.reason, str(error)]
    return None


def robot_outputs(robot):
    """Every output of one robot (see the module docstring)."""
    out = {}
    positions = np.array([s[0] for s in STATES])
    velocities = np.array([s[1] for s in STATES])
    accelerations = np.array([s[2] for s in STATES])
    solutions = [mechanics.solve(robot, *state) for state in STATES]
    out['solve'] = [tuple(s) for s in solutions]
    out['solve_batch'] = tuple(mechanics.solve_batch(
        robot, positions, velocities, accelerations))
    forces = np.array([s.force for s in solutions]) + 10.0
    out['forward_dynamics'] = [
        mechanics.forward_dynamics(robot, p, v, f)
        for p, v, f in zip(positions, velocities, forces)]
    out['forward_dynamics_batch'] = mechanics.forward_dynamics_batch(
        robot, positions, velocities, forces)
    lambdas = np.array([s.lambda_ for s in solutions] + list(LAMBDAS))
    out['forward_kinematics_rows'] = mechanics.forward_kinematics_rows(
        robot, lambdas)
    out['forward_kinematics'] = [
        mechanics.forward_kinematics(robot, s.lambda_) for s in solutions]
    points = np.vstack([positions, REFUSED])
    out['workspace_status'] = tuple(mechanics.workspace_status(robot, points))
    out['jacobians'] = mechanics.jacobians(robot, positions)
    out['platform_velocity'] = [
        mechanics.platform_velocity(robot, s[0], sol.lambdadot)
        for s, sol in zip(STATES, solutions)]
    out['payload_force'] = [
        mechanics.payload_force(robot, 4.0, sol.lambda_, sol.lambdadot,
                                sol.lambdaddot) for sol in solutions]
    out['leg_joints'] = [
        {leg: tuple(j) for leg, j in bodies.leg_joints(
            robot, s[0], s[1]).items()} for s in STATES]
    out['leg_joints_batch'] = {
        leg: tuple(j) for leg, j in bodies.leg_joints(
            robot, positions, velocities).items()}
    out['elements'] = [bodies.elements(robot, *STATES[i]) for i in (1, 4)]
    out['rk4_step'] = [
        plant.rk4_step(robot, p, v, f, 1e-3)
        for p, v, f in zip(positions, velocities, forces)]
    out['refused'] = [refusal(lambda p=p: mechanics.solve(robot, p))
                      for p in REFUSED]
    out['refused_batch'] = refusal(lambda: mechanics.solve_batch(
        robot, np.vstack([positions, REFUSED[:1]])))
    return out


def outputs(rows=None):
    """
    Every robot's outputs, as JSON-ready nests of hex strings.

    ``rows``: a function of a robot's values returning more ``Robot``
    keyword arguments (none by default).
    """
    return {name: flat(robot_outputs(Robot(**values, **(
        rows(values) if rows else {})))) for name, values in ROBOTS.items()}


def main(argv):
    """Write FILE (``--write``) from the code that runs this script."""
    if argv != ['--write']:
        print(__doc__)
        return 2
    import orthoglide_ros
    root = Path(orthoglide_ros.__file__).resolve().parents[1]
    commit = subprocess.run(['git', '-C', str(root), 'rev-parse', 'HEAD'],
                            capture_output=True, text=True,
                            check=True).stdout.strip()
    FILE.write_text(json.dumps({'commit': commit, 'robots': outputs()},
                               separators=(',', ':'), sort_keys=True) + '\n')
    print(f'{FILE}: the outputs of {root} at {commit}')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
