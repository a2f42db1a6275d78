"""
The nodes' console scripts: signals and memory bounds first, then imports.

Standard library only: before rclpy or numpy, each script bounds the
memory and makes SIGINT and SIGTERM only record a stop (:data:`STOP`)
(doc/robustness.md#start-and-stop). Once the node has run, both
are ignored: a signal during Fast DDS's teardown would end the process
with -2; that can go when the teardown takes no time to speak of
(``benchmarks/upstream_checks.py``, ``teardown``).
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


def _run(name, node_class):
    stop = install_signal_handlers()
    memory.bound()
    try:
        module = importlib.import_module(f'orthoglide_ros.ros.{name}_node')
        from orthoglide_ros.ros.node_runtime import run
        return run(getattr(module, node_class), name, stop)
    finally:
        for number in (signal.SIGINT, signal.SIGTERM):
            signal.signal(number, signal.SIG_IGN)


def _node(name, node_class):
    """Return node ``name``'s console script: run it, return its exit code."""
    def script():
        return _run(name, node_class)
    script.__name__ = script.__qualname__ = name
    script.__doc__ = f'Run the ``{name}`` node; return its exit code.'
    return script


# The console scripts of setup.py, one per node: its module, its class.
feedforward = _node('feedforward', 'FeedforwardNode')
simulator = _node('simulator', 'SimulatorNode')
tracking_controller = _node('tracking_controller', 'TrackingControllerNode')
setpoint_publisher = _node('setpoint_publisher', 'SetpointPublisher')
mechanism_state_publisher = _node('mechanism_state_publisher',
                                  'MechanismStatePublisherNode')
planner = _node('planner', 'PlannerNode')
