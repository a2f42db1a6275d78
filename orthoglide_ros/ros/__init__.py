"""
The ROS glue: rclpy nodes that hand messages to the cores.

``<node>_node.py`` for each core of :mod:`orthoglide_ros.cores` (and
``recorder_node`` for ``orthoglide record``), each a
:class:`managed_node.ManagedNode` (the one shape: a lifecycle node around
one core, its input table, its logs); what a node owns:
:mod:`input_threads` and :mod:`reply_guard` (the two workarounds of
upstream behaviour, each saying how to tell when it can go),
:mod:`diagnostics` and :mod:`parameters`; :mod:`node_runtime` (``run()``:
the process), :mod:`service_replies` (the reply rule) and :mod:`console`
(the console scripts).
"""
