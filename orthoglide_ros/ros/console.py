"""
The nodes' console scripts: signals and memory bounds first, then imports.

``ros2 run orthoglide_ros feedforward`` runs :func:`feedforward`, and so on
for each node. The first things each does, before any import of rclpy,
numpy or the node's module (about 0.3 s), are
:func:`orthoglide_ros.cores.memory.bound` (one malloc arena, small thread
stacks, one OpenBLAS thread: what ``lock_memory`` would lock is bounded
before the first thread is made) and :func:`install_signal_handlers`:
from then on SIGINT (Ctrl-C) and SIGTERM only record that a stop was asked.
The node's ``run()`` (``node_runtime.run``) looks at :data:`STOP` before it
starts and while it spins, so a signal at any moment, during the imports
included, ends the process with exit code 0 and nothing on standard error
(Python's defaults would print a KeyboardInterrupt traceback or die by the
signal). Once ``main()`` returns, both signals are ignored: Python's
finalization puts the default action back for any other handler, and a
signal during the exit (Fast DDS's teardown: tens of
milliseconds) would kill the process with -2 or -15 instead of its code.

This module imports only the standard library (and the standard-library
module :mod:`orthoglide_ros.cores.memory`).
"""

import importlib
import signal

from orthoglide_ros.cores import memory

# The signals received so far (their numbers): a stop was asked if any.
STOP = []


def install_signal_handlers():
    """Make SIGINT and SIGTERM append to :data:`STOP`; return STOP."""
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, _record)
    return STOP


def _record(number, frame):
    STOP.append(number)


def _run(module):
    install_signal_handlers()
    memory.bound()
    try:
        return importlib.import_module(f'orthoglide_ros.ros.{module}').main()
    finally:
        for number in (signal.SIGINT, signal.SIGTERM):
            signal.signal(number, signal.SIG_IGN)


def feedforward():
    """Run the ``feedforward`` node; return its exit code."""
    return _run('feedforward_node')


def simulator():
    """Run the ``simulator`` node; return its exit code."""
    return _run('simulator_node')


def tracking_controller():
    """Run the ``tracking_controller`` node; return its exit code."""
    return _run('tracking_controller_node')


def setpoint_publisher():
    """Run the ``setpoint_publisher`` node; return its exit code."""
    return _run('setpoint_publisher_node')


def mechanism_state_publisher():
    """Run the ``mechanism_state_publisher`` node; return its exit code."""
    return _run('mechanism_state_publisher_node')


def planner():
    """Run the ``planner`` node; return its exit code."""
    return _run('planner_node')
