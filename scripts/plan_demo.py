"""
Planning demo: the fastest motion within the drives' limits, tracked.

Plans the contour of doc/programs/contour.nc (lines, tangent arcs, a
helical turn) on the robot of doc/programs/drives.yaml (drives, friction,
a 5 kg payload) within 90 % of the 400 N each drive gives (the rest for
the feedback; :func:`orthoglide_ros.planning.parametrization.plan`, the
core of
``orthoglide plan``), and times the same path kinematically for the same
duration (one Cartesian acceleration limit per axis, chosen so that the
motion lasts as long). Both are sent as one Cartesian trajectory through
the feedforward to the tracking controller, on the simulated robot in
MuJoCo whose drives clip at 400 N (the simulator's
``joint_limits.<joint>.max_effort``).
Prints, for each, the peak force the model asks of each drive against its
limit, the share of the pass the drives clipped, and the contour error
measured; writes a PNG: the path coloured by speed, and the forces against
the limits over time.

Run it through ``bash scripts/plan_demo.sh`` (sets up .venv, keeps DDS on
this host, picks a ROS_DOMAIN_ID). Exit code 0 on success, 1 if a node
failed or a pass did not complete, 2 on a usage error; the last line is
the verdict.
"""

import argparse
import math
import os
from pathlib import Path
import sys

# DDS stays on this host whoever starts the demo; a domain of its own.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))

ROOT = Path(__file__).resolve().parents[1]

import numpy as np  # noqa: E402

from orthoglide_ros.formats.params_file import load_robot  # noqa: E402
from orthoglide_testing import closed_loop as harness  # noqa: E402
from orthoglide_testing import phase_plane, use_checkout, verdicts  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.planning import parametrization  # noqa: E402
from orthoglide_ros.planning.limits import limits_from_mapping  # noqa: E402
from orthoglide_ros.planning.programs import read_program  # noqa: E402

use_checkout(ROOT)

LIMIT = 400.0       # N, each drive
PLANNED = 0.9       # the share of it the plan may use: the rest is feedback's
RATE = 1000.0       # Hz, the planned samples


def kinematic(path, duration):
    """Return ``(acceleration, t, p, v, a)``: the same path, same duration."""
    motion = phase_plane.kinematic_planner(path, RATE)
    low, high = 0.05, 500.0
    for _ in range(40):     # the acceleration that takes ``duration``
        middle = math.sqrt(low * high)
        if motion(middle)[0][-1] > duration:
            low = middle
        else:
            high = middle
    return (high, *motion(high))


def as_motion(t, p, v, a):
    """Return the samples as the harness's Motion (the nearest at t)."""
    def sample(time):
        k = min(max(int(round(time * RATE)), 0), len(t) - 1)
        return tuple(p[k]), tuple(v[k]), tuple(a[k])
    return harness.Motion([], float(t[-1]), sample)


def picture(path_file, cases):
    """Draw the path coloured by speed and the forces against the limits."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    figure = Figure(figsize=(13, 8), layout='constrained')
    FigureCanvasAgg(figure)
    axes = figure.subplots(2, 2)
    for column, (name, (t, p, v, force, run)) in enumerate(cases.items()):
        top = axes[0, column]
        speed = np.linalg.norm(v, axis=1)
        shown = top.scatter(p[:, 0] * 1e3, p[:, 1] * 1e3, c=speed, s=2,
                            cmap='viridis')
        figure.colorbar(shown, ax=top, label='speed of G (m/s)')
        top.set_title(f'{name}: the path coloured by speed')
        top.set_xlabel('x (mm)')
        top.set_ylabel('y (mm)')
        top.set_aspect('equal')
        bottom = axes[1, column]
        for j, leg in enumerate('ABC'):
            bottom.plot(t, force[:, j], label=f'model, drive {leg}')
        if run is not None:
            bottom.plot(run.times, run.efforts, color='grey', lw=0.6,
                        alpha=0.6)
        for sign in (1, -1):
            bottom.axhline(sign * LIMIT, color='red', ls='--')
        bottom.set_title(f'{name}: forces (N) against the limit, grey: '
                         'applied')
        bottom.set_xlabel('t (s)')
        bottom.legend(loc='lower right', fontsize=8)
    path_file.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path_file, dpi=90)


def main(argv=None):
    """Plan, time, track both; print, draw; return the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--engine', choices=('mujoco', 'builtin'),
                        default='mujoco', help='the simulator\'s engine '
                        '(default mujoco)')
    parser.add_argument('--plot', default=str(ROOT / 'out' / 'plan_demo.png'),
                        metavar='FILE', help='the PNG (default '
                        'out/plan_demo.png)')
    args = parser.parse_args(argv)
    robot = load_robot(ROOT / 'doc' / 'programs' / 'drives.yaml')
    limits = limits_from_mapping({j: {'max_effort': PLANNED * LIMIT}
                                  for j in (
        'slider_a', 'slider_b', 'slider_c')})
    path = read_program(ROOT / 'doc' / 'programs' / 'contour.nc',
                        (0.0, 0.0, 0.0), 1e-5)
    motion = parametrization.plan(robot, path, limits, RATE)
    acceleration, *timed = kinematic(path, motion.duration)
    planned = (motion.t, motion.position, motion.velocity,
               motion.acceleration)
    cases = {'planned': planned, f'kinematic, {acceleration:.3g} m/s^2':
             tuple(timed)}
    results = {}
    try:
        with harness.demo_loop(engine=args.engine, max_effort=LIMIT) as loop:
            for name, (t, p, v, a) in cases.items():
                run = loop.run(as_motion(t, p, v, a), model=robot,
                               plant=robot, mode='trajectory')
                force = mechanics.solve_batch(robot, p, v, a).force
                results[name] = (t, p, v, force, run)
    except harness.LoopError as error:
        print(f'verdict: FAILED, {error}')
        return 1
    print(f'contour {path.length:.3f} m in {motion.duration:.3f} s, planned '
          f'within {PLANNED * LIMIT:g} N; drives clip at {LIMIT:g} N; '
          f'{args.engine} plant')
    print(f'{"case":<28}{"peak |f| A, B, C (N)":>26}{"clipped":>9}'
          f'{"contour rms":>13}{"max":>8}')
    verdict = []
    for name, (t, p, v, force, run) in results.items():
        peak = np.abs(force).max(0)
        clipped = float((np.abs(run.efforts) >= LIMIT * 0.999).any(1).mean())
        print(f'{name:<28}{" ".join(f"{f:7.1f}" for f in peak):>26}'
              f'{clipped:>8.1%}{run.rms_mm:>10.3f} mm{run.max_mm:>6.2f} mm')
        if run.braked or run.skipped_s > verdicts.SKIP_LIMIT:
            verdict.append(f'{name}: the pass was spoiled (the plant braked '
                           'or skipped)')
    planned_peak = np.abs(results['planned'][3]).max()
    if planned_peak > PLANNED * LIMIT * 1.001:
        verdict.append(f'the plan asks {planned_peak:.1f} N, beyond '
                       f'{PLANNED * LIMIT:g} N')
    picture(Path(args.plot), results)
    print(f'picture: {args.plot}')
    print('verdict: ' + ('OK' if not verdict else 'FAILED, '
                         + '; '.join(verdict)))
    return 0 if not verdict else 1


if __name__ == '__main__':
    sys.exit(main())
