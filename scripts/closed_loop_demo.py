"""
Closed-loop demo: PD alone against PD + feedforward, over DDS, no hardware.

Starts the ``simulator``, ``feedforward`` and ``tracking_controller`` nodes
as processes, then for the paper's trajectory (eq. 6) and a faster one
streams one pass per case from a ``setpoint_publisher`` process: PD alone
and PD + feedforward, on the exact plant and on a plant whose platform is
20 % heavier than the model; ``--engine mujoco`` runs the plant in
MuJoCo (the simulator's second engine). Then, on the exact plant, a
``--payload`` (5 kg) picked up halfway through each pass, PD + feedforward
with the feedforward told (its ``robot.payload`` set at that instant) and
not told. With ``--mode trajectory`` each pass is sent
once, whole, as a Cartesian trajectory that the feedforward converts into a
JointTrajectory and the tracking controller follows as
joint_trajectory_controller would. Prints the tracking error of every case
and writes a PNG of the errors over time. The loop and its error measure are
in ``testing/orthoglide_testing/closed_loop.py`` (shared with
``test_closed_loop.py``).

Run it through ``bash scripts/closed_loop_demo.sh`` (sets up .venv, keeps
DDS on this host, picks a ROS_DOMAIN_ID); ``--help`` for the options. Exit
code 0 on success, 1 if a node failed or a pass did not complete, 2 on a
usage error.
"""

import argparse
import os
from pathlib import Path
import sys

# DDS stays on this host whoever starts the demo; a domain of its own.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))

ROOT = Path(__file__).resolve().parents[1]

from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing import closed_loop as harness  # noqa: E402
from orthoglide_testing import verdicts  # noqa: E402
from orthoglide_testing.load import (add_load_options, REALTIME,  # noqa: E402
                                     check_load_options)

use_checkout(ROOT)

CASES = ((False, 1.0), (True, 1.0), (False, harness.MISMATCH),
         (True, harness.MISMATCH))      # (feedforward, plant mass factor)


def main(argv=None):
    """Run every case, print the table, write the PNG; return the code."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--loop-rate', type=float, default=harness.LOOP_RATE,
                        metavar='HZ', help='setpoints, feedforward and '
                        f'commands per second (default {harness.LOOP_RATE:g})')
    parser.add_argument('--plant-rate', type=float,
                        default=harness.PLANT_RATE, metavar='HZ',
                        help='simulator steps per second (default '
                        f'{harness.PLANT_RATE:g})')
    parser.add_argument('--trajectories', default='paper,fast',
                        help='comma-separated, of: '
                        + ', '.join(harness.TRAJECTORIES))
    parser.add_argument('--engine', choices=('builtin', 'mujoco'),
                        default='builtin', help='the simulator\'s engine: '
                        'builtin (the package\'s forward dynamics, default) '
                        'or mujoco (the robot\'s MJCF in MuJoCo)')
    parser.add_argument('--mode', choices=('stream', 'trajectory'),
                        default='stream', help='stream: setpoints from a '
                        'setpoint_publisher (default); trajectory: each '
                        'pass as one Cartesian trajectory, converted by the '
                        'feedforward, followed as a JointTrajectory')
    parser.add_argument('--payload', type=float, default=5.0, metavar='KG',
                        help='payload picked up halfway through a pass, the '
                        'feedforward told and not told (default 5; 0: no '
                        'pick-up cases)')
    add_load_options(parser, realtime_default=REALTIME)
    parser.add_argument('--plot', default=str(ROOT / 'out' /
                                              'closed_loop.png'),
                        metavar='FILE', help='PNG of the tracking errors '
                        '(default out/closed_loop.png in the repository)')
    args = parser.parse_args(argv)
    names = args.trajectories.split(',')
    unknown = [n for n in names if n not in harness.TRAJECTORIES]
    if unknown or not (1.0 <= args.loop_rate <= args.plant_rate <= 10000.0):
        parser.error(f'unknown trajectories {unknown}' if unknown else
                     'rates: need 1 <= loop rate <= plant rate <= 10000 Hz')
    check_load_options(parser, args)
    if not 0.0 <= args.payload <= 1000.0:
        parser.error('--payload must lie in [0, 1000] kg')

    runs, pickups = {}, {}
    try:
        with harness.demo_loop(
                args.load, loop_rate=args.loop_rate,
                plant_rate=args.plant_rate, engine=args.engine,
                realtime=args.realtime) as loop:
            for name in names:
                for feedforward, mass in CASES:
                    run = loop.run_unspoiled(
                        name, feedforward, mass_factor=mass, mode=args.mode,
                        report=lambda text: print('  ' + text, flush=True))
                    print(f'  {run.label}: {run.samples} samples, position '
                          f'error RMS {run.rms_mm:.3f} mm, max '
                          f'{run.max_mm:.3f} mm', flush=True)
                    runs[name, feedforward, mass] = run
                for told in (False, True) if args.payload else ():
                    at = 0.5 * harness.TRAJECTORIES[name].duration
                    run = loop.run_unspoiled(
                        name, True, mode=args.mode,
                        pickup=(at, args.payload, told),
                        report=lambda text: print('  ' + text, flush=True))
                    print(f'  {run.label}: position error RMS '
                          f'{run.rms_mm:.3f} mm', flush=True)
                    pickups[name, told] = (run, at)
    except harness.LoopError as error:
        print(f'closed_loop_demo: error: {error}', file=sys.stderr)
        return 1
    print_table(runs, names, args)
    if pickups:
        print_pickups(pickups, names, args)
    plot(runs, names, args.plot)
    print(f'plot: {args.plot}')
    spoiled = [f'{run.label}: {verdicts.pass_spoiled_by(run)}' for run in (
        *runs.values(), *(run for run, _ in pickups.values()))
        if verdicts.pass_spoiled_by(run)]
    if spoiled:
        print('verdict: FAILED, every pass of these rows was spoiled by a '
              'stall (their figures measure the stall, not the loop; try '
              '--realtime): ' + '; '.join(spoiled), file=sys.stderr)
        return 1
    print('verdict: OK, no pass spoiled')
    return 0


def print_table(runs, names, args):
    """Print the RMS and max errors and the PD / PD + FF ratios."""
    print(f'\nTracking error of the platform centre (mm), loop '
          f'{args.loop_rate:g} Hz, plant {args.plant_rate:g} Hz '
          f'({args.engine}), '
          + ('streamed setpoints' if args.mode == 'stream' else
             'one joint trajectory per pass')
          + f', {args.load} busy loop(s), '
          + ('real-time nodes:' if args.realtime else 'normal scheduling:'))
    print(f'{"trajectory":<10} {"plant":<16} {"PD rms":>8} {"PD max":>8} '
          f'{"PD+FF rms":>10} {"PD+FF max":>10} {"ratio rms":>10}')
    for name in names:
        for mass in (1.0, harness.MISMATCH):
            pd, ff = runs[name, False, mass], runs[name, True, mass]
            plant = 'exact' if mass == 1.0 else f'm5 x{mass:g}'
            mark = ' spoiled' if (verdicts.pass_spoiled_by(pd)
                                  or verdicts.pass_spoiled_by(ff)) else ''
            print(f'{name:<10} {plant:<16} {pd.rms_mm:8.3f} {pd.max_mm:8.3f} '
                  f'{ff.rms_mm:10.3f} {ff.max_mm:10.3f} '
                  f'{pd.rms_mm / ff.rms_mm:9.1f}x{mark}')


def print_pickups(pickups, names, args):
    """Print PD + FF's error before and after the payload came."""
    print(f'\n{args.payload:g} kg picked up halfway through the pass, exact '
          'plant, PD + feedforward: RMS position error (mm)')
    print(f'{"trajectory":<10} {"feedforward":<12} {"before":>8} '
          f'{"after":>8}')
    for name in names:
        for told in (False, True):
            run, at = pickups[name, told]
            print(f'{name:<10} {"told" if told else "not told":<12} '
                  f'{harness.rms_mm(run, end=at):8.3f} '
                  f'{harness.rms_mm(run, at):8.3f}')


def plot(runs, names, path):
    """Write the error norms over time, one panel per trajectory."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import numpy as np
    figure, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4.5),
                                squeeze=False)
    styles = {(False, 1.0): ('tab:red', '-'), (True, 1.0): ('tab:blue', '-'),
              (False, harness.MISMATCH): ('tab:red', '--'),
              (True, harness.MISMATCH): ('tab:blue', '--')}
    for axis, name in zip(axes[0], names):
        for (feedforward, mass), (color, line) in styles.items():
            run = runs[name, feedforward, mass]
            norm = np.linalg.norm(run.position_error, axis=1) * 1e3
            axis.semilogy(run.times, np.maximum(norm, 1e-4), color=color,
                          linestyle=line, label=(
                              f'{"PD + FF" if feedforward else "PD"}, '
                              f'{"exact plant" if mass == 1.0 else "m5 x%g" % mass}'
                              f' (rms {run.rms_mm:.3g} mm)'))
        axis.set_title(f'{name} trajectory')
        axis.set_xlabel('t (s)')
        axis.set_ylabel('|r_G - r*| (mm)')
        axis.grid(True, which='both', alpha=0.3)
        axis.legend(fontsize=8)
    figure.suptitle('Orthoglide closed loop over DDS: tracking error')
    figure.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)


if __name__ == '__main__':
    raise SystemExit(main())
