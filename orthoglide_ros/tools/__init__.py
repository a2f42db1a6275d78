"""
The ``orthoglide`` command-line tool and what only it uses, without ROS.

:mod:`cli` (the subcommands), :mod:`identification` (the robot's masses
and friction from a log) and :mod:`drawing` (the pictures). ``orthoglide
record`` alone imports rclpy, from :mod:`orthoglide_ros.ros`.
"""
