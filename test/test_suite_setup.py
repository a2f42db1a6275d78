"""
The suite's own set-up (``test/conftest.py``).

Each test process holds a ROS domain of its own: one of the session
domains (odd, so that the neighbour and namespace domains the tests use
are never another session's), its lock file held while the process lives;
processes started side by side, as pytest-xdist starts its workers, take
different domains.
"""

import fcntl
import os
from pathlib import Path
import subprocess
import sys

from conftest import DOMAIN_LOCKS, SESSION_DOMAINS
import pytest

HERE = Path(__file__).resolve().parent
# A process that claims its domain as a worker does, prints it and holds it
# until its standard input closes.
CLAIM = ('import os, sys; sys.path.insert(0, sys.argv[1]); import conftest; '
         'print(os.environ["ROS_DOMAIN_ID"], flush=True); sys.stdin.read()')


EXPLICIT = pytest.mark.skipif(
    bool(os.environ.get('ORTHOGLIDE_TEST_DOMAIN_ID')),
    reason='ORTHOGLIDE_TEST_DOMAIN_ID chose the domain')


@EXPLICIT
def test_the_domain_is_a_session_domain_and_held():
    domain = int(os.environ['ROS_DOMAIN_ID'])
    assert domain in SESSION_DOMAINS
    assert str(domain) != os.environ['ORTHOGLIDE_CALLER_DOMAIN_ID']
    with open(DOMAIN_LOCKS / f'{domain}.lock', 'a') as other:
        with pytest.raises(BlockingIOError):
            fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)


@EXPLICIT
def test_processes_side_by_side_take_different_domains():
    environment = {k: v for k, v in os.environ.items()
                   if k != 'ORTHOGLIDE_TEST_DOMAIN_ID'}
    started = []
    try:
        for _ in range(3):
            started.append(subprocess.Popen(
                [sys.executable, '-c', CLAIM, str(HERE)], env=environment,
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True))
        domains = [int(p.stdout.readline()) for p in started]
    finally:
        for process in started:
            process.communicate(timeout=30)
    assert all(p.returncode == 0 for p in started)
    mine = int(os.environ['ROS_DOMAIN_ID'])
    assert len(set(domains + [mine])) == 4, (domains, mine)
    assert all(d in SESSION_DOMAINS for d in domains)
