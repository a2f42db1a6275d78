"""``draw``, ``render``, ``animate``: pictures of the robot (PNG, GIF)."""

import os

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.tools.cli.common import (
    add_output, add_position, add_size, CliError, read_trajectory,
    solve_trajectory, Subcommand, within, write_output)

# Pictures: size limits (pixels) and the animation's defaults.
MIN_PIXELS, MAX_PIXELS = 100, 4000
MAX_FRAMES = 1000
DEFAULT_FRAMES, DEFAULT_FPS = 41, 20.0
_pixels = within(int, MIN_PIXELS, MAX_PIXELS, unit=' pixels')
_frames = within(int, 1, MAX_FRAMES)
_fps = within(float, 0.5, 50.0, unit=' frames/s')


def add_draw(parser):
    """Add the options of ``draw``: a picture at one position (matplotlib)."""
    add_position(parser)
    add_output(parser, 'PNG file to write', True, 'FILE.png')
    add_size(parser, (800, 800), _pixels)


def run_draw(robot, args):
    """Draw the robot at one platform position; write a PNG."""
    _check_extension(args.output, '.png')
    drawing = _drawing_module()
    try:
        data = drawing.draw(robot, args.position, args.size)
    except mechanics.WorkspaceError as error:
        raise CliError(str(error)) from None
    write_output(args.output, data)
    return 0


def add_render(parser):
    """Add the options of ``render``: MuJoCo's picture (PNG, GIF)."""
    add_position(parser, False, '; for a PNG')
    add_output(parser, 'PNG file, or GIF (animation) to write', True,
               'FILE.png|.gif')
    _add_gif(parser, 'GIF frames along eq. (6)', 'GIF frames per second')
    add_size(parser, (800, 600), _pixels)


def _add_gif(parser, frames_help, fps_help, fps_note=''):
    """Add a GIF's ``--frames`` and ``--fps``, their defaults in the help."""
    parser.add_argument('--frames', type=_frames, default=DEFAULT_FRAMES,
                        metavar='N',
                        help=frames_help + ' (default %(default)s)')
    parser.add_argument('--fps', type=_fps, default=DEFAULT_FPS, metavar='F',
                        help=f'{fps_help} (default %(default)g{fps_note})')


def run_render(robot, args):
    """
    Render the robot with MuJoCo; write a PNG, or a GIF along eq. (6).

    A ``.png`` at ``--position``; a ``.gif``: ``--frames`` along the
    paper's trajectory (the demos' motion), ``--fps`` frames a second.
    """
    animated = args.output.lower().endswith('.gif')
    if not animated:
        _check_extension(args.output, '.png')
        if args.position is None:
            raise CliError('--position X Y Z is needed for a PNG')
    from orthoglide_ros.tools.rendering import Renderer, RenderError
    try:
        renderer = Renderer(robot, args.size)
        try:
            if animated:
                positions = trajectory.paper_batch(
                    trajectory.paper_times(max(args.frames, 2)))[0]
                data = renderer.gif(positions, args.fps)
            else:
                data = renderer.png(args.position)
        finally:
            renderer.close()
    except (RenderError, mechanics.WorkspaceError) as error:
        raise CliError(str(error)) from None
    write_output(args.output, data)
    return 0


def add_animate(parser):
    """Add the options of ``animate``: a motion with its forces (GIF)."""
    parser.add_argument('--input', metavar='FILE', help='trajectory CSV '
                        'file, - for standard input (default: the paper\'s '
                        'trajectory, eq. (6))')
    add_output(parser, 'GIF file to write', True, 'FILE.gif')
    _add_gif(parser, 'frames at most, evenly spread over the trajectory',
             'frames per second of the GIF', ': eq. (6) in real time')
    add_size(parser, (640, 640), _pixels)


def run_animate(robot, args):
    """Animate the robot along a trajectory; write a GIF."""
    _check_extension(args.output, '.gif')
    drawing = _drawing_module()
    if args.input is None:
        times = trajectory.paper_times(max(args.frames, 2))
        p, v, a = trajectory.paper_batch(times)
        where = 'the paper trajectory'
        lines = None
    else:
        where, times, p, v, a, lines = read_trajectory(args.input)
        if not len(p):
            raise CliError(f'{where}: no data row')
    sol = solve_trajectory(robot, where, times, lines, p, v, a)
    rows = drawing.frame_rows(len(p), args.frames)
    data = drawing.animate(
        robot, None if times is None else times[rows], p[rows],
        sol.force[rows], args.size, args.fps,
        'Orthoglide, ' + ('eq. (6)' if lines is None
                          else os.path.basename(where)))
    write_output(args.output, data)
    return 0


def _drawing_module():
    try:
        from orthoglide_ros.tools import drawing
        import matplotlib  # noqa: F401
    except ImportError:
        raise CliError('drawing needs matplotlib (pip install matplotlib)',
                       code=1) from None
    return drawing


def _check_extension(path, extension):
    if not path.lower().endswith(extension):
        raise CliError(f'--output {path}: the file name must end with '
                       f'{extension} (the picture is written as '
                       f'{extension[1:].upper()})')


SUBCOMMANDS = (
    Subcommand(
        'draw', run_draw, add_draw,
        'draw the robot at a position (PNG)',
        'Draw the robot in 3D with its platform centre at a '
        'position: every body, the actuator axes, the paper\'s workspace '
        'cube (|x|, |y|, |z| <= 0.3 m) and the actuator forces (N) that '
        'hold it at rest there. Needs matplotlib.'),
    Subcommand(
        'render', run_render, add_render,
        'render the robot at a position with MuJoCo (PNG)',
        'Render the robot\'s MuJoCo model (orthoglide mjcf) '
        'with its platform centre at a position, through MuJoCo\'s '
        'offscreen renderer (OpenGL: MUJOCO_GL=egl by default, or osmesa). '
        'Needs mujoco; exits 2 where no OpenGL backend exists. A .gif '
        'output animates the robot along the paper\'s trajectory.'),
    Subcommand(
        'animate', run_animate, add_animate,
        'animate the robot along a trajectory (GIF)',
        'Animate the robot along a trajectory with each '
        'actuator\'s force (N, an arrow along its slider) and the time. '
        'The trajectory is the paper\'s, eq. (6), or a CSV file read as '
        'batch reads it (x, y, z in m; vx, vy, vz in m/s and ax, ay, az in '
        'm/s^2 optional; t in s optional); its rows are sampled evenly '
        'down to --frames. Needs matplotlib.'),
)
