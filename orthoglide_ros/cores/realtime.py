"""
Real-time scheduling of a node's process, without ROS: priority, CPUs, memory.

:func:`apply` makes the parameters of :data:`SPECS` hold for every thread,
once, as the node is made, one warning per refusal; :func:`in_effect`
reads back what holds (doc/deployment.md#real-time).
"""

from collections import namedtuple
import ctypes
import errno
import os
import resource

from orthoglide_ros.cores.parameters import Spec

# SCHED_FIFO priorities (sched_get_priority_min/max on Linux).
PRIORITY_RANGE = (0, 99)
# mlockall(2) flags; the capabilities that lift RLIMIT_RTPRIO (SCHED_FIFO)
# and RLIMIT_MEMLOCK.
MCL_CURRENT, MCL_FUTURE, MCL_ONFAULT = 1, 2, 4
CAP_SYS_NICE, CAP_IPC_LOCK = 23, 14
# The RLIMIT_MEMLOCK a node needs locked, without CAP_IPC_LOCK (bytes): with
# MCL_FUTURE a mapping that would take the locked memory beyond the limit
# fails (an allocation error in the node, mlockall(2)), and a node's
# mappings reach 210-300 MB as it runs (doc/deployment.md#memory-locked).
MEMLOCK_NEEDED = 512 << 20
POLICIES = {os.SCHED_OTHER: 'SCHED_OTHER', os.SCHED_FIFO: 'SCHED_FIFO',
            os.SCHED_RR: 'SCHED_RR', os.SCHED_BATCH: 'SCHED_BATCH',
            os.SCHED_IDLE: 'SCHED_IDLE'}
# Rounds of "list the threads, set the new ones": a thread made meanwhile
# by one not yet set is found by the next round.
ROUNDS = 10
_ONLINE = '/sys/devices/system/cpu/online'


def machine_cpus():
    """Return the CPUs this machine has online, as a sorted tuple."""
    try:
        with open(_ONLINE) as f:
            return _cpu_list(f.read())
    except (OSError, ValueError):
        return tuple(range(os.cpu_count() or 1))


def _cpu_list(text):
    """Read a kernel CPU list (``0-3,6``) as a sorted tuple."""
    cpus = set()
    for part in text.strip().split(','):
        low, _, high = part.partition('-')
        cpus.update(range(int(low), int(high or low) + 1))
    return tuple(sorted(cpus))


def _cpus(value):
    """Return the CPUs of ``cpu_affinity`` as a sorted tuple (a Spec check)."""
    have = machine_cpus()
    missing = sorted({c for c in value if c not in have})
    if missing:
        raise ValueError(
            f'CPU {", ".join(map(str, missing))} is not a CPU of this '
            f'machine (it has {format_cpus(have)})')
    return tuple(sorted(set(value)))


SPECS = (
    Spec('thread_priority', 'integer', 0,
         'real-time priority of every thread of the node\'s process: 0 '
         'leaves the scheduling it was started with (the OS\'s normal one); '
         '1-99 runs every thread SCHED_FIFO at that priority '
         '(ros2_control\'s default: 50)', PRIORITY_RANGE, read_only=True),
    Spec('cpu_affinity', 'integer_array', [],
         'CPUs every thread of the node\'s process may run on; empty: as '
         'started (any CPU)', check=_cpus, read_only=True),
    Spec('lock_memory', 'bool', False,
         'lock every page of the process in memory from its first use '
         '(mlockall current, future, on fault): the loop never waits for a '
         'page', read_only=True),
)
NAMES = tuple(s.name for s in SPECS)


def settings_of(values):
    """
    Return ``(thread_priority, cpu_affinity, lock_memory)`` checked.

    ``values``: ``{name: value}`` of a node's parameters, None or absent
    taking the default; raises :class:`ParameterError` naming the first
    bad one.

    >>> settings_of({s.name: s.default for s in SPECS})
    (0, (), False)
    """
    return tuple(spec.validate(spec.default if values.get(spec.name) is None
                               else values[spec.name]) for spec in SPECS)


def format_cpus(cpus):
    """Return CPUs as the kernel writes a list: ``0-3,6``."""
    cpus = sorted(cpus)
    parts, start = [], None
    for i, cpu in enumerate(cpus):
        if start is None:
            start = cpu
        if i + 1 == len(cpus) or cpus[i + 1] != cpu + 1:
            parts.append(str(start) if start == cpu else f'{start}-{cpu}')
            start = None
    return ','.join(parts) or 'none'


def apply(thread_priority, cpu_affinity, lock_memory):
    """
    Make the settings hold for every thread of this process.

    Memory first (a locked page is never faulted in later), then the CPUs,
    then the priority, on every task of ``/proc/self/task`` (threads made
    later inherit them). Returns the warnings, one line per setting the OS
    refused, naming the limit and its fix (empty: all in effect); a refused
    setting is left as it was.

    >>> apply(0, (), False)
    []
    """
    warnings = []
    if lock_memory:
        warnings += _lock_memory()
    if cpu_affinity:
        cpus = set(cpu_affinity)
        warnings += every_thread(
            lambda tid: os.sched_setaffinity(tid, cpus), os.sched_getaffinity,
            os.sched_setaffinity, lambda error: _affinity_refused(
                cpu_affinity, error))
    if thread_priority:
        param = os.sched_param(thread_priority)
        warnings += every_thread(
            lambda tid: os.sched_setscheduler(tid, os.SCHED_FIFO, param),
            lambda tid: (os.sched_getscheduler(tid), os.sched_getparam(tid)),
            lambda tid, old: os.sched_setscheduler(tid, *old),
            lambda error: priority_refused(thread_priority, error))
    return warnings


def capable(capability):
    """Whether this process holds ``capability`` (its effective set)."""
    with open('/proc/self/status') as f:
        effective = next(int(line.split()[1], 16) for line in f
                         if line.startswith('CapEff:'))
    return bool(effective >> capability & 1)


def every_thread(change, read, restore, refused, pid='self'):
    """
    ``change(tid)`` for every thread of ``pid``, found anew until none is new.

    The OS refusing one (an OSError other than a thread that has ended)
    puts back what was changed (``restore(tid, read(tid))``) and returns
    ``[refused(error)]``; else ``[]``.
    """
    done = {}
    try:
        for _ in range(ROUNDS):
            new = [tid for tid in thread_ids(pid) if tid not in done]
            if not new:
                break
            for tid in new:
                try:
                    old = read(tid)
                    change(tid)
                except ProcessLookupError:  # the thread ended meanwhile
                    continue
                done[tid] = old
    except OSError as error:
        for tid, old in done.items():
            try:
                restore(tid, old)
            except OSError:
                pass
        return [refused(error)]
    return []


def thread_ids(pid='self'):
    """Return the thread ids of a process (this one by default)."""
    return [int(name) for name in os.listdir(f'/proc/{pid}/task')]


def soft_limit(kind):
    """Return this process's soft limit ``kind`` ('unlimited' if none)."""
    soft = resource.getrlimit(kind)[0]
    return 'unlimited' if soft == resource.RLIM_INFINITY else soft


def priority_refused(priority, error):
    """Return the warning line of a refused SCHED_FIFO ``priority``."""
    return (
        f'thread_priority {priority} refused by the OS ({error.strerror}): '
        'SCHED_FIFO needs CAP_SYS_NICE or an RLIMIT_RTPRIO of at least '
        f'{priority} (it is {soft_limit(resource.RLIMIT_RTPRIO)}); allow it '
        'with "<user> - rtprio 99" in /etc/security/limits.conf, '
        'LimitRTPRIO=99 in a systemd unit, or docker run '
        '--cap-add=sys_nice --ulimit rtprio=99; running at normal '
        'scheduling')


def _affinity_refused(cpus, error):
    return (
        f'cpu_affinity {format_cpus(cpus)} refused by the OS '
        f'({error.strerror}): this process may run on CPUs '
        f'{format_cpus(os.sched_getaffinity(0))} only (its cpuset: docker '
        'run --cpuset-cpus, systemd AllowedCPUs=); running on those')


def _lock_memory():
    limit = soft_limit(resource.RLIMIT_MEMLOCK)
    if limit != 'unlimited' and limit < MEMLOCK_NEEDED and \
            not capable(CAP_IPC_LOCK):
        return [_memory_refused(
            f'(RLIMIT_MEMLOCK {limit // 1024} kiB, no CAP_IPC_LOCK): it '
            f'needs {MEMLOCK_NEEDED >> 20} MiB, room for what a node maps as '
            'it runs, since once locked an allocation beyond the limit '
            'fails')]
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0:
        return []
    if ctypes.get_errno() == errno.EINVAL:     # before Linux 4.4
        if libc.mlockall(MCL_CURRENT | MCL_FUTURE) == 0:
            return []
    error = ctypes.get_errno()
    limit = limit if limit == 'unlimited' else f'{limit // 1024} kiB'
    return [_memory_refused(
        f'by the OS ({os.strerror(error)}): mlockall needs CAP_IPC_LOCK or '
        f'an RLIMIT_MEMLOCK above the process\'s '
        f'{_status_kb("VmSize") // 1024} MiB (it is {limit})')]


def _memory_refused(reason):
    return (
        f'lock_memory refused {reason}; allow it with "<user> - memlock '
        'unlimited" in /etc/security/limits.conf, LimitMEMLOCK=infinity in '
        'a systemd unit, or docker run --ulimit memlock=-1; memory not '
        'locked')


def _status_kb(key):
    """Return a ``kB`` value of /proc/self/status (0 if absent)."""
    with open('/proc/self/status') as f:
        for line in f:
            if line.startswith(key + ':'):
                return int(line.split()[1])
    return 0


Effect = namedtuple('Effect', 'policy priority cpus threads alike '
                    'locked_kb resident_kb')
Effect.__doc__ = """What holds for the process, read from ``/proc``.

``policy`` (a name of :data:`POLICIES`), ``priority`` (its real-time
priority, 0 for SCHED_OTHER) and ``cpus`` (a sorted tuple) of the main
thread; ``threads``: how many the process has; ``alike``: how many of them
run at that policy, priority and CPUs; ``locked_kb``: VmLck, the memory
under the lock (kB: every mapping whole, reserved or touched, as
RLIMIT_MEMLOCK counts it); ``resident_kb``: VmRSS, the memory in RAM (kB;
locked, the pages the lock holds)."""


def in_effect():
    """Return the :class:`Effect` that holds now."""
    main = os.getpid()
    rows = []
    for tid in thread_ids():
        try:
            with open(f'/proc/self/task/{tid}/stat') as f:
                fields = f.read().rsplit(')', 1)[1].split()
            cpus = tuple(sorted(os.sched_getaffinity(tid)))
        except (OSError, IndexError):   # the thread ended meanwhile
            continue
        # stat(5): field 40 rt_priority, 41 policy; fields[0] is field 3.
        rows.append((tid, int(fields[38]), int(fields[37]), cpus))
    mine = next((r for r in rows if r[0] == main), rows[0])
    alike = sum(1 for r in rows if r[1:] == mine[1:])
    return Effect(POLICIES.get(mine[1], str(mine[1])), mine[2], mine[3],
                  len(rows), alike, _status_kb('VmLck'),
                  _status_kb('VmRSS'))


def status_values(effect):
    """Return the diagnostics' ``(key, value)`` pairs of an Effect."""
    return [('scheduling policy', effect.policy),
            ('thread priority', effect.priority),
            ('cpu affinity', format_cpus(effect.cpus)),
            ('threads at that policy', f'{effect.alike} of {effect.threads}'),
            ('memory locked (kB)', effect.locked_kb),
            ('memory resident (kB)', effect.resident_kb)]


def shortfall(thread_priority, cpu_affinity, lock_memory, effect):
    """
    Return what was asked and does not hold, as one line, or None.

    The diagnostics turn WARN with it: a node asked to run in real time
    that does not (the OS refused, or a thread escaped) is degraded.
    """
    missing = []
    if thread_priority and (effect.policy, effect.priority) != (
            'SCHED_FIFO', thread_priority):
        missing.append(f'SCHED_FIFO {thread_priority} asked, '
                       f'{effect.policy} {effect.priority} in effect')
    if cpu_affinity and effect.cpus != tuple(cpu_affinity):
        missing.append(f'CPUs {format_cpus(cpu_affinity)} asked, '
                       f'{format_cpus(effect.cpus)} in effect')
    if (thread_priority or cpu_affinity) and effect.alike < effect.threads:
        missing.append(f'{effect.threads - effect.alike} of '
                       f'{effect.threads} threads not at that policy')
    if lock_memory and not effect.locked_kb:
        missing.append('lock_memory asked, no memory locked')
    return 'real time not in effect: ' + '; '.join(missing) if missing \
        else None
