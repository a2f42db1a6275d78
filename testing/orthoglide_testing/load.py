"""
A loaded machine, and the real-time set the demos and timing tests use.

The nodes of a loop run every thread SCHED_FIFO NODE_PRIORITY (their
``thread_priority``, ros2_control's default), the process that feeds and
records them CLIENT_PRIORITY, above it (doc/deployment.md#real-time):
:func:`client`, with the nodes' own :mod:`orthoglide_ros.cores.realtime`;
REALTIME says whether the OS grants it here. :func:`busy_loops` loads
the machine; :func:`add_load_options` gives a demo its ``--realtime`` and
``--load N``.
"""

from contextlib import contextmanager
import os
import resource
import subprocess
import sys

from orthoglide_ros.cores import realtime

NODE_PRIORITY = 50
CLIENT_PRIORITY = 60


def client(priority, pid='self'):
    """
    Run every thread of a process SCHED_FIFO ``priority``, not its children.

    For a process that feeds or records a real-time node and starts
    processes itself (a demo, a test, a benchmark): with
    SCHED_RESET_ON_FORK, the processes and threads it makes afterwards
    start at normal scheduling, so a node it starts runs as its own
    ``thread_priority`` says. Call it again after making threads (a DDS
    participant's) to include them. ``pid``: this process, or another one
    once it has started (its start-up, imports and discovery, then does
    not preempt the real-time loop). Returns the warnings as
    :func:`realtime.apply`.
    """
    param = os.sched_param(priority)
    return realtime.every_thread(
        lambda tid: os.sched_setscheduler(
            tid, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, param),
        lambda tid: (os.sched_getscheduler(tid), os.sched_getparam(tid)),
        lambda tid, old: os.sched_setscheduler(tid, *old),
        lambda error: realtime.priority_refused(priority, error), pid)


def normal():
    """Put every thread of this process back at normal scheduling."""
    for tid in realtime.thread_ids():
        try:
            os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
        except ProcessLookupError:  # the thread ended meanwhile
            pass


def granted(priority):
    """Whether this process may take SCHED_FIFO ``priority`` (caps, limit)."""
    limit = realtime.soft_limit(resource.RLIMIT_RTPRIO)
    if limit == 'unlimited' or limit >= priority:
        return True
    return realtime.capable(realtime.CAP_SYS_NICE)


# Whether the OS grants it here: the timing tests then run their nodes
# and their recording processes at it, so that their verdicts do not
# depend on what else the machine runs.
REALTIME = granted(CLIENT_PRIORITY)
# A busy loop that puts itself at normal scheduling first: a real-time
# parent's children inherit its policy unless it resets them.
BUSY_LOOP = ('import os; os.sched_setscheduler(0, os.SCHED_OTHER, '
             'os.sched_param(0))\nwhile True: pass')


def realtime_args(on=REALTIME):
    """Return a node's arguments for NODE_PRIORITY (none if not ``on``)."""
    return ['-p', f'thread_priority:={NODE_PRIORITY}'] if on else []


def client_prefix(on=REALTIME):
    """Return the command prefix of a client process at CLIENT_PRIORITY."""
    return ['chrt', '-f', str(CLIENT_PRIORITY)] if on else []


def elevate(proc, on=REALTIME):
    """
    Put a started client process at CLIENT_PRIORITY (every thread).

    For a process whose start-up (imports, discovery: a second of CPU)
    must not preempt a real-time loop already running, as
    :func:`client_prefix` would make it.
    """
    if on:
        client(CLIENT_PRIORITY, proc.pid)


@contextmanager
def realtime_client(on=REALTIME):
    """
    Run every thread of this process at CLIENT_PRIORITY meanwhile.

    For a test or demo that records a real-time node in its own process;
    its children start at normal scheduling (:func:`client`).
    Call it once the process's DDS participant exists.
    """
    if on:
        client(CLIENT_PRIORITY)
    try:
        yield
    finally:
        if on:
            normal()


@contextmanager
def busy_loops(count):
    """Run ``count`` busy loops (processes, normal scheduling) meanwhile."""
    procs = [subprocess.Popen([sys.executable, '-c', BUSY_LOOP],
                              stdin=subprocess.DEVNULL)
             for _ in range(count)]
    try:
        yield procs
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def add_load_options(parser, realtime_default=False):
    """
    Add a demo's ``--realtime`` and ``--load N`` to its ``parser``.

    ``realtime_default``: real time unless ``--no-realtime`` (a loop demo
    on a machine where it is granted: on two cores the loop's own five
    processes stall one another past the simulator's command timeout).
    """
    parser.add_argument('--realtime', action='store_true',
                        default=realtime_default, help=(
                            'run every thread of the loop\'s nodes '
                            f'SCHED_FIFO {NODE_PRIORITY} (their '
                            'thread_priority) and this recorder SCHED_FIFO '
                            f'{CLIENT_PRIORITY}: doc/deployment.md#real-time'
                            + (' (the default here)' if realtime_default
                               else '')))
    if realtime_default:
        parser.add_argument('--no-realtime', dest='realtime',
                            action='store_false', help='the nodes and the '
                            'recorder at normal scheduling')
    parser.add_argument('--load', type=int, default=0, metavar='N',
                        help='run N busy loops meanwhile, a loaded machine '
                        '(default 0)')


def check_load_options(parser, args):
    """Refuse a negative load, or --realtime where it is not granted."""
    if args.load < 0:
        parser.error('--load must be >= 0')
    if args.realtime and not granted(CLIENT_PRIORITY):
        parser.error('--realtime: SCHED_FIFO is not granted here '
                     '(CAP_SYS_NICE or an RLIMIT_RTPRIO, '
                     'doc/deployment.md#real-time)')
