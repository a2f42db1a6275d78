"""
Curves written as CAM writes them: runs of short G1 chords.

What the planner's chord-run fitting is measured and tested on
(benchmarks/bench_plan.py, test/test_plan_chords.py, scripts/plan_demo.py):

- :func:`spiral_program`: the geometry of LinuxCNC's ``nc_files/spiral.ngc``
  (its "acceleration test", 2006), reconstructed, not copied: that file is
  a G20 program of 1000 chords from home's level, point ``k`` (from 0) at
  radius ``2 - 0.002 k`` inches and angle ``-0.5309648 - 0.1 k`` rad (an
  Archimedean spiral inward, 15.9 turns; chords of 5.1 mm outside, 0.05 mm
  at the centre), at F999, after ``G0 X0 Y0 Z0``; this formula gives each
  of its points within 1e-6 inch (0.025 um) once written with 6 decimals.
  The file itself (GPL) is not part of this repository:
  ``bench_plan.py --spiral FILE`` measures it where a copy is at hand.
- :func:`loop_program`: a closed 3D loop (a circle of 60 mm whose height
  is 15 mm sin 2 phi) as ``chords`` chords, 95 by default (sagitta up to
  52 um), written to 0.1 um; :func:`loop_point` the true curve;
- :func:`bulge_points`: 20 points 20 um inside the paper robot's singular
  margin (0.2) whose curve bulges 20 um beyond it, between the 10th and
  the 11th.
"""

import math

import numpy as np

SPIRAL_CHORDS = 1000
SPIRAL_START = -0.5309648           # rad
SPIRAL_FEED = 999.0                 # in/min
LOOP_RADIUS = 0.06                  # m
LOOP_HEIGHT = 0.015                 # m
LOOP_CHORDS = 95
# Where the paper robot's singular margin (0.2) crosses y = z = 0 (m), and
# its slope dx/dy there (bisection on solve_batch, 2026-12-06).
MARGIN_EDGE = 0.7869470848066686
MARGIN_SLOPE = -0.1


def spiral_points(chords=SPIRAL_CHORDS):
    """Return the spiral's programmed points (chords, 3), inches."""
    k = np.arange(chords)
    radius = 2.0 - 0.002 * k * (SPIRAL_CHORDS / chords)
    angle = SPIRAL_START - 0.1 * k * (SPIRAL_CHORDS / chords)
    return np.stack((radius * np.cos(angle), radius * np.sin(angle),
                     np.zeros(chords)), 1)


def spiral_program(chords=SPIRAL_CHORDS, mode='G64'):
    """
    Return the spiral as G-code: G20, ``mode``, from home, ``chords`` G1.

    ``mode``: the path control word (``G64``: plain, the tolerance the
    planner's); more chords sample the same spiral more densely.
    """
    lines = [f'(spiral of {chords} chords, LinuxCNC\'s spiral.ngc geometry)',
             f'G20 G90 G17 {mode}', 'G0 X0 Y0 Z0']
    lines += [f'G1 X{x:.6f} Y{y:.6f} F{SPIRAL_FEED:g}'
              for x, y, _ in spiral_points(chords)]
    return '\n'.join(lines + ['M2', ''])


def loop_point(phi):
    """Return the true loop at ``phi`` (n,) rad: p, dp/dphi, d2p/dphi2 (m)."""
    phi = np.asarray(phi, dtype=float)
    c, s = np.cos(phi), np.sin(phi)
    c2, s2 = np.cos(2 * phi), np.sin(2 * phi)
    r, h = LOOP_RADIUS, LOOP_HEIGHT
    p = np.stack((r * c, r * s, h * s2), -1)
    d1 = np.stack((-r * s, r * c, 2 * h * c2), -1)
    d2 = np.stack((-r * c, -r * s, -4 * h * s2), -1)
    return p, d1, d2


def loop_program(chords=LOOP_CHORDS, feed=30000.0, mode='G64',
                 approach=False):
    """
    Return the loop as G-code (mm, 4 decimals) and its first point (m).

    G starts at the first point (``--start``), or with ``approach`` at
    home, a G0 taking it there: ``chords`` G1 at ``feed`` (mm/min) around
    the loop, back to it.
    """
    phi = np.linspace(0.0, 2.0 * math.pi, chords + 1)
    points = loop_point(phi)[0] * 1e3
    lines = [f'(a 3D loop as CAM writes it: {chords} chords, plain G64; '
             'orthoglide_testing.chord_programs.loop_program)',
             f'G21 G90 {mode} F{feed:g}']
    if approach:
        lines.append('G0 X{:.4f} Y{:.4f} Z{:.4f}'.format(*points[0]))
    lines += ['G1 X{:.4f} Y{:.4f} Z{:.4f}'.format(*p) for p in points[1:]]
    return '\n'.join(lines + ['M2', '']), loop_point(np.zeros(1))[0][0]


def bulge_points():
    """
    Return 20 points (m) along the singular margin, each 20 um inside it.

    2 mm apart in y, on the parabola ``x = edge + 20 um + slope y - 40 y^2``
    beside the margin's edge: the curve through them reaches 20 um beyond
    it between the 10th and the 11th, the chord between them stays 20 um
    within.
    """
    y = (np.arange(20) - 9.5) * 0.002
    x = MARGIN_EDGE + 20e-6 + MARGIN_SLOPE * y - 40.0 * y ** 2
    return np.stack((x, y, np.zeros(20)), 1)
