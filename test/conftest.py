"""
Test-session set-up: DDS stays on this host, in a domain of its own.

Set before anything imports rclpy, so a bare ``pytest`` is as safe as the
README's test command:

- ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``: Fast DDS discovers only on the
  loopback interface (otherwise it multicasts out of the network card);
- ``ROS_DOMAIN_ID``: one per test session (drawn from the process id, and
  never the caller's own domain; ``ORTHOGLIDE_TEST_DOMAIN_ID`` overrides),
  so parallel runs and a live ROS graph on the same machine do not see each
  other;
- ``ROS_LOG_DIR``: a temporary directory, so tests leave no logs behind.

It names the checkout the proving ground runs from
(:func:`orthoglide_testing.use_checkout`, pytest's root directory).
"""

from contextlib import contextmanager
import os
import sys
import tempfile

import pytest

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
_CALLER_DOMAIN = os.environ.get('ROS_DOMAIN_ID', '0')
_DOMAIN = 1 + os.getpid() % 232
if str(_DOMAIN) == _CALLER_DOMAIN:
    _DOMAIN = _DOMAIN % 232 + 1
# An explicit choice wins (e.g. a range agreed on a shared machine).
_DOMAIN = int(os.environ.get('ORTHOGLIDE_TEST_DOMAIN_ID', _DOMAIN))
os.environ['ROS_DOMAIN_ID'] = str(_DOMAIN)
os.environ.setdefault('ROS_LOG_DIR', tempfile.mkdtemp(prefix='orthoglide-ros-log-'))


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


def pytest_configure(config):
    """
    Name the checkout to ``orthoglide_testing`` (its ``config/``, its cwd).

    ``scripts/setup_venv.sh`` installs it; where it is not installed
    (``colcon test``), it is taken from the checkout's ``testing/``, for
    the processes the tests start too.
    """
    try:
        import orthoglide_testing
    except ImportError:
        testing = str(config.rootpath / 'testing')
        sys.path.insert(0, testing)
        os.environ['PYTHONPATH'] = os.pathsep.join(
            [testing] + [p for p in [os.environ.get('PYTHONPATH')] if p])
        import orthoglide_testing
    orthoglide_testing.use_checkout(config.rootpath)


def pytest_collection_modifyitems(config, items):
    """
    Skip the tests marked ``soak`` unless asked for.

    They are the long versions (10 s floods, 5 restarts): ``pytest -m soak``
    or ``ORTHOGLIDE_SOAK=1`` runs them; the default run has a short version
    of each.
    """
    if os.environ.get('ORTHOGLIDE_SOAK') == '1' \
            or 'soak' in (config.getoption('markexpr') or ''):
        return
    skip = pytest.mark.skip(
        reason='soak test: select it with -m soak or ORTHOGLIDE_SOAK=1')
    for item in items:
        if 'soak' in item.keywords:
            item.add_marker(skip)
