"""
The node cores: every rule of every node, without ROS.

One module per node, named as its executable (:mod:`feedforward`,
:mod:`tracking_controller`, :mod:`simulator`, :mod:`setpoint_publisher`,
:mod:`mechanism_state_publisher`): each owns its ``PARAMETERS`` table, its
rules, its counters and its ``status()``, and takes plain values and a
time, so tests drive it without DDS. The rules they share:
:mod:`parameters` (the parameter mechanism), :mod:`inputs` (``Rejected``,
the stamp rule, byte limits, joint states by name) and :mod:`status`
(levels and periods). Nothing here imports rclpy.
"""
