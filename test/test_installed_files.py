"""
What ``pip install .`` installs: the product, and nothing of its proving ground.

The wheel of a copy of the checkout (its tracked files and new ones, so the
source tree gets no ``build/``) holds every module of ``orthoglide_ros/``
and only those, the data files ``setup.py`` names, and no test support:
``orthoglide_testing`` (``testing/``), ``test/``, ``scripts/`` and
``benchmarks/`` stay in the checkout. The colcon install tree is checked
the same way in ``test_colcon_build.py``.
"""

from pathlib import Path
import shutil
import subprocess
import sys
import zipfile

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = {'share/ament_index/resource_index/packages/orthoglide_ros',
        'share/orthoglide_ros/package.xml',
        'share/orthoglide_ros/config/orthoglide.yaml',
        'share/orthoglide_ros/config/fastdds_one_host.xml',
        'share/orthoglide_ros/config/orthoglide.rviz',
        'share/orthoglide_ros/urdf/orthoglide.urdf',
        'share/orthoglide_ros/mjcf/orthoglide.xml'}
# Names no installed path may hold: the test support, old and new.
TEST_SUPPORT = ('orthoglide_testing', 'harness', 'test/', 'tests/',
                'scripts/', 'benchmarks/', 'conftest')


def checkout_files():
    """Return the checkout's files as git sees them (tracked and new)."""
    if shutil.which('git') is None or not (ROOT / '.git').exists():
        pytest.skip('not a git checkout')
    listed = subprocess.run(
        ['git', 'ls-files', '--cached', '--others', '--exclude-standard',
         '-z'], cwd=ROOT, capture_output=True, check=True, timeout=60)
    return [name for name in listed.stdout.decode().split('\0')
            if name and (ROOT / name).is_file()]


@pytest.fixture(scope='module')
def wheel(tmp_path_factory):
    """Build the wheel of a copy; return its names, top level, the copy."""
    tmp = tmp_path_factory.mktemp('wheel')
    source = tmp / 'source'
    for name in checkout_files():
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, source / name)
    built = subprocess.run(
        [sys.executable, '-m', 'pip', 'wheel', '--no-deps',
         '--no-build-isolation', '-q', '-w', str(tmp / 'wheel'),
         str(source)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stdout + built.stderr
    [path] = (tmp / 'wheel').glob('orthoglide_ros-*.whl')
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
        top = next(n for n in names if n.endswith('dist-info/top_level.txt'))
        return names, archive.read(top).decode().split(), source


def test_the_wheel_holds_every_module_of_the_package_and_no_other(wheel):
    names, _, source = wheel
    modules = {n for n in names if n.endswith('.py')}
    product = {str(p.relative_to(source))
               for p in (source / 'orthoglide_ros').rglob('*.py')}
    assert modules == product, (modules ^ product)
    assert len(product) > 50


def test_the_wheel_holds_no_test_support(wheel):
    names, top_level, _ = wheel
    support = [n for n in names if any(s in n for s in TEST_SUPPORT)]
    assert support == []
    assert top_level == ['orthoglide_ros']


def test_the_wheel_installs_the_data_files_setup_names(wheel):
    names, _, _ = wheel
    data = {n.split('.data/data/', 1)[1] for n in names if '.data/data/' in n}
    assert data == DATA
