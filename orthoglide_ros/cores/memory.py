"""
The address space of a node's process, bounded before its imports.

:func:`bound` caps the malloc arenas, thread stacks and OpenBLAS's threads
before numpy or rclpy is imported; standard library only
(doc/deployment.md#memory-locked).
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
    Cap malloc arenas, thread stacks and OpenBLAS's threads.

    :data:`ARENAS` arena (``mallopt(M_ARENA_MAX)``, unless
    ``MALLOC_ARENA_MAX`` is set), :data:`NATIVE_STACK` for threads made by
    C code (``pthread_setattr_default_np``, or a smaller ``ulimit -s``),
    :data:`PYTHON_STACK` for Python's (``threading.stack_size``),
    :data:`BLAS_THREADS` OpenBLAS thread (unless ``OPENBLAS_NUM_THREADS``
    is set). Call it once, before the first thread starts and before numpy
    is imported; ``environ``: the environment OpenBLAS will read. A C
    library without one of these calls keeps that default; it never raises.
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
