"""``urdf``, ``mjcf``: the robot as a URDF and as a MuJoCo model."""

from orthoglide_ros.model import mechanics
from orthoglide_ros.tools.cli.common import (
    add_joint_names, add_output, non_negative_float, option_joint_names,
    positive_float, Subcommand, within, write_output)

_singularity_margin = within(float, 0.0, 0.99)


def add_urdf(parser):
    """Add the options of ``urdf``: the robot's URDF."""
    add_output(parser, 'URDF file')
    add_joint_names(parser, 'the prismatic joints')
    parser.add_argument('--singularity-margin', type=_singularity_margin,
                        default=mechanics.DEFAULT_SINGULARITY_MARGIN,
                        metavar='D', help='the workspace of the joint limits: '
                        'singularity distance at least D, in [0, 0.99] '
                        '(default %(default)g)')


def run_urdf(robot, args):
    """Write the robot's URDF (standard output or ``--output``)."""
    from orthoglide_ros.model import urdf
    names = option_joint_names(args)
    text = urdf.urdf(robot, names, args.singularity_margin)
    write_output(args.output, text.encode('utf-8'))
    return 0


def add_mjcf(parser):
    """Add the options of ``mjcf``: the robot's MJCF."""
    add_output(parser, 'MJCF file')
    add_joint_names(parser, 'the slide joints and actuators')
    parser.add_argument('--force-limit', type=positive_float, default=None,
                        metavar='N', help='the actuators\' control range '
                        '+-N (newton; default: none)')
    parser.add_argument('--armature', type=non_negative_float, nargs=3,
                        default=None, metavar=('A', 'B', 'C'),
                        help='the drives\' inertia reflected to each slider '
                        '(kg; MuJoCo\'s armature): sets robot.armature '
                        '(default: the parameters file\'s, 0 in the paper\'s '
                        'robot)')


def run_mjcf(robot, args):
    """Write the robot's MJCF (standard output or ``--output``)."""
    from orthoglide_ros.model import mjcf
    names = option_joint_names(args)
    if args.armature is not None:
        robot = robot.replace(armature=tuple(args.armature))
    text = mjcf.mjcf(robot, names, args.force_limit)
    write_output(args.output, text.encode('utf-8'))
    return 0


SUBCOMMANDS = (
    Subcommand(
        'urdf', run_urdf, add_urdf,
        'write the robot\'s URDF',
        'Write the URDF of the robot (lengths m, masses kg, '
        'inertias kg m^2, angles rad): a cut tree of the closed mechanism '
        'for robot_state_publisher, whose every moving joint the '
        'mechanism_state_publisher node publishes. Joint limits are the '
        'ranges over the workspace within the singularity margin.'),
    Subcommand(
        'mjcf', run_mjcf, add_mjcf,
        'write the robot\'s MJCF (MuJoCo)',
        'Write the robot as a MuJoCo model (MJCF): the URDF\'s '
        'bodies, masses and inertias, the loops closed by equality '
        'constraints, three force actuators named as the sliders (N); '
        'see doc/mujoco.md.'),
)
