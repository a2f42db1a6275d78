"""ament_flake8 over the package, its tests, scripts and benchmarks."""

from pathlib import Path

import pytest

ament_flake8 = pytest.importorskip('ament_flake8.main')


@pytest.mark.flake8
@pytest.mark.linter
@pytest.mark.slow     # 9.4-12.4 s of CPU, one process, 2026-12-06
def test_flake8(tmp_path):
    """
    The code follows ROS 2's flake8 rules.

    ament_flake8's own configuration plus ``jobs = 1``: flake8's default
    process pool forks this process, whose DDS threads (of the tests that
    ran before) can leave a forked worker deadlocked.
    """
    config = tmp_path / 'flake8.ini'
    config.write_text((Path(ament_flake8.__file__).parent / 'configuration'
                       / 'ament_flake8.ini').read_text() + 'jobs = 1\n')
    rc, errors = ament_flake8.main_with_errors(argv=['--config', str(config)])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' \
        + '\n'.join(errors)
