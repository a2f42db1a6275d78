"""
The ``orthoglide`` command-line tool: the mechanics without ROS.

One module per job, each with its ``SUBCOMMANDS`` table
(:class:`.common.Subcommand` rows); :mod:`.common` what they share. Bad
input exits 2 with one line (doc/cli.md).
"""

import argparse
import os
import signal
import sys

from orthoglide_ros.formats.params_file import ParametersFileError
from orthoglide_ros.model.robot import ParameterError
from orthoglide_ros.tools.cli import (calibrating, identifying, models,
                                      pictures, planning, solving)
from orthoglide_ros.tools.cli.common import (check_distinct, check_output,
                                             CliError, CSV_COLUMNS,
                                             OUTPUT_OPTIONS, print_error,
                                             PROG, read_params, robot_of)

__all__ = ('CliError', 'CSV_COLUMNS', 'main')


def main(argv=None):
    """Run the tool on ``argv`` (default: sys.argv[1:]); return the code."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:      # --help, --version or a usage error
        return 0 if stop.code is None else stop.code
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        check_distinct(args)
        if args.command != 'record':    # a bag: the recorder's own checks
            for option in OUTPUT_OPTIONS:
                check_output(getattr(args, option, None), option)
        # Every subcommand but record reads the robot (--params), the file
        # once: args.parameters holds it for what else a command takes.
        robot = None
        if 'params' in args:
            args.parameters = read_params(args.params)
            robot = robot_of(args.parameters)
        code = args.run(robot, args)
        sys.stdout.flush()      # a reader gone shows here, not at exit
        return code
    except CliError as error:
        print_error(str(error))
        return error.code
    except (ParametersFileError, ParameterError) as error:
        print_error(str(error))
        return 2
    except BrokenPipeError:
        return _reader_gone()


def _reader_gone():
    """
    End quietly when standard output's reader has gone (``| head -1``).

    As a Unix tool killed by SIGPIPE: exit status 128 + SIGPIPE (141),
    nothing on standard error. Standard output is pointed at /dev/null so
    that Python's flush at exit raises nothing more (the recipe of
    Python's documentation, library/signal.html#note-on-sigpipe).
    """
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return 128 + signal.SIGPIPE


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose usage errors take one line (exit code 2)."""

    def error(self, message):
        """Print ``orthoglide: error: COMMAND: message`` and exit 2."""
        command = self.prog.removeprefix(PROG).strip()
        print_error(f'{command + ": " if command else ""}{message} '
                    f'({self.prog} --help lists the options)')
        self.exit(2)


def _version():
    try:
        from importlib.metadata import version
        return version('orthoglide_ros')
    except Exception:       # not installed: running from a source tree
        return 'unknown'


def _parser():
    """Return the tool's parser: the options every subcommand shares once."""
    common = _Parser(add_help=False)
    common.add_argument(
        '--params', metavar='FILE',
        help='ROS 2 parameters file with the robot.* parameters (as '
             'config/orthoglide.yaml: lengths m, angle rad, masses kg, '
             'gravity m/s^2, slider friction N s/m and N); default: the '
             'paper\'s robot')
    parser = _Parser(
        prog=PROG, description='Inverse kinematics and dynamics of the '
        'Orthoglide, without ROS. Units: m, m/s, m/s^2, N, W, s. Bad input '
        'exits with code 2 and one line on standard error.')
    parser.add_argument('--version', action='version',
                        version=f'%(prog)s {_version()}')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND')
    for module in (solving, planning, identifying, calibrating, models,
                   pictures):
        for command in module.SUBCOMMANDS:
            one = sub.add_parser(
                command.name, parents=[common] if command.robot else [],
                help=command.help, description=command.description)
            one.set_defaults(run=command.run)
            command.add(one)
    return parser
