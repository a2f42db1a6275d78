"""
The address space of a node's process, bounded before its imports.

``lock_memory`` (:mod:`orthoglide_ros.cores.realtime`) locks every mapping
of the process, and the kernel counts each one whole (``VmLck``), touched
or only reserved; that count is what ``RLIMIT_MEMLOCK`` limits. On the C
library's and OpenBLAS's defaults a node maps about 950 MB, almost all of
it reserved and never used (doc/measurements.md#memory-of-the-nodes):

- glibc's malloc arenas: one per thread that allocates, up to 8 per CPU,
  each reserving 64 MiB (9 of them in a node: 576 MiB);
- thread stacks: 8 MiB each (the default ``RLIMIT_STACK``), 18 threads
  (144 MiB), where the deepest measured reaches 32 KiB;
- OpenBLAS's pool: a thread per CPU beside the main one and a 32 MiB
  buffer per thread (72 MiB on two CPUs), for the node's 3x3 matrices.

:func:`bound` caps them in the console script (``ros/console.py``) before
numpy, rclpy or the node is imported, since arenas, stacks and OpenBLAS's
threads are made as the first threads start; it applies to every node,
locked or not (unlocked, the reservations cost address space only):

- :data:`ARENAS` malloc arena (``mallopt(M_ARENA_MAX)``; the threads
  share the main heap, each with glibc's own small per-thread cache); an
  ``MALLOC_ARENA_MAX`` in the environment is left to glibc;
- :data:`NATIVE_STACK` for the stack of every thread made by C or C++
  code (Fast DDS's, LTTng's: ``pthread_setattr_default_np``), or the
  smaller default the process was started with (``ulimit -s``);
- :data:`PYTHON_STACK` for the stack of every thread made by Python
  (``threading.stack_size``): a recursion reaching Python's limit (1000
  frames) through C calls needs about 0.7 MiB, and must raise
  RecursionError, not overflow the stack;
- OpenBLAS on :data:`BLAS_THREADS` thread (``OPENBLAS_NUM_THREADS``,
  unless set).

A C library without one of these calls (not glibc >= 2.18) keeps that
default; :func:`bound` never raises. Only the standard library is imported
here.
"""

import ctypes
import os
import threading

ARENAS = 1
NATIVE_STACK = 1 << 20      # bytes: 32 times the deepest Fast DDS thread
PYTHON_STACK = 2 << 20      # bytes: about 3 times a RecursionError's depth
BLAS_THREADS = '1'
M_ARENA_MAX = -8            # mallopt(3)
_ATTR_BYTES = 128           # at least sizeof(pthread_attr_t) (56 on x86_64)


def bound(environ=os.environ):
    """
    Cap malloc arenas, thread stacks and OpenBLAS's threads (see above).

    Call it once, before the first thread starts and before numpy is
    imported. ``environ``: the environment OpenBLAS will read.
    """
    environ.setdefault('OPENBLAS_NUM_THREADS', BLAS_THREADS)
    try:
        libc = ctypes.CDLL(None, use_errno=True)
    except OSError:
        return
    if 'MALLOC_ARENA_MAX' not in environ and hasattr(libc, 'mallopt'):
        libc.mallopt(M_ARENA_MAX, ARENAS)
    _native_stack(libc, NATIVE_STACK)
    threading.stack_size(PYTHON_STACK)


def native_stack():
    """Return the default stack size (bytes) of a thread made by C code."""
    libc = ctypes.CDLL(None, use_errno=True)
    if not hasattr(libc, 'pthread_getattr_default_np'):
        return None
    attr = ctypes.create_string_buffer(_ATTR_BYTES)
    size = ctypes.c_size_t()
    if libc.pthread_getattr_default_np(attr):
        return None
    try:
        libc.pthread_attr_getstacksize(attr, ctypes.byref(size))
    finally:
        libc.pthread_attr_destroy(attr)
    return size.value


def _native_stack(libc, limit):
    """Make ``limit`` the default stack of new C threads, if smaller."""
    if not hasattr(libc, 'pthread_setattr_default_np'):
        return
    current = native_stack()
    if current is not None and current <= limit:
        return
    attr = ctypes.create_string_buffer(_ATTR_BYTES)
    if libc.pthread_attr_init(attr):
        return
    try:
        if libc.pthread_attr_setstacksize(attr, ctypes.c_size_t(limit)) == 0:
            libc.pthread_setattr_default_np(attr)
    finally:
        libc.pthread_attr_destroy(attr)
