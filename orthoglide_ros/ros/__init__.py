"""
The ROS glue: rclpy nodes that hand messages to the cores.

``<node>_node.py`` for each core of :mod:`orthoglide_ros.cores` (and
``recorder_node`` for ``orthoglide record``), each a
:class:`managed_node.ManagedNode` whose ``build`` says, one line per input,
which topic feeds which method of its core; :mod:`input_threads` and
:mod:`reply_guard` hold the workarounds of upstream behaviour (each saying
how to tell it can go: ``benchmarks/upstream_checks.py``).
"""
