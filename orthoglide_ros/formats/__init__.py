"""
File and message formats, without ROS.

:mod:`cdr` (serialized ROS messages read and written with numpy, the
nodes' hot paths and rosbag2 logs), :mod:`csvfile` (columns of numbers by
header name) and :mod:`params_file` (ROS 2 parameters files with rcl's
typing). They import the model and the parameter tables, never rclpy.
"""
