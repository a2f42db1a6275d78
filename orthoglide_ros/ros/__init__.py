"""
The ROS glue: rclpy nodes that hand messages to the cores.

``<node>_node.py`` for each core of :mod:`orthoglide_ros.cores` (and
``recorder_node`` for ``orthoglide record``), :mod:`node_runtime`
(``InputNode``: parameters, logging, ``/diagnostics``, ``run()``),
:mod:`input_threads` and :mod:`reply_guard` (the two workarounds of
upstream behaviour, each saying how to tell when it can go),
:mod:`service_replies` (the reply rule) and :mod:`console` (the console
scripts).
"""
