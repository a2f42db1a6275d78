"""
The process around a node: start-up, signals, spinning, the exit code.

:func:`run` runs every node (``console.py``) and ``orthoglide record``.
Works around rclpy 7.1.6's ``EventsExecutor.spin()``, which busy-loops
without running callbacks or seeing Ctrl-C: the executor is spun by
``spin_once`` in a loop. It can go when ``spin()`` runs a timer's
callbacks (``benchmarks/upstream_checks.py``, ``events_spin``).
"""

import gc

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.signals import SignalHandlerOptions

from orthoglide_ros.formats.text import clip

SPIN_PERIOD = 0.1   # s: the main loop sees a signal within this time


class NotStarting(ValueError):
    """A node that refuses to start; its message says why (exit 2)."""


def run(node_class, name, stop, args=None, report=None):
    """
    Run one node until Ctrl-C, SIGTERM or shutdown; return the exit code.

    0 on a normal stop, also when a signal comes during start-up; 2 when
    the node refuses its start-up parameters (ValueError or
    ParameterException, logged as FATAL, or given to ``report(reason)``:
    a tool's own one-line error) or rcl refuses the arguments.
    Ctrl-C and SIGTERM only append to ``stop`` (``console.STOP``, from
    :func:`console.install_signal_handlers`), which this loop reads within
    SPIN_PERIOD: rclpy's handlers would raise or shut the context down
    inside a callback, breaking off a publish. An exception out of the
    executor once the node runs (a defect of a callback) is counted and
    the node goes on.
    """
    if stop:
        return 0
    logger = rclpy.logging.get_logger(name)
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as error:   # rcl refuses the arguments or file
        if stop:
            return 0
        logger.fatal(clip(f'cannot start: {error}'))
        return 2
    node = None
    try:
        try:
            node = node_class()
        except (ValueError, ParameterException) as error:
            if not stop:
                reason = error if isinstance(error, NotStarting) \
                    else f'invalid parameters: {error}'
                if report is not None:
                    report(clip(str(reason)))
                else:
                    logger.fatal(clip(f'not starting: {reason}'))
                return 2
            return 0
        executor = _executor()
        executor.add_node(node)
        freeze_start_up_objects()
        # Not executor.spin(): with the EventsExecutor of the rclpy 7.1.6
        # wheels it busy-loops without running callbacks or seeing SIGINT.
        while rclpy.ok() and not stop and not node.finished:
            try:
                executor.spin_once(timeout_sec=SPIN_PERIOD)
            except ExternalShutdownException:
                break
            except Exception:   # a defect of a callback: the node goes on
                node.report_defect('in a callback of the executor')
        node.on_stop(interrupted=bool(stop) or not rclpy.ok())
    except RuntimeError:
        if rclpy.ok() and not stop:
            raise
        # Interrupted while starting: rcl calls fail on the shut-down context.
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


def freeze_start_up_objects():
    """
    Keep the start-up objects out of the garbage collector's full passes.

    After the imports and the node's construction a process tracks ~37,000
    objects (rclpy, numpy, the messages); a full (generation 2) collection
    walks them all with the GIL held, 11-16 ms measured here, a stall of
    every thread of the node that a 500 Hz-1 kHz loop sees as a hiccup.
    ``gc.freeze()`` moves them to a permanent generation: collections then
    walk only what was allocated since (0.01 ms measured after it).
    """
    gc.collect()
    gc.freeze()


def _executor():
    """Return the EventsExecutor (2.5x less CPU per message here) if any."""
    try:
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    except ImportError:
        return rclpy.executors.SingleThreadedExecutor()
