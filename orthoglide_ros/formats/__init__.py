"""
File and message formats, without ROS.

:mod:`cdr` (serialized ROS messages), :mod:`csvfile` (columns of numbers
by header name), :mod:`logs` (the logs identification reads),
:mod:`params_file` (ROS 2 parameters files with rcl's typing) and
:mod:`text` (text from peers made safe to show). They import the model,
never rclpy.
"""
