"""
Processes started and stopped the way a user does: the one way here.

:func:`start_node_process` starts a console script (a node, the
``orthoglide`` tool) or any command with its standard output and error in
temporary files; :func:`stop_process` stops it as Ctrl-C does (SIGINT,
then SIGKILL after a timeout) and gives back its exit code and what it
wrote; :func:`interrupt` is the SIGINT-then-kill rule alone;
:func:`run_to_exit` waits for a process that ends by itself. And what
``/proc`` says of a process: :func:`cpu_seconds`, :func:`rss_mb`,
:func:`memory_kb`, :func:`page_faults`, :func:`process_environment`.
"""

import os
import signal
import subprocess
import sys
import tempfile
import time

STOP_TIMEOUT = 10.0     # s between SIGINT and SIGKILL
CLK_TCK = os.sysconf('SC_CLK_TCK')


def node_executable(name='feedforward'):
    """Return the console script ``name`` next to the running Python."""
    return os.path.join(os.path.dirname(sys.executable), name)


def start_node_process(args, env=None, command=None, cwd=None):
    """
    Start ``command`` (default: the feedforward console script) + ``args``.

    ``env`` defaults to ``os.environ`` (which conftest keeps on localhost
    and in the session's domain). Standard output and error go to temporary
    files, read back by :func:`stop_process`.
    """
    command = [node_executable()] if command is None else list(command)
    out = tempfile.TemporaryFile()
    err = tempfile.TemporaryFile()
    proc = subprocess.Popen(command + list(args),
                            env=os.environ if env is None else env,
                            cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
                            stderr=err)
    proc.output_files = (out, err)
    return proc


def interrupt(proc, timeout=STOP_TIMEOUT):
    """
    Stop ``proc`` as Ctrl-C does: SIGINT, wait ``timeout`` s, then SIGKILL.

    The one process-stopping helper of the tests, scripts and benchmarks.
    Returns True when it had exited or SIGINT stopped it, False when it
    had to be killed. Safe on a process that has already exited.
    """
    if proc.poll() is not None:
        return True
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout)
        return True
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout)
        return False


def stop_process(proc, timeout=STOP_TIMEOUT):
    """
    Stop ``proc``: SIGINT, wait ``timeout`` s, then SIGKILL (:func:`interrupt`).

    Returns (exit code, standard error text); the exit code is negative for
    a signal (-9 if it had to be killed). Safe on a process that has
    already exited, and a second call returns the first one's answer.
    """
    if getattr(proc, 'stopped', None) is not None:
        return proc.stopped
    try:
        interrupt(proc, timeout)
    finally:
        out, err = proc.output_files
        err.seek(0)
        text = err.read().decode('utf-8', 'replace')
        out.seek(0)
        text_out = out.read().decode('utf-8', 'replace')
        out.close()
        err.close()
    if text_out:
        text += '\n[stdout]\n' + text_out
    proc.stopped = (proc.returncode, text)
    return proc.stopped


def timed_stop(proc):
    """Stop ``proc`` (:func:`stop_process`); return (code, stderr, seconds)."""
    start = time.monotonic()
    code, stderr = stop_process(proc)
    return code, stderr, time.monotonic() - start


def run_to_exit(args, command, timeout):
    """Start ``command`` + ``args``, wait for its exit: (code, stderr)."""
    proc = start_node_process(args, command=command)
    try:
        wait_exit(proc, timeout)
    finally:
        code, stderr = stop_process(proc)
    return code, stderr


def wait_exit(proc, timeout):
    """Wait up to ``timeout`` s for ``proc`` to exit; return its code or None."""
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        return None


def _stat(pid):
    """
    Return a process's ``/proc/<pid>/stat`` fields from field 3 on, or None.

    stat(5) numbers them from 1: ``fields[0]`` is field 3 (the state).
    """
    try:
        with open(f'/proc/{pid}/stat') as f:
            return f.read().rsplit(')', 1)[1].split()
    except (OSError, IndexError):
        return None


def cpu_seconds(pid):
    """Return utime + stime (s) of a process; None if it is gone."""
    fields = _stat(pid)
    return None if fields is None else \
        (int(fields[11]) + int(fields[12])) / CLK_TCK


def waited_ms(pid):
    """
    Return ``{thread id: ms}`` each thread of a process has waited, runnable.

    The second field of ``/proc/<pid>/task/<tid>/schedstat``: time spent
    on a run queue, ready but not run (the machine's, not the thread's
    own); an empty dict if the process is gone.
    """
    waits = {}
    try:
        tids = os.listdir(f'/proc/{pid}/task')
    except OSError:
        return waits
    for tid in tids:
        try:
            with open(f'/proc/{pid}/task/{tid}/schedstat') as f:
                waits[int(tid)] = int(f.read().split()[1]) / 1e6
        except (OSError, IndexError, ValueError):
            pass
    return waits


def rss_mb(pid):
    """Return the resident set size of a process (MB), None if it is gone."""
    try:
        with open(f'/proc/{pid}/status') as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def memory_kb(pid):
    """
    Return the memory of a process (kB) as the kernel counts it, or None.

    A dict: ``locked`` (VmLck: every locked mapping whole, as
    RLIMIT_MEMLOCK counts it), ``resident`` (VmRSS), ``mapped`` (VmSize),
    ``threads``, and from ``smaps_rollup`` ``proportional`` (Pss: shared
    pages divided among the processes that map them), ``private`` (pages
    of this process alone) and ``locked_resident`` (its locked pages,
    counted as Pss is).
    """
    keys = {'VmLck': 'locked', 'VmRSS': 'resident', 'VmSize': 'mapped',
            'Threads': 'threads', 'Pss': 'proportional',
            'Private_Clean': 'private', 'Private_Dirty': 'private',
            'Locked': 'locked_resident'}
    held = dict.fromkeys(keys.values(), 0)
    try:
        for name in ('status', 'smaps_rollup'):
            with open(f'/proc/{pid}/{name}') as f:
                for line in f:
                    key, _, value = line.partition(':')
                    if key in keys and value.split():
                        held[keys[key]] += int(value.split()[0])
    except OSError:
        return None
    return held


def page_faults(pid):
    """Return (minor, major) page faults of a process so far, or None."""
    fields = _stat(pid)     # stat(5): field 10 minflt, 12 majflt
    return None if fields is None else (int(fields[7]), int(fields[9]))


def process_environment(pid):
    """Return the environment a process started with, as a dict."""
    with open(f'/proc/{pid}/environ', 'rb') as f:
        items = f.read().split(b'\0')
    return dict(item.decode('utf-8', 'replace').split('=', 1)
                for item in items if b'=' in item)
