"""
Solve the inverse mechanics: ``paper``, ``solve``, ``batch``.

Of eq. (6), of one sample, of a trajectory file; see doc/cli.md.
"""

import json
import sys

import numpy as np

from orthoglide_ros.model.robot import LEGS
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.tools.cli.common import (
    add_output, add_position, CliError, CSV_COLUMNS, csv_text,
    joint_trajectory_yaml, new_figure, params_joint_names, png_bytes, PROG,
    QUANTITIES, read_trajectory, solve_trajectory, Subcommand,
    table_row, within, write_output)

DEFAULT_SAMPLES = 201
UNITS = {'lambda': 'm', 'lambdadot': 'm/s', 'lambdaddot': 'm/s^2',
         'force': 'N', 'power': 'W'}
_samples = within(int, 2)
_COLUMNS = ', '.join(CSV_COLUMNS)


def add_paper(parser):
    """Add the options of ``paper``: the paper's figures 3-8."""
    parser.add_argument('--samples', type=_samples, default=DEFAULT_SAMPLES,
                        metavar='N', help='number of instants evenly spaced '
                        'over [0, 2] s, both ends included (default '
                        '%(default)s)')
    parser.add_argument('--csv', metavar='FILE', help='write the samples as '
                        f'CSV ({_COLUMNS}; SI units); - for standard output')
    parser.add_argument('--plot', metavar='FILE', help='write figures 3-8 as '
                        'a PNG image (needs matplotlib)')


def run_paper(robot, args):
    """Solve the trajectory of eq. (6); write the CSV, plot or summary."""
    times = trajectory.paper_times(args.samples)
    p, v, a = trajectory.paper_batch(times)
    sol = solve_trajectory(robot, 'the paper trajectory', times, None, p, v,
                           a)
    outputs = []
    if args.plot is not None:
        outputs.append((args.plot, _plot_png(times, sol)))
    if args.csv is not None:
        outputs.append((args.csv, csv_text(times, p, sol)))
    if not outputs:
        static = mechanics.solve(robot, tuple(float(c) for c in p[0]))
        print(_paper_summary(times, sol, static.force))
    for path, data in outputs:
        write_output(path, data)
    return 0


def _paper_summary(times, sol, static_force):
    lines = [f'Paper trajectory, eq. (6): {len(times)} samples over '
             f'[{times[0]:g}, {times[-1]:g}] s', table_row('', 'A', 'B', 'C')]
    for label, values in (
            ('peak |lambda| (m)', sol.lambda_),
            ('peak |force| (N)', sol.force),
            ('peak |power| (W)', sol.power)):
        lines.append(table_row(label, *np.abs(values).max(0)))
    lines.append(table_row('statics force at t=0 (N)', *static_force))
    return '\n'.join(lines)


def _plot_png(times, sol):
    """Render figures 3-8 as PNG bytes."""
    figure = new_figure((13, 7), '--plot')
    axes = figure.subplots(2, 3, sharex=True)
    for j, leg in enumerate('ABC'):
        top, bottom = axes[0, j], axes[1, j]
        top.plot(times, sol.lambda_[:, j] * 1e3)
        top.set_title(f'Fig. {3 + j}: displacement of actuator {leg}')
        top.set_ylabel(f'$\\lambda_{leg}$ (mm)')
        bottom.plot(times, sol.power[:, j], color='tab:red')
        bottom.set_title(f'Fig. {6 + j}: power of actuator {leg}')
        bottom.set_ylabel(f'$p_{leg}$ (W)')
        bottom.set_xlabel('t (s)')
        for ax in (top, bottom):
            ax.grid(True, alpha=0.4)
    figure.suptitle('Orthoglide, trajectory of eq. (6)')
    return png_bytes(figure)


def add_solve(parser):
    """Add the options of ``solve``: one sample."""
    add_position(parser)
    parser.add_argument('--velocity', type=float, nargs=3,
                        default=mechanics.ZERO, metavar=('VX', 'VY', 'VZ'),
                        help='its velocity (m/s; default 0 0 0)')
    parser.add_argument('--acceleration', type=float, nargs=3,
                        default=mechanics.ZERO, metavar=('AX', 'AY', 'AZ'),
                        help='its acceleration (m/s^2; default 0 0 0)')
    parser.add_argument('--json', action='store_true', help='print one JSON '
                        f'object with the keys {_COLUMNS[3:]} (SI units, full '
                        'double precision)')


def run_solve(robot, args):
    """Solve one sample; print a table or a JSON object."""
    try:
        sol = mechanics.solve(robot, args.position, args.velocity,
                              args.acceleration)
    except mechanics.WorkspaceError as error:
        raise CliError(str(error)) from None
    if args.json:
        record = dict(zip(('x', 'y', 'z'), args.position))
        for q, values in zip(QUANTITIES, sol):
            record.update(zip((f'{q}_{leg}' for leg in LEGS), values))
        print(json.dumps({k: float(v) for k, v in record.items()}))
        return 0
    lines = [table_row('', 'A', 'B', 'C')]
    for q, values in zip(QUANTITIES, sol):
        lines.append(table_row(f'{q} ({UNITS[q]})', *values))
    lines.append(f'singularity distance: {sol.singularity_distance:.6g} '
                 f'(1 at home, refused below '
                 f'{mechanics.DEFAULT_SINGULARITY_MARGIN:g})')
    print('\n'.join(lines))
    return 0


def add_batch(parser):
    """Add the options of ``batch``: a trajectory file."""
    parser.add_argument('--input', required=True, metavar='FILE',
                        help='trajectory CSV file; - for standard input')
    parser.add_argument('--format', choices=('csv', 'joint_trajectory'),
                        default='csv', help='csv: the columns above '
                        '(default); joint_trajectory: a trajectory_msgs/'
                        'JointTrajectory in YAML, as ros2 topic pub and '
                        'launch files read it (needs t; joint names from '
                        'the --params file\'s joint_names, default '
                        'slider_a, slider_b, slider_c)')
    add_output(parser, 'result file')


def run_batch(robot, args):
    """Solve every row of a trajectory file; write CSV or a JointTrajectory."""
    name, times, p, v, a, lines = read_trajectory(args.input)
    sol = solve_trajectory(robot, name, times, lines, p, v, a)
    if args.format == 'joint_trajectory':
        data = joint_trajectory_yaml(_time_from_start(times, lines, name),
                                     sol, params_joint_names(args.parameters))
    else:
        data = csv_text(times, p, sol)
    write_output(args.output, data)
    missing = [group for group, values in (('velocity (vx, vy, vz)', v), (
        'acceleration (ax, ay, az)', a)) if values is None]
    if missing:     # once written: a refusal stays one line
        print(f'{PROG}: note: {name} has no ' + ' and no '.join(missing)
              + ' columns: taken as zero', file=sys.stderr)
    return 0


def _time_from_start(times, lines, name):
    """
    Return the rows' ``t`` as time_from_start in nanoseconds (int64).

    Refused (CliError): no row, no ``t`` column, or a ``t`` that is
    negative, not below 2**31 s (a Duration's int32 seconds) or, rounded
    to the nanosecond, not later than the row before it.
    """
    if times is None:
        raise CliError(f'{name}: no \'t\' column: a joint trajectory '
                       'needs each point\'s time_from_start (s)')
    if len(times) == 0:
        raise CliError(f'{name}: no data row: a joint trajectory needs at '
                       'least one point')
    bad = (times < 0.0) | (times >= 2.0 ** 31)
    nanoseconds = np.round(np.where(bad, 0.0, times) * 1e9).astype(np.int64)
    bad |= np.r_[False, np.diff(nanoseconds) <= 0]
    if bad.any():
        row = int(np.argmax(bad)) + 1
        raise CliError(f'{name}: data row {row} (line {lines[row - 1]}): '
                       't must be in [0, 2**31) s and increase from row to '
                       'row (to the nanosecond)')
    return nanoseconds


SUBCOMMANDS = (
    Subcommand(
        'paper', run_paper, add_paper,
        'reproduce the paper\'s figures 3-8',
        'Solve the trajectory of eq. (6), r_G(t) = r* (1 - '
        'cos(pi t / 3)) with r* = (0.05, 0.10, -0.20) m, over [0, 2] s: '
        'actuator displacements lambda (m; figures 3-5) and powers p (W; '
        'figures 6-8). Without --csv or --plot, print peak |lambda| (m), '
        '|force| (N), |power| (W) per actuator and the statics force (N) at '
        't = 0.'),
    Subcommand(
        'solve', run_solve, add_solve,
        'solve one sample',
        'Inverse kinematics and dynamics of one sample: lambda '
        '(m), lambdadot (m/s), lambdaddot (m/s^2), force (N, on each slider '
        'along +lambda) and power (W) of actuators A, B, C.'),
    Subcommand(
        'batch', run_batch, add_batch,
        'solve a trajectory CSV file',
        'Solve every row of a trajectory CSV file. Columns are '
        'matched by header name, in any order, case-insensitively; others '
        'are ignored. x, y, z (m) are required; vx, vy, vz (m/s) and ax, '
        'ay, az (m/s^2) are optional, each group all or none, a missing '
        'group meaning zero; t (s) is optional and copied to the output, '
        'left empty if absent. Blank lines are skipped; rows are counted '
        'from 1 after the header. Output columns: ' + _COLUMNS + ' (SI '
        'units). Nothing is written unless every row is solved.'),
)
