"""
Plan the fastest motion along a program: ``plan``.

A G-code program or CSV waypoints in, the time-optimal motion of G out
(:mod:`orthoglide_ros.planning`), as the CSV ``batch`` reads or as the
JointTrajectory ``batch`` writes.
"""

import math
import sys

import numpy as np

from orthoglide_ros.formats.params_file import ParametersFileError
from orthoglide_ros.planning import parametrization
from orthoglide_ros.planning.moves import ProgramError
from orthoglide_ros.planning.limits import (limits_from_params_file,
                                            LimitsError, load_limits,
                                            paper_limits)
from orthoglide_ros.planning.programs import read_program
from orthoglide_ros.tools.cli.common import (CliError, finite_float,
                                             INPUT_GROUPS,
                                             joint_trajectory_yaml,
                                             params_joint_names, Subcommand,
                                             table_csv, within, write_output)

DEFAULT_RATE = 1000.0           # Hz
# The memory the path and its plan may take (bytes): with the
# interpreter's 50 MB, the command stays within 1 GB.
PLAN_BYTES = parametrization.MAX_BYTES
DEFAULT_TOLERANCE = 1e-5        # m
# The columns written: those ``batch`` reads.
PLAN_COLUMNS = tuple(c for _, names, _ in INPUT_GROUPS for c in names)
_rate = within(float, 1.0, 100000.0, unit=' Hz')
_tolerance = within(float, 0.0, 0.01, unit=' m')
_speed = within(float, 0.0, 100.0, above=True, unit=' m/s')


def add_plan(parser):
    """Add the options of ``plan``: the fastest motion along a program."""
    parser.add_argument('--input', required=True, metavar='PROGRAM',
                        help='G-code program or CSV waypoints; - for standard '
                        'input')
    parser.add_argument('--output', required=True, metavar='FILE',
                        help='the planned motion; - for standard output')
    parser.add_argument('--limits', metavar='FILE', help='YAML file with a '
                        'top-level joint_limits: mapping (ros2_control / '
                        'MoveIt form, per joint slider_a, slider_b, slider_c: '
                        'has_effort_limits, max_effort (N), has_velocity_limits, '
                        'max_velocity (m/s), has_acceleration_limits, '
                        'max_acceleration (m/s^2), has_jerk_limits, max_jerk '
                        '(m/s^3))')
    parser.add_argument('--rate', type=_rate, default=DEFAULT_RATE,
                        metavar='HZ', help='samples per second (default '
                        '%(default)g)')
    parser.add_argument('--start', type=finite_float, nargs=3,
                        default=[0.0, 0.0, 0.0], metavar=('X', 'Y', 'Z'),
                        help='where G starts, at rest (m, base frame; default '
                        'home 0 0 0)')
    parser.add_argument('--tolerance', type=_tolerance,
                        default=DEFAULT_TOLERANCE, metavar='M',
                        help='runs of chords of waypoints and of G64 without '
                        'P are followed as the curve they sample within this '
                        'distance of every programmed point, their corners '
                        'blended within it (m, default %(default)g; 0: G '
                        'stops at every corner)')
    parser.add_argument('--max-speed', type=_speed, default=math.inf,
                        metavar='M/S', help='G\'s speed cap beside the '
                        'programmed feed (m/s; default none)')
    parser.add_argument('--format', choices=('csv', 'joint_trajectory'),
                        default='csv', help='csv: the columns above (default); '
                        'joint_trajectory: a trajectory_msgs/JointTrajectory in '
                        'YAML with the forces as efforts, as batch writes it')


def run_plan(robot, args):
    """Plan the program; write CSV or a JointTrajectory."""
    name = '<stdin>' if args.input == '-' else args.input
    names = params_joint_names(args.parameters)
    limits, told = _limits(args, names)
    try:
        path = read_program(args.input, args.start, args.tolerance,
                            parametrization.most_pieces(PLAN_BYTES))
        motion = parametrization.plan(robot, path, limits, args.rate,
                                      args.max_speed, max_bytes=PLAN_BYTES)
    except ProgramError as error:
        raise CliError(f'{name}: {error}') from None
    if args.format == 'joint_trajectory':
        nanoseconds = np.round(motion.t * 1e9).astype(np.int64)
        data = joint_trajectory_yaml(nanoseconds, motion.solution, names)
    else:
        data = table_csv(PLAN_COLUMNS, motion.t, _Joined(
            motion.position, motion.velocity, motion.acceleration))
    write_output(args.output, data)
    if not told:
        print('orthoglide: note: no --limits and no planner section in '
              '--params: the paper robot\'s limits (doc/planning.md)',
              file=sys.stderr)
    if args.output != '-':
        print(f'planned {motion.duration:.6g} s ({len(motion.t)} samples at '
              f'{args.rate:g} Hz) along {path.length:.6g} m')
    return 0


class _Joined:
    """Arrays side by side, joined a chunk at a time (for table_csv)."""

    def __init__(self, *arrays):
        self.arrays = arrays

    def __len__(self):
        return len(self.arrays[0])

    def __getitem__(self, part):
        return np.hstack([array[part] for array in self.arrays])


def _limits(args, names):
    """
    Return ``(limits, given)``: --limits, --params' planner's, the paper's.

    The ``--params`` file as the command read it (``args.parameters``).
    """
    try:
        if args.limits is not None:
            return load_limits(args.limits, names), True
        if args.parameters is not None:
            found = limits_from_params_file(args.parameters, 'planner', names)
            if found is not None:
                return found, True
    except (LimitsError, ParametersFileError) as error:
        raise CliError(str(error)) from None
    return paper_limits(), False


SUBCOMMANDS = (
    Subcommand(
        'plan', run_plan, add_plan,
        'plan the fastest motion along a G-code program or waypoints',
        'The fastest motion of the platform centre G that '
        'starts at rest at --start, follows the program\'s path and ends at '
        'rest at its last point, within the actuators\' limits under the '
        'robot\'s own dynamics (masses, payload, armature, friction, '
        'gravity) and within the programmed feed. The program: G-code (the '
        'subset of doc/planning.md: G0 G1 G2 G3, G5 G5.1, G17-G19, '
        'G20/G21, G90/G91, G94, G61, G61.1, G64 P, F, N, comments, M2/M30; '
        'mm by default, origin at home; chords under plain G64 followed as '
        'the curve they sample) or CSV waypoints (header x,y,z in m, '
        'optional feed in m/s). Limits: --limits FILE (ros2_control\'s '
        'joint_limits form), else the --params file\'s planner section, else '
        'the paper robot\'s. Output columns: ' + ','.join(PLAN_COLUMNS)
        + ' (SI units), the last sample exactly at the end. Nothing is '
        'written unless the whole motion is planned.'),
)
