"""
The ROS glue: rclpy nodes that hand messages to the cores.

One ``<node>_node.py`` per core (and ``recorder_node``), each a
:class:`managed_node.ManagedNode`; :mod:`input_threads` and
:mod:`reply_guard` hold the workarounds of upstream behaviour.
"""
