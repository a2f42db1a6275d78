"""
Network namespaces for the tests whose DDS settings reach beyond LOCALHOST.

A process whose discovery range is not LOCALHOST (the one-host profile runs
with SYSTEM_DEFAULT, the several-host settings with SUBNET or a discovery
server) runs only inside a namespace made here: :class:`Namespace` has
nothing but its own loopback, :func:`pair` two namespaces joined by a veth
pair whose addresses are the test's. Every namespace is deleted on exit,
also on failure; a process in it is started by :meth:`Namespace.command`.

:func:`unavailable` says why namespaces cannot be made (not root, no
``ip``, a kernel or container that refuses): the tests then skip with it.

"""

from contextlib import contextmanager
import functools
import itertools
import os
import shutil
import subprocess

_COUNT = itertools.count()
# The veth pair's subnet: link-local-like test addresses, never routed.
PAIR_ADDRESSES = ('10.231.0.1', '10.231.0.2')
PAIR_PREFIX = 24


def _ip(*args, check=True):
    return subprocess.run(['ip', *args], capture_output=True, text=True,
                          timeout=20, check=check)


@functools.lru_cache(maxsize=None)
def unavailable():
    """Return why a namespace cannot be made here, '' if it can."""
    if shutil.which('ip') is None:
        return 'no `ip` command (iproute2)'
    if os.geteuid() != 0:
        return 'network namespaces need root'
    try:
        with Namespace():
            pass
    except (OSError, subprocess.SubprocessError) as error:
        return f'cannot make a network namespace: {error}'
    return ''


def _name():
    return f'og{os.getpid()}n{next(_COUNT)}'


class Namespace:
    """
    A network namespace with only its loopback, up; deleted on exit.

    ``multicast``: loopback multicast on, with a 224.0.0.0/4 route on it,
    for multicast discovery inside.
    """

    def __init__(self, multicast=False):
        self.name = _name()
        self.multicast = multicast

    def __enter__(self):
        """Make the namespace and bring its loopback up."""
        _ip('netns', 'add', self.name)
        try:
            self.run_ip('link', 'set', 'lo', 'up')
            if self.multicast:
                self.run_ip('link', 'set', 'lo', 'multicast', 'on')
                self.run_ip('route', 'add', '224.0.0.0/4', 'dev', 'lo')
        except BaseException:
            self.delete()
            raise
        return self

    def __exit__(self, *exc):
        """Delete the namespace."""
        self.delete()
        return False

    def delete(self):
        """Delete the namespace (its processes should be stopped first)."""
        _ip('netns', 'del', self.name, check=False)

    def run_ip(self, *args):
        """Run ``ip ARGS`` inside the namespace; raise if it fails."""
        _ip('netns', 'exec', self.name, 'ip', *args)

    def command(self, argv):
        """Return ``argv`` run inside the namespace."""
        return [*exec_prefix(self.name), *argv]

    def interfaces(self):
        """Return the namespace's interface names."""
        out = _ip('netns', 'exec', self.name, 'ip', '-o', 'link').stdout
        return [line.split(':')[1].strip().split('@')[0]
                for line in out.splitlines()]


def exec_prefix(name):
    """Return the command prefix that runs a command in namespace ``name``."""
    return ['ip', 'netns', 'exec', name]


def link_bytes():
    """Return the bytes this namespace's interfaces but loopback moved."""
    total = 0
    for name in os.listdir('/sys/class/net'):
        if name == 'lo':
            continue
        for way in ('rx_bytes', 'tx_bytes'):
            with open(f'/sys/class/net/{name}/statistics/{way}') as f:
                total += int(f.read())
    return total


@contextmanager
def pair():
    """
    Yield two namespaces joined by a veth pair: two hosts on one link.

    Each has its loopback and one end of the pair, with PAIR_ADDRESSES
    (/PAIR_PREFIX) and multicast on; both are deleted on exit (the pair
    with them).
    """
    with Namespace() as a, Namespace() as b:
        ends = (f'{a.name}v', f'{b.name}v')
        _ip('link', 'add', ends[0], 'netns', a.name, 'type', 'veth',
            'peer', 'name', ends[1], 'netns', b.name)
        for ns, end, address in zip((a, b), ends, PAIR_ADDRESSES):
            ns.run_ip('addr', 'add', f'{address}/{PAIR_PREFIX}', 'dev', end)
            ns.run_ip('link', 'set', end, 'multicast', 'on')
            ns.run_ip('link', 'set', end, 'up')
            ns.run_ip('route', 'add', '224.0.0.0/4', 'dev', end)
        yield a, b
