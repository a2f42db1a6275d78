"""
The ``orthoglide`` command-line tool and what only it uses, without ROS.

:mod:`cli` (the subcommands), :mod:`identification` (the robot's masses,
drives and friction from a log), :mod:`excitation_design` (a motion that
identifies them), :mod:`drawing` and :mod:`rendering` (pictures).
``orthoglide record`` alone imports rclpy, from :mod:`orthoglide_ros.ros`.
See doc/cli.md.
"""
