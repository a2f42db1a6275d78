"""
The bounds a node's process sets before its imports (``cores/memory.py``).

In child processes (this test process keeps glibc's defaults), read from
``/proc`` by the kernel's account, not by the package's reader: the stack
of a thread is the mapping that holds its stack pointer (the ``sp`` of
``/proc/PID/task/TID/syscall`` while it sleeps); a malloc arena beyond
the main one is a 64 MiB reservation (an anonymous ``---p`` mapping of
tens of MiB). After :func:`memory.bound`, a thread made by C code (as Fast
DDS makes its own: ``pthread_create`` with default attributes) has a
1 MiB stack, a thread made by Python 2 MiB, threads that allocate make no
arena, and OpenBLAS is told one thread; without it, 8 MiB stacks and an
arena per thread. A smaller ``ulimit -s`` and a user's
``MALLOC_ARENA_MAX`` or ``OPENBLAS_NUM_THREADS`` are kept.
"""

import json
import os
import resource
import subprocess
import sys
import time

import pytest

from orthoglide_ros.cores import memory

MiB = 1 << 20
THREADS = ('native', 'python0', 'python1', 'python2')
# A child: bounds (argv[1] == 'bound') or not, then a thread made by C code
# and three made by Python, all allocating and then sleeping, named by
# prctl; prints "ready" and waits for stdin to close.
CHILD = r'''
import ctypes, json, os, sys, threading
from orthoglide_ros.cores import memory
if sys.argv[1] == 'bound':
    memory.bound()
libc = ctypes.CDLL(None)
ready = threading.Semaphore(0)

def work(name):
    libc.prctl(15, name)                   # PR_SET_NAME
    held = [bytes(4096) for _ in range(64)]  # malloc: an arena, if any
    ready.release()
    libc.sleep(60)

START = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p)
native = START(lambda arg: work(b'native'))
tid = ctypes.c_ulong()
assert libc.pthread_create(ctypes.byref(tid), None, native, None) == 0
for i in range(3):
    threading.Thread(target=work, args=(b'python%d' % i,), daemon=True).start()
for _ in range(4):
    ready.acquire()
print(json.dumps({'openblas': os.environ.get('OPENBLAS_NUM_THREADS')}),
      flush=True)
sys.stdin.read()
os._exit(0)
'''


def mappings(pid):
    """Return [(start, end, perms, name)] of /proc/PID/maps."""
    found = []
    with open(f'/proc/{pid}/maps') as f:
        for line in f:
            fields = line.split()
            start, end = (int(x, 16) for x in fields[0].split('-'))
            found.append((start, end, fields[1],
                          fields[5] if len(fields) > 5 else ''))
    return found


def stacks(pid):
    """Return {thread name: size (bytes) of the mapping its sp is in}."""
    maps = mappings(pid)
    sizes = {}
    for tid in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{tid}/comm') as f:
            name = f.read().strip()
        with open(f'/proc/{pid}/task/{tid}/syscall') as f:
            fields = f.read().split()
        if len(fields) < 3:     # running, not in a system call
            continue
        sp = int(fields[-2], 16)
        sizes[name] = next(end - start for start, end, _, _ in maps
                           if start <= sp < end)
    return sizes


def arenas(pid):
    """Return how many 64 MiB malloc reservations the process has."""
    return sum(1 for start, end, perms, name in mappings(pid)
               if not name and perms == '---p' and end - start >= 32 * MiB)


def settled_stacks(pid, names, timeout=10.0):
    """Return :func:`stacks` once every thread of ``names`` is in a call."""
    deadline = time.monotonic() + timeout
    while True:
        sizes = stacks(pid)
        if set(names) <= set(sizes) or time.monotonic() > deadline:
            return sizes
        time.sleep(0.01)


def run_child(mode, env=None, stack_limit=None):
    """Run CHILD; return (its report, stacks by thread name, arenas)."""
    def limits():
        if stack_limit is not None:
            resource.setrlimit(resource.RLIMIT_STACK,
                               (stack_limit, stack_limit))
    child_env = {k: v for k, v in os.environ.items()
                 if k not in ('MALLOC_ARENA_MAX', 'OPENBLAS_NUM_THREADS')}
    child_env.update(env or {})
    proc = subprocess.Popen([sys.executable, '-c', CHILD, mode],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            text=True, env=child_env, preexec_fn=limits)
    try:
        report = json.loads(proc.stdout.readline())
        found = settled_stacks(proc.pid, THREADS), arenas(proc.pid)
    finally:
        proc.stdin.close()
        proc.wait(10)
    return (report, *found)


@pytest.mark.skipif(not sys.platform.startswith('linux'),
                    reason='/proc and glibc')
def test_bounded_stacks_one_arena_one_blas_thread():
    report, sizes, made = run_child('bound')
    assert sizes['native'] == memory.NATIVE_STACK == MiB
    for i in range(3):
        assert sizes[f'python{i}'] == memory.PYTHON_STACK == 2 * MiB
    assert made == 0
    assert report['openblas'] == '1'


@pytest.mark.skipif(not sys.platform.startswith('linux'),
                    reason='/proc and glibc')
def test_without_the_bounds_glibc_gives_8_mib_stacks_and_arenas():
    # What the bounds are for: the defaults the kernel then locks whole.
    report, sizes, made = run_child('plain', stack_limit=8 * MiB)
    assert sizes['native'] == sizes['python0'] == 8 * MiB
    assert made >= 1
    assert report['openblas'] is None


@pytest.mark.skipif(not sys.platform.startswith('linux'),
                    reason='/proc and glibc')
def test_what_the_user_set_is_kept():
    report, sizes, made = run_child(
        'bound', env={'MALLOC_ARENA_MAX': '4', 'OPENBLAS_NUM_THREADS': '2'},
        stack_limit=512 * 1024)
    assert sizes['native'] == 512 * 1024      # ulimit -s 512, smaller
    assert sizes['python0'] == memory.PYTHON_STACK
    assert made >= 1                          # glibc's 4 arenas
    assert report['openblas'] == '2'
