"""
Pictures of the Orthoglide from its model: a still (PNG), an animation (GIF).

Every body where :func:`bodies.elements` puts it (the joint centres of
eqs. 1-8), the actuator axes, the paper's tested cube and the actuator
forces as arrows, on matplotlib's Agg canvas (imported on first use).
:func:`draw` (one position, the statics forces), :func:`animate` (a
trajectory), :func:`frame_rows`. See doc/cli.md#draw.
"""

import io
import math
import os
import tempfile

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.urdf import LEG_COLOURS

# Half side of the paper's tested workspace, |x|, |y|, |z| <= 0.3 m.
WORKSPACE_CUBE = 0.3
# Longest force arrow (m), for the largest |force| of the picture.
ARROW = 0.35
DPI = 100
# The segments drawn per leg: (from, to, what) with joint centres of
# bodies.elements; 'bar' in the leg's colour, 'rod' in steel grey.
SEGMENTS = (('A1', 'A2', 'rod'), ('A3', 'A6', 'rod'), ('A3', 'A4', 'bar'),
            ('A6', 'A7', 'bar'), ('A4', 'A7', 'rod'), ('A5', 'G', 'rod'))
STEEL = (0.3, 0.3, 0.35)
# Cube edges as pairs of corner indices (corner bits: x, y, z).
_EDGES = [(a, b) for a in range(8) for b in range(8)
          if a < b and bin(a ^ b).count('1') == 1]


def draw(robot, position, size=(800, 800), title=None):
    """
    Draw the robot with its platform centre at ``position`` (m, frame 0).

    Shows every body, the actuator axes, the workspace cube and the forces
    that hold the robot at rest there (:func:`mechanics.solve`, N). Returns
    PNG bytes of ``size`` (width, height) pixels. Raises
    :class:`mechanics.WorkspaceError` where the position is refused.
    """
    force = mechanics.solve(robot, position).force
    scene = _Scene(robot, size, max(abs(f) for f in force))
    scene.update(position, force, title or (
        f'Orthoglide at G = {_mm(position)} mm, at rest'))
    buffer = io.BytesIO()
    scene.figure.savefig(buffer, format='png', dpi=DPI)
    return buffer.getvalue()


def animate(robot, times, positions, forces, size=(640, 640), fps=20.0,
            title='Orthoglide'):
    """
    Animate the robot along a trajectory, one frame per sample.

    ``times`` (s, or None: frames are numbered), ``positions`` (N, 3) of G
    (m, frame 0), ``forces`` (N, 3) of actuators A, B, C (N). Returns GIF
    bytes of ``size`` pixels, ``fps`` frames per second, looping. Raises
    :class:`mechanics.WorkspaceError` where a position is refused.
    """
    from matplotlib.animation import PillowWriter

    positions = np.asarray(positions, dtype=float)
    forces = np.asarray(forces, dtype=float)
    scene = _Scene(robot, size, float(np.abs(forces).max(initial=0.0)))
    writer = PillowWriter(fps=fps)
    handle, path = tempfile.mkstemp(suffix='.gif')
    os.close(handle)
    try:
        with writer.saving(scene.figure, path, DPI):
            for i, (p, f) in enumerate(zip(positions, forces)):
                when = (f't = {times[i]:.3f} s' if times is not None
                        else f'sample {i + 1} of {len(positions)}')
                scene.update(p, f, f'{title}: {when}')
                writer.grab_frame()
        with open(path, 'rb') as stream:
            return stream.read()
    finally:
        os.unlink(path)


def frame_rows(samples, frames):
    """
    Return the indices of at most ``frames`` samples spread evenly.

    Over ``samples`` samples, the first and the last included.

    >>> frame_rows(11, 3).tolist()
    [0, 5, 10]
    """
    count = max(1, min(frames, samples))
    return np.unique(np.linspace(0, samples - 1, count).round().astype(int))


class _Scene:
    """A figure with the static parts drawn and the moving parts to update."""

    def __init__(self, robot, size, force_scale):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.robot = robot
        width, height = size
        self.figure = Figure(figsize=(width / DPI, height / DPI), dpi=DPI)
        FigureCanvasAgg(self.figure)
        ax = self.figure.add_axes((0.0, 0.0, 1.0, 0.93), projection='3d')
        self.ax = ax
        home = elements(robot, mechanics.ZERO)
        low = min(float(home[leg]['joints']['A1'].min()) for leg in 'ABC')
        span = (low - 0.1, WORKSPACE_CUBE + 0.15)
        ax.set_xlim(*span)
        ax.set_ylim(*span)
        ax.set_zlim(*span)
        ax.set_box_aspect((1.0, 1.0, 1.0))
        ax.view_init(elev=24.0, azim=-130.0)
        ax.set_xlabel('x0 (m)')
        ax.set_ylabel('y0 (m)')
        ax.set_zlabel('z0 (m)')
        ax.tick_params(labelsize=7)
        # The workspace cube and the actuator axes (each through its point
        # a_i: frame 0's origin on the drawing's robot).
        ax.plot(*_cube_edges(np.zeros(3), WORKSPACE_CUBE), color='0.6',
                linewidth=0.8, linestyle=':')
        self.axes = {}
        for leg, built in zip('ABC', robot.legs):
            bodies = home[leg]['bodies']
            axis = bodies[1]['rotation'][2]           # z1 in frame 0
            ends = np.asarray(built.point) + np.array(
                [span[0] * axis, span[1] * axis])
            ax.plot(*ends.T, color='0.45', linewidth=0.8, linestyle='--')
            ax.text(*ends[0], f'actuator {leg}', fontsize=8,
                    color=LEG_COLOURS[leg][:3])
            self.axes[leg] = axis
        self.lines = {}
        for leg in 'ABC':
            for start, end, kind in SEGMENTS:
                colour = LEG_COLOURS[leg][:3] if kind == 'bar' else STEEL
                self.lines[leg, start, end], = ax.plot(
                    [], [], [], color=colour,
                    linewidth=2.5 if kind == 'bar' else 2.0)
            self.lines[leg, 'slider'], = ax.plot(
                [], [], [], marker='s', markersize=8, linestyle='',
                color=STEEL)
            self.lines[leg, 'force'], = ax.plot(
                [], [], [], color='black', linewidth=2.5, marker='o',
                markersize=4, markevery=[1])
        self.platform, = ax.plot([], [], [], color='0.35', linewidth=1.2)
        self.labels = {leg: ax.text2D(0.02, 0.95 - 0.04 * i, '',
                                      transform=ax.transAxes, fontsize=9)
                       for i, leg in enumerate('ABC')}
        self.note = ax.text2D(
            0.02, 0.81, f'dotted: the workspace cube |x|, |y|, |z| <= '
            f'{WORKSPACE_CUBE:g} m;\narrows: the actuator forces on the sliders',
            transform=ax.transAxes, fontsize=7, color='0.4')
        self.title = self.figure.suptitle('', fontsize=11)
        self.scale = ARROW / force_scale if force_scale > 0.0 else 0.0

    def update(self, position, force, title):
        """Move every body to ``position`` (m); show ``force`` (N)."""
        legs = elements(self.robot, position)
        for leg, f in zip('ABC', force):
            joints = legs[leg]['joints']
            for start, end, _ in SEGMENTS:
                self.lines[leg, start, end].set_data_3d(
                    *np.array([joints[start], joints[end]]).T)
            slider = joints['A1']
            self.lines[leg, 'slider'].set_data_3d(*slider[:, None])
            tip = slider + self.scale * f * self.axes[leg]
            arrow = self.lines[leg, 'force']
            arrow.set_data_3d(*np.array([slider, tip]).T)
            self.labels[leg].set_text(f'f_{leg} = {f:8.2f} N')
            self.labels[leg].set_color(LEG_COLOURS[leg][:3])
        self.platform.set_data_3d(*_cube_edges(
            legs['A']['joints']['G'], self.robot.l / 2.0))
        self.title.set_text(title)


def _cube_edges(centre, half):
    """Return x, y, z of a cube's 12 edges as one line (NaN between)."""
    corners = np.array([[(i >> k) & 1 for k in range(3)]
                        for i in range(8)], dtype=float)
    corners = centre + (2.0 * corners - 1.0) * half
    points = []
    for a, b in _EDGES:
        points += [corners[a], corners[b], [math.nan] * 3]
    return np.array(points).T


def _mm(position):
    return '(' + ', '.join(f'{1e3 * float(v):.0f}' for v in position) + ')'
