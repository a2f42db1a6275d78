"""
The Orthoglide parallel robot for ROS 2: its mechanics, nodes and tool.

:mod:`.model` (the paper's mechanics, plain numpy), :mod:`.formats` (files
and messages), :mod:`.cores` (the nodes' rules, without ROS), :mod:`.ros`
(the rclpy glue), :mod:`.tools` (the ``orthoglide`` tool). See README.md
and doc/mechanics.md.
"""
