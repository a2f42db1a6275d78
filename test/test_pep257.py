"""ament_pep257 over the package, its tests, scripts and benchmarks."""

import pytest

ament_pep257 = pytest.importorskip('ament_pep257.main')


@pytest.mark.linter
@pytest.mark.pep257
@pytest.mark.slow     # 5.5-6.5 s of CPU, one process, 2026-12-06
def test_pep257():
    """Docstrings follow ROS 2's pep257 rules."""
    rc = ament_pep257.main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'
