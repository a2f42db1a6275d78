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

First it plans a program as CAM writes curves: the spiral of LinuxCNC's
``nc_files/spiral.ngc`` (reconstructed, :mod:`orthoglide_testing.
chord_programs`), 1000 G1 chords under plain G64, followed as the curve
they sample, against the same chords as lines blended within 10 um (G64
P); prints both durations and writes a second PNG (``--chords-plot``,
doc/planning_chords.png is one): a few chords beside the path followed,
and G's speed along the spiral both ways. ``--chords-only`` stops there
(no DDS, a few seconds).

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
from orthoglide_testing import (chord_programs, phase_plane,  # noqa: E402
                                use_checkout, verdicts)
from orthoglide_ros.planning import gcode  # noqa: E402
from orthoglide_ros.planning.path import from_moves  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.planning import parametrization  # noqa: E402
from orthoglide_ros.planning.limits import (  # noqa: E402
    limits_from_mapping, load_limits)
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


def chords(robot, limits, plot):
    """
    Plan the spiral of 1000 chords as its curve and as lines; draw both.

    Returns the two durations (s); ``plot``: the PNG.
    """
    text = chord_programs.spiral_program()
    moves = gcode.read_gcode(text)
    points = np.array([m.end for m in moves])
    fitted = from_moves(moves, 1e-5)
    lines = from_moves(gcode.read_gcode(text.replace('G64', 'G64 P0.000394')),
                       1e-5)
    motions = {name: parametrization.plan(robot, path, limits, RATE)
               for name, path in (('curve', fitted), ('lines', lines))}
    chord_picture(plot, points, {'curve': fitted, 'lines': lines}, motions)
    return motions['curve'].duration, motions['lines'].duration


def chord_picture(path_file, points, paths, motions):
    """
    Draw a few chords beside the paths, and G's speed along each.

    Left: six chords of the spiral's outer turn unrolled (along each chord,
    and the offset across it in um): the programmed points, the chords,
    the curve followed (plain G64), the lines blended within 10 um (G64
    P). Right: G's speed along the spiral, both ways.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    figure = Figure(figsize=(13, 4.8), layout='constrained')
    FigureCanvasAgg(figure)
    left, right = figure.subplots(1, 2, width_ratios=(1.3, 1.0))
    first = 200       # six chords of the outer turns, after the approach
    corners = points[first:first + 7]
    start = 0.0
    for a, b in zip(corners[:-1], corners[1:]):
        along = (b - a) / np.linalg.norm(b - a)
        across = np.cross((0.0, 0.0, 1.0), along)
        length = float(np.linalg.norm(b - a))
        left.plot([start * 1e3, (start + length) * 1e3], [0.0, 0.0],
                  color='grey', lw=0.8)
        for name, colour in (('curve', 'tab:blue'), ('lines', 'tab:orange')):
            path = paths[name]
            dense = np.vstack([piece.evaluate(np.linspace(
                0.0, piece.length, max(2, int(piece.length / 2e-5))))[0]
                for piece in path.pieces])
            u = (dense - a) @ along
            inside = (u >= 0.0) & (u <= length) & (
                np.abs((dense - a) @ across) < 2e-3)
            order = np.argsort(u[inside])
            left.plot((start + u[inside][order]) * 1e3,
                      ((dense[inside] - a) @ across)[order] * 1e6,
                      color=colour, lw=1.2)
        start += length
    left.plot(np.cumsum(np.r_[0.0, np.linalg.norm(np.diff(
        corners, axis=0), axis=1)]) * 1e3, np.zeros(len(corners)), 'ko',
        ms=4)
    left.set_xlabel('along the chords (mm)')
    left.set_ylabel('across them (um)')
    left.set_title('six chords of the spiral (grey), its points (black): '
                   'followed as the curve (blue), as lines (orange)',
                   fontsize=9)
    feed = chord_programs.SPIRAL_FEED * 0.0254 / 60.0
    for name, colour, label in (
            ('curve', 'tab:blue', 'the curve (plain G64)'),
            ('lines', 'tab:orange', 'lines blended within 10 um (G64 P)')):
        motion = motions[name]
        travelled = np.concatenate(([0.0], np.cumsum(np.linalg.norm(
            np.diff(motion.position, axis=0), axis=1))))
        right.plot(travelled, np.linalg.norm(motion.velocity, axis=1)
                   / feed, color=colour, lw=0.8,
                   label=f'{label}: {motion.duration:.2f} s')
    right.set_xlabel('along the spiral (m)')
    right.set_ylabel('speed of G / the feed')
    right.set_title('1000 chords, 999 in/min, drives of 160, 250, 520 N',
                    fontsize=9)
    right.legend(loc='lower left', fontsize=8)
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
    parser.add_argument('--chords-plot', metavar='FILE',
                        default=str(ROOT / 'out' / 'plan_chords.png'),
                        help='the chords\' PNG (default out/plan_chords.png)')
    parser.add_argument('--chords-only', action='store_true',
                        help='plan and draw the chords only (no DDS)')
    args = parser.parse_args(argv)
    robot = load_robot(ROOT / 'doc' / 'programs' / 'drives.yaml')
    curve, lines = chords(robot, load_limits(
        ROOT / 'doc' / 'programs' / 'drives_limits.yaml'),
        Path(args.chords_plot))
    print(f'spiral of 1000 chords (plain G64): {curve:.3f} s along its '
          f'curve, {lines:.3f} s as lines blended within 10 um '
          f'({lines / curve - 1:+.0%}); picture: {args.chords_plot}')
    if args.chords_only:
        return 0
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
