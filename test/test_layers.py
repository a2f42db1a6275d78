"""
The layers: their order, and the model, formats, cores and tool without ROS.

The package's folders are its layers, in this order: ``model`` (the
math), ``formats`` (files and messages), ``planning`` (paths and their
time-optimal motions), ``cores`` (the nodes' rules), ``ros`` (the glue),
``tools`` (the ``orthoglide`` tool). A module imports from its own layer
and those before it, never after: every ``import`` of every module, those
inside functions included, is read here. What the demos, benchmarks and
tests share, ``orthoglide_testing`` (``testing/``), sits above them all
and outside the package: no module of the package imports it.

A fresh interpreter whose import system refuses rclpy (and every ROS
message package) imports every module of ``model``, ``formats``,
``planning``, ``cores`` and ``tools``, and runs ``orthoglide solve``, ``batch``,
``urdf``, ``draw`` and ``identify`` on a CSV log: where ROS is not
installed they work the same. Only ``ros`` (and ``orthoglide_testing``)
may import rclpy.

No module of the package imports one that imports it back, through any
chain: every import counts, those under ``TYPE_CHECKING`` and inside
functions included.
"""

import ast
import os
import pkgutil
import subprocess
import sys

import pytest

import orthoglide_ros

HERE = os.path.dirname(os.path.abspath(__file__))
LAYERS = ('model', 'formats', 'planning', 'cores', 'ros', 'tools')
ROS_FREE = ('model', 'formats', 'planning', 'cores', 'tools')
# An import hook refusing rclpy and the message packages, then the code.
REFUSE_ROS = '''
import sys
class RefuseRos:
    def find_spec(self, name, path=None, target=None):
        top = name.split('.')[0]
        if top in ('rclpy', 'rosidl_runtime_py') or top.endswith('_msgs') \\
                or top.endswith('_srvs') or top == 'rcl_interfaces':
            raise ImportError(f'{name} refused: ROS must not be imported')
sys.meta_path.insert(0, RefuseRos())
'''


def run_without_ros(code, *args, cwd=None):
    return subprocess.run(
        [sys.executable, '-c', REFUSE_ROS + code, *args], cwd=cwd,
        capture_output=True, text=True, timeout=300)


def ros_free_modules():
    """Return the modules that must import without ROS (not the scripts)."""
    return [name for name, layer in modules_by_layer()
            if layer in ROS_FREE and not name.endswith('.__main__')]


def modules_by_layer():
    """Yield ``(module name, layer)`` of every module of the package."""
    root = os.path.dirname(orthoglide_ros.__file__)
    for module in pkgutil.walk_packages([root], 'orthoglide_ros.'):
        parts = module.name.split('.')
        if len(parts) > 2 or module.ispkg:
            yield module.name, parts[1]


def imported_names(name):
    """Return the absolute names a module imports, with the line of each."""
    spec = __import__('importlib.util').util.find_spec(name)
    with open(spec.origin) as f:
        tree = ast.parse(f.read())
    found = []
    for node in ast.walk(tree):
        names = [a.name for a in node.names] if isinstance(
            node, ast.Import) else [node.module or ''] if isinstance(
            node, ast.ImportFrom) and node.level == 0 else []
        found += [(imported, node.lineno) for imported in names]
    return found


def imported_layers(name):
    """Return the package's layers a module imports, with the line of each."""
    return [(imported.split('.')[1], line)
            for imported, line in imported_names(name)
            if imported.startswith('orthoglide_ros.')]


def test_the_layers_are_the_folders():
    root = os.path.dirname(orthoglide_ros.__file__)
    folders = sorted(entry for entry in os.listdir(root)
                     if os.path.isdir(os.path.join(root, entry))
                     and not entry.startswith('__'))
    assert folders == sorted(LAYERS)
    modules = [m.name for m in pkgutil.iter_modules([root]) if not m.ispkg]
    assert modules == [], f'modules outside a layer: {modules}'


def test_a_layer_imports_only_itself_and_those_before_it():
    wrong = []
    for name, layer in modules_by_layer():
        for imported, line in imported_layers(name):
            if LAYERS.index(imported) > LAYERS.index(layer):
                wrong.append(f'{name} (line {line}) imports {imported}')
    assert not wrong, wrong


def test_the_package_never_imports_its_proving_ground():
    """orthoglide_testing is not installed with the package: never needed."""
    wrong = [f'{name} (line {line}) imports {imported}'
             for name, _ in modules_by_layer()
             for imported, line in imported_names(name)
             if imported.split('.')[0] in ('orthoglide_testing', 'harness')]
    assert not wrong, wrong
    assert len(list(modules_by_layer())) > 50


def test_model_formats_cores_and_tools_import_without_rclpy():
    modules = ros_free_modules()
    assert len(modules) > 15
    result = run_without_ros(
        'import importlib\n'
        f'for name in {modules!r}:\n'
        '    importlib.import_module(name)\n'
        'assert "rclpy" not in sys.modules\n')
    assert result.returncode == 0, result.stderr


def test_the_hook_refuses_rclpy():
    """The test above can fail: the glue does not import here."""
    result = run_without_ros('import orthoglide_ros.ros.feedforward_node')
    assert result.returncode != 0 and 'refused' in result.stderr


@pytest.mark.slow     # 8.1 s of CPU (its interpreters), one process, 2026-12-06
def test_the_tool_works_without_rclpy(tmp_path):
    from cli_runs import identification_log
    source, _ = identification_log(tmp_path, duration=20.0)
    trajectory = tmp_path / 'in.csv'
    trajectory.write_text('t,x,y,z\n0,0,0,0\n0.1,0.01,0,0\n')
    for argv in (['solve', '--position', '0.05', '0.1', '-0.2'],
                 ['batch', '--input', str(trajectory)],
                 ['urdf', '--output', str(tmp_path / 'robot.urdf')],
                 ['draw', '--position', '0', '0', '0', '--output',
                  str(tmp_path / 'robot.png')],
                 ['identify', '--input', str(source), '--output',
                  str(tmp_path / 'robot.yaml')]):
        result = run_without_ros(
            'from orthoglide_ros.tools.cli import main\n'
            'code = main(sys.argv[1:])\n'
            'assert "rclpy" not in sys.modules\n'
            'sys.exit(code)\n', *argv, cwd=tmp_path)
        assert result.returncode == 0, (argv, result.stderr)
    assert (tmp_path / 'robot.yaml').exists()


def test_record_says_it_needs_ros_without_it(tmp_path):
    result = run_without_ros(
        'from orthoglide_ros.tools.cli import main\n'
        'sys.exit(main(sys.argv[1:]))\n', 'record', '--output',
        str(tmp_path / 'bag'), '--duration', '1')
    assert result.returncode == 2
    assert 'record needs ROS 2 (rclpy)' in result.stderr


def package_modules():
    """Return ``{module name: source path}`` of every module of the package."""
    root = os.path.dirname(orthoglide_ros.__file__)
    found = {'orthoglide_ros': os.path.join(root, '__init__.py')}
    for module in pkgutil.walk_packages([root], 'orthoglide_ros.'):
        found[module.name] = __import__('importlib.util').util.find_spec(
            module.name).origin
    return found


def imported_modules(name, path, known):
    """Return the modules of ``known`` that module ``name`` imports."""
    with open(path) as f:
        tree = ast.parse(f.read())
    package = name if path.endswith('__init__.py') else name.rpartition('.')[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                parts = package.split('.')
                parent = '.'.join(parts[:len(parts) - node.level + 1])
                base = f'{parent}.{base}' if base else parent
            for alias in node.names:
                full = f'{base}.{alias.name}'
                found.add(full if full in known else base)
    return {module for module in found if module in known and module != name}


def find_cycle(graph):
    """Return one cycle of ``graph`` (``{node: successors}``) as a list."""
    state = {}

    def visit(node, path):
        state[node] = 'open'
        for successor in sorted(graph.get(node, ())):
            if state.get(successor) == 'open':
                return path[path.index(successor):] + [successor]
            if successor not in state:
                cycle = visit(successor, path + [successor])
                if cycle:
                    return cycle
        state[node] = 'done'
        return None
    for start in sorted(graph):
        if start not in state:
            cycle = visit(start, [start])
            if cycle:
                return cycle
    return None


def test_find_cycle_finds_one():
    """The test below can fail: a cycle two imports long is found."""
    assert find_cycle({'a': {'b'}, 'b': {'c'}, 'c': {'a'}}) == \
        ['a', 'b', 'c', 'a']
    assert find_cycle({'a': {'b', 'c'}, 'b': {'c'}, 'c': set()}) is None


def test_no_module_imports_one_that_imports_it_back():
    modules = package_modules()
    graph = {name: imported_modules(name, path, modules)
             for name, path in modules.items()}
    assert graph['orthoglide_ros.model.robot'], 'the graph holds no import'
    cycle = find_cycle(graph)
    assert cycle is None, 'an import cycle: ' + ' -> '.join(cycle)


pytestmark = pytest.mark.filterwarnings('ignore::DeprecationWarning')
