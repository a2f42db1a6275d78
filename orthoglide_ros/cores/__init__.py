"""
The node cores: every rule of every node, without ROS.

One module per node, named as its executable, each owning its
``PARAMETERS`` table, rules, counters and ``status()``; the shared rules
in :mod:`parameters`, :mod:`inputs` and :mod:`status`.
"""
