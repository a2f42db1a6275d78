"""
Planning: the fastest motion of G along a path, under the robot's dynamics.

No ROS. At its bottom, :mod:`moves`: the moves a program is made of (a
line, an arc, a spline), the path control modes and :class:`ProgramError`
with its reasons. :mod:`gcode` reads the G-code subset into moves (a
line's words: :mod:`gcode_words`); :mod:`path` makes a path of moves, or
of waypoints: its pieces (:mod:`pieces`: helices and Bezier curves), runs
of chords followed as the curve they sample (:mod:`chords`), corners
blended (:mod:`blends`). :mod:`limits` reads the actuators' limits in
ros2_control's ``joint_limits`` form, :mod:`programs` reads a program file
(G-code or CSV waypoints), and :mod:`parametrization` finds the
time-optimal motion along the path (TOPP-RA's reachability analysis on
the package's inverse dynamics, friction and all), split as toppra
splits it: the gridpoints (:mod:`grid`), the dynamics' rows along the
path (:mod:`constraints`), the passes (:mod:`reachability`), the time
law and its samples (:mod:`timing`), jerk limits (:mod:`smoothing`),
every sample checked with
:func:`orthoglide_ros.model.mechanics.solve_batch`
(:mod:`verification`), and a plan's memory, time and refusals
(:mod:`bounds`).
"""
