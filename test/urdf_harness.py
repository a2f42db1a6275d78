"""
Helpers for the URDF tests: load it with an independent library, check its cuts.

The URDF is loaded with ``yourdfpy`` (its own parser and forward
kinematics, no code of this package), a joint state is applied by name, and
:func:`cut_errors` measures how far the tree is from closing: the
``platform`` link from G, each ``x_leg_end`` from its ``x_platform_mount``
and each parallelogram's two A7 frames from each other.
"""

import io
from pathlib import Path

import numpy as np
import pytest

# Not on every apt ROS install (no rosdep key): the URDF tests skip then.
yourdfpy = pytest.importorskip('yourdfpy')

ROOT = Path(__file__).resolve().parents[1]
COMMITTED_URDF = ROOT / 'urdf' / 'orthoglide.urdf'
LEG_PREFIXES = ('a', 'b', 'c')
# Closure tolerances: 1e-9 m and 1e-9 rad.
TOLERANCE = 1e-9


def load(text):
    """Return a yourdfpy URDF of the text (no meshes, no collision scene)."""
    return yourdfpy.URDF.load(io.StringIO(text), build_scene_graph=True,
                              load_meshes=False,
                              build_collision_scene_graph=False)


def rotation_angle(r):
    """
    Return the angle (rad) of a rotation matrix.

    From both its sine (the antisymmetric part) and its cosine (the trace):
    the arccosine of the trace alone loses half the digits near 0.
    """
    sine = np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0],
                           r[1, 0] - r[0, 1]]) / 2.0
    return float(np.arctan2(sine, (np.trace(r) - 1.0) / 2.0))


def rotation_z(angle):
    """Return the active rotation by ``angle`` (rad) about z."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def cut_errors(model, names, positions, centre, phi32):
    """
    Apply a joint state; return the worst distance (m) and angle (rad).

    ``names``, ``positions``: the joint state; ``centre``: where G must be
    (m, frame 0); ``phi32``: each leg's phi32 (rad), by which the A7 frame
    on the rod is turned from the one on the bar (about their z axis).
    Checks ``platform`` at G with frame 0's orientation, ``x_leg_end`` on
    ``x_platform_mount``, and the two A7 frames of each parallelogram.
    """
    model.update_cfg(dict(zip(names, positions)))
    transform = model.get_transform
    platform = transform('platform', 'base_link')
    distance = np.abs(platform[:3, 3] - centre).max()
    angle = rotation_angle(platform[:3, :3])
    for leg, turn in zip(LEG_PREFIXES, phi32):
        end = transform(f'{leg}_leg_end', 'base_link')
        mount = transform(f'{leg}_platform_mount', 'base_link')
        distance = max(distance, np.abs(end[:3, 3] - mount[:3, 3]).max())
        angle = max(angle, rotation_angle(end[:3, :3].T @ mount[:3, :3]))
        bar = transform(f'{leg}_a7_bar', 'base_link')
        rod = transform(f'{leg}_a7_rod', 'base_link')
        distance = max(distance, np.abs(bar[:3, 3] - rod[:3, 3]).max())
        angle = max(angle, rotation_angle(
            (bar[:3, :3] @ rotation_z(-turn)).T @ rod[:3, :3]))
    return distance, angle
