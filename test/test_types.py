"""
The public API of model/, formats/, planning/ and two tools is typed.

The tools: identification and calibration. Every public function and
method there has annotations on its parameters
and its return (checked from the source), and mypy, with the project's
configuration (setup.cfg), finds them consistent with the code and its
callers within those packages.
"""

import ast
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
TYPED = ('orthoglide_ros/model', 'orthoglide_ros/formats',
         'orthoglide_ros/planning',
         'orthoglide_ros/tools/identification',
         'orthoglide_ros/tools/calibration')


def public_functions():
    """Yield (file, name, node) of every public function and method."""
    for folder in TYPED:
        for path in sorted((ROOT / folder).glob('*.py')):
            tree = ast.parse(path.read_text())
            for top in tree.body:
                if isinstance(top, ast.ClassDef) and top.name.startswith('_'):
                    continue
                inner = top.body if isinstance(top, ast.ClassDef) else [top]
                for node in inner:
                    if isinstance(node, ast.FunctionDef) and (
                            not node.name.startswith('_')
                            or node.name == '__init__'):
                        yield path.relative_to(ROOT), node.name, node


def test_every_public_function_is_annotated():
    """Parameters (but self) and returns of public classes and functions."""
    missing = []
    for path, name, node in public_functions():
        args = node.args
        params = [a for a in args.posonlyargs + args.args + args.kwonlyargs
                  if a.arg not in ('self', 'cls')]
        params += [a for a in (args.vararg, args.kwarg) if a is not None]
        if node.returns is None or any(a.annotation is None for a in params):
            missing.append(f'{path}:{node.lineno} {name}')
    assert len(list(public_functions())) > 100
    assert not missing, 'not annotated:\n' + '\n'.join(missing)


def test_mypy_finds_the_annotations_consistent():
    """No error in the typed packages."""
    mypy = pytest.importorskip('mypy.api')
    out, err, code = mypy.run(['--config-file', str(ROOT / 'setup.cfg'),
                               *(str(ROOT / f) for f in TYPED)])
    assert code == 0, out + err


def test_a_wrong_call_is_caught(tmp_path):
    """The check can fail: a caller passing a string for a robot."""
    pytest.importorskip('mypy.api')
    bad = tmp_path / 'bad_caller.py'
    bad.write_text('from orthoglide_ros.model import mechanics\n'
                   "mechanics.solve('robot', (0.0, 0.0, 0.0))\n")
    result = subprocess.run(
        [sys.executable, '-m', 'mypy', '--config-file',
         str(ROOT / 'setup.cfg'), str(bad)],
        capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 1, result.stdout
    assert 'arg-type' in result.stdout, result.stdout
