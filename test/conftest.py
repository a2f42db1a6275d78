"""
Test-session set-up: DDS stays on this host, in a domain of its own.

Set before anything imports rclpy, so a bare ``pytest`` is as safe as the
README's test command:

- ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``: Fast DDS discovers only on the
  loopback interface (otherwise it multicasts out of the network card);
- ``ROS_DOMAIN_ID``: one per test process (each pytest-xdist worker too),
  held with a lock file so that no other session of this suite on the host
  takes it, and never the caller's own domain (see :func:`_claim_domain`;
  ``ORTHOGLIDE_TEST_DOMAIN_ID`` overrides);
- ``ROS_LOG_DIR``: a temporary directory, so tests leave no logs behind;
- the hypothesis profile (:mod:`hypothesis_profiles`): ``default``, or
  ``thorough`` in the soak run;
- scripts/test.sh's phases (PHASE): the tests marked ``serial`` apart.

The marks ``slow`` and ``serial`` are on the tests themselves, each with
its reason (measured, or the kind of verdict) in a comment by it
(setup.cfg lists the markers).

It names the checkout the proving ground runs from
(:func:`orthoglide_testing.use_checkout`, pytest's root directory).
"""

from contextlib import contextmanager
import fcntl
import os
from pathlib import Path
import re
import sys
import tempfile

from hypothesis import settings
import hypothesis_profiles  # noqa: F401 (registers the profiles)
import pytest

# The domains a session may take: odd ones, so that a test's neighbour
# domain (test_isolation.py: domain + 1) and the network namespaces' domain
# (orthoglide_testing.live_graph.namespace_domain: domain + 117, modulo)
# are even and never another session's.
SESSION_DOMAINS = range(1, 232, 2)
DOMAIN_LOCKS = Path(tempfile.gettempdir()) / 'orthoglide-test-domains'


def _claim_domain():
    """
    Return this process's ROS domain, and the lock that holds it.

    ``ORTHOGLIDE_TEST_DOMAIN_ID`` (the N-th xdist worker: that plus 2 N)
    wins. Otherwise the first of SESSION_DOMAINS, from one drawn from the
    process id on, whose lock file no other process holds (an exclusive
    ``flock``, released when the process ends), other than the domain of
    the caller (``ROS_DOMAIN_ID`` as the session found it).
    """
    worker = os.environ.get('PYTEST_XDIST_WORKER', 'gw0')   # gw0, gw1, ...
    explicit = os.environ.get('ORTHOGLIDE_TEST_DOMAIN_ID')
    if explicit:
        return int(explicit) + 2 * int(worker[2:]), None
    # The xdist controller runs first: its workers see the caller's domain.
    caller = os.environ.setdefault('ORTHOGLIDE_CALLER_DOMAIN_ID',
                                   os.environ.get('ROS_DOMAIN_ID', '0'))
    start = os.getpid() % len(SESSION_DOMAINS)
    DOMAIN_LOCKS.mkdir(exist_ok=True)
    for k in range(len(SESSION_DOMAINS)):
        domain = SESSION_DOMAINS[(start + k) % len(SESSION_DOMAINS)]
        if str(domain) == caller:
            continue
        lock = open(DOMAIN_LOCKS / f'{domain}.lock', 'a')
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        return domain, lock
    raise RuntimeError(f'every test domain is taken ({DOMAIN_LOCKS})')


os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
_DOMAIN, _DOMAIN_LOCK = _claim_domain()
os.environ['ROS_DOMAIN_ID'] = str(_DOMAIN)
os.environ.setdefault('ROS_LOG_DIR', tempfile.mkdtemp(prefix='orthoglide-ros-log-'))


def _soak(config):
    """Whether this is the soak run: ``-m soak`` or ``ORTHOGLIDE_SOAK=1``."""
    return os.environ.get('ORTHOGLIDE_SOAK') == '1' or bool(re.search(
        r'(?<!not )\bsoak\b', config.getoption('markexpr') or ''))


@contextmanager
def _fresh_context():
    rclpy = pytest.importorskip('rclpy')
    context = rclpy.context.Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)


@pytest.fixture
def ros_context():
    """Give one test a fresh rclpy context, shut down afterwards."""
    with _fresh_context() as context:
        yield context


@pytest.fixture(scope='session', params=['paper', 'other'])
def robot(request):
    """
    Give a test of the model each robot in turn: the paper's, then another.

    The other (``mechanics_reference.OTHER_ROBOT_VALUES``) differs in every
    length and angle and in m4, m6. Session-scoped, so that hypothesis
    draws its examples for each (a Robot is immutable).
    """
    from mechanics_reference import OTHER_ROBOT_VALUES
    from orthoglide_ros.model.robot import Robot
    return Robot(**(OTHER_ROBOT_VALUES if request.param == 'other' else {}))


@pytest.fixture(scope='module')
def closed_loop():
    """
    Start the closed loop's nodes once for a module; stop them after.

    :class:`orthoglide_testing.closed_loop.ClosedLoop` in a context of its
    own; every node must have exited 0.
    """
    harness = pytest.importorskip('orthoglide_testing.closed_loop')
    with harness.demo_loop() as running:
        yield running


@pytest.hookimpl(trylast=True)
def pytest_configure(config):
    """
    Name the checkout to ``orthoglide_testing`` (its ``config/``, its cwd).

    ``scripts/setup_venv.sh`` installs it; where it is not installed
    (``colcon test``), it is taken from the checkout's ``testing/``, for
    the processes the tests start too. Load the ``thorough`` hypothesis
    profile for the soak run, unless one is named (after hypothesis' own
    hook: trylast).
    """
    if _soak(config) and not config.getoption('hypothesis_profile'):
        settings.load_profile('thorough')
    if PHASE in ('parallel', 'serial'):
        config.pluginmanager.register(_Phase(), 'orthoglide-test-phase')
    try:
        import orthoglide_testing
    except ImportError:
        testing = str(config.rootpath / 'testing')
        sys.path.insert(0, testing)
        os.environ['PYTHONPATH'] = os.pathsep.join(
            [testing] + [p for p in [os.environ.get('PYTHONPATH')] if p])
        import orthoglide_testing
    orthoglide_testing.use_checkout(config.rootpath)


# scripts/test.sh's two phases: 'parallel' leaves the ``serial`` tests out,
# 'serial' runs only them; their count goes to ORTHOGLIDE_SERIAL_COUNT.
PHASE = os.environ.get('ORTHOGLIDE_TEST_PHASE')


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """
    Skip ``soak`` unless asked.

    The soak tests are the long versions (10 s floods, 5 restarts):
    ``pytest -m soak`` or ``ORTHOGLIDE_SOAK=1`` runs them; the default run
    has a short version of each.
    """
    if _soak(config):
        return
    skip = pytest.mark.skip(
        reason='soak test: select it with -m soak or ORTHOGLIDE_SOAK=1')
    for item in items:
        if 'soak' in item.keywords:
            item.add_marker(skip)


class _Phase:
    """scripts/test.sh's phase: its tests of the selection, after -m and -k."""

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, config, items):
        """Keep PHASE's tests; write how many of them are ``serial``."""
        serial = [item for item in items if item.get_closest_marker('serial')]
        if os.environ.get('ORTHOGLIDE_SERIAL_COUNT'):
            Path(os.environ['ORTHOGLIDE_SERIAL_COUNT']).write_text(
                str(len(serial)))
        kept = serial if PHASE == 'serial' else [
            item for item in items if not item.get_closest_marker('serial')]
        config.hook.pytest_deselected(items=[
            item for item in items if item not in kept])
        items[:] = kept
