"""
Planning: the fastest motion of G along a path, under the robot's dynamics.

No ROS. :mod:`gcode` reads the G-code subset into moves, :mod:`path` makes
them a path of lines, exact arcs and helices and corner blends (and a
polyline of waypoints a smooth one), :mod:`limits` reads the actuators'
limits in ros2_control's ``joint_limits`` form, :mod:`programs` reads a
program file (G-code or CSV waypoints), and :mod:`parametrization` finds
the time-optimal motion along the path (TOPP-RA's reachability analysis,
its passes in :mod:`reachability`, on the package's inverse dynamics,
friction and all) and checks every sample of it with
:func:`orthoglide_ros.model.mechanics.solve_batch`.
"""
