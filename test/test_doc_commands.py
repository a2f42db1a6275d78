"""
Every command of README.md and doc/ runs as written, where no robot is needed.

The shell blocks of the documents are read line by line (comments and
continuations joined):

- the ``orthoglide`` tool's commands that need no robot and no DDS (paper,
  solve, batch, plan, excitation, urdf, mjcf, draw, animate) run, in the order of
  their document, in a scratch folder that holds the clone's ``.venv`` and
  ``config``: exit 0, no error line; identify and validate of a log that
  only a robot gives (a bag ``record`` writes) are left out;
- the nodes' commands (``.venv/bin/NODE ...``, ``ros2 run orthoglide_ros
  NODE ...``) are checked against the node's parameter table: every
  ``-p``/``-r``/``--params-file`` after ``--ros-args`` (rcl takes one
  before it for a remapping), every parameter one the node declares, its
  value one the node takes, every file given one the clone has.
"""

from pathlib import Path
import re
import shlex
import subprocess

import pytest
import yaml

from orthoglide_ros.cores import (feedforward, mechanism_state_publisher,
                                  planner, setpoint_publisher, simulator,
                                  tracking_controller)

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / 'README.md', *sorted((ROOT / 'doc').glob('*.md'))]
TABLES = {'feedforward': feedforward.PARAMETERS,
          'simulator': simulator.PARAMETERS,
          'tracking_controller': tracking_controller.PARAMETERS,
          'setpoint_publisher': setpoint_publisher.PARAMETERS,
          'mechanism_state_publisher': mechanism_state_publisher.PARAMETERS,
          'planner': planner.PARAMETERS}
# The lifecycle's, declared by every node (orthoglide_ros.ros.managed_node).
COMMON = {'autostart'}
TOOL = '.venv/bin/orthoglide '
# The tool's subcommands that need no robot and no DDS; identify and
# validate also need their log, run where an earlier command wrote it.
OFFLINE = {'paper', 'solve', 'batch', 'plan', 'excitation', 'urdf', 'mjcf',
           'draw', 'animate', 'identify', 'validate'}
LOGS = {'identify', 'validate'}
NODE = re.compile(r'^(?:\.venv/bin/|ros2 run orthoglide_ros )(\w+)(.*)$')


def commands(path):
    """Return the shell lines of ``path``'s bash blocks, comments off."""
    lines = []
    for block in re.findall(r'```bash\n(.*?)```', path.read_text(), re.S):
        text = block.replace('\\\n', ' ')
        for line in text.splitlines():
            line = re.sub(r'\s+#.*$', '', line).strip()
            if line and not line.startswith('#'):
                lines.append(line)
    return lines


def tool_commands():
    """Yield (document, [its offline tool lines]) for documents with any."""
    for path in DOCUMENTS:
        lines = [line for line in commands(path)
                 if line == 'mkdir -p out' or (
                     line.startswith(TOOL)
                     and line[len(TOOL):].split()[0] in OFFLINE)]
        if any(line.startswith(TOOL) for line in lines):
            yield pytest.param(path, lines, id=path.name)


def node_commands():
    """Yield (document, line, node, arguments, files its commands write)."""
    for path in DOCUMENTS:
        lines = commands(path)
        written = {word for line in lines for word in re.findall(
            r'--output (\S+)', line)}
        for line in lines:
            match = NODE.match(line)
            if match and match.group(1) in TABLES:
                yield pytest.param(path, line, match.group(1),
                                   shlex.split(match.group(2)), written,
                                   id=f'{path.name}: {line[:60]}')


@pytest.mark.parametrize('path, lines', list(tool_commands()))
def test_tool_commands_run_as_written(tmp_path, path, lines):
    """In the document's order: what one writes, the next may read."""
    (tmp_path / '.venv').symlink_to(ROOT / '.venv')
    (tmp_path / 'config').symlink_to(ROOT / 'config')
    for folder in ('urdf', 'mjcf', 'doc'):     # the committed pictures' own
        (tmp_path / folder).mkdir()
    (tmp_path / 'doc' / 'programs').symlink_to(ROOT / 'doc' / 'programs')
    recorded = {word for line in commands(path) for word in re.findall(
        r'record --output (\S+)', line)}
    for line in lines:
        words = line.split()
        if words[1] in LOGS:
            log = words[words.index('--input') + 1]
            if not (tmp_path / log).exists():
                assert log in recorded, f'{line}: nothing writes {log}'
                continue
        result = subprocess.run(line, shell=True, cwd=tmp_path, text=True,
                                capture_output=True, timeout=120)
        assert result.returncode == 0, (path.name, line, result.stderr)
        assert 'error' not in result.stderr, (path.name, line, result.stderr)


@pytest.mark.parametrize('path, line, node, arguments, written',
                         list(node_commands()))
def test_node_commands_take_their_arguments(path, line, node, arguments,
                                            written):
    """A file given is the clone's, or one the document's commands write."""
    table = TABLES[node]
    names = {spec.name for spec in table.specs} | COMMON
    ros = False
    k = 0
    while k < len(arguments):
        word = arguments[k]
        if word == '--ros-args':
            ros = True
        elif word in ('-p', '-r', '--params-file'):
            assert ros, f'{line}: {word} before --ros-args'
            value = arguments[k + 1]
            k += 1
            if word == '--params-file' and '$(' not in value:
                assert (ROOT / value).is_file() or value in written, \
                    f'{line}: no file {value}'
            elif word == '-p':
                name, text = value.split(':=', 1)
                if not name.startswith('qos_overrides.'):
                    assert name in names, f'{line}: {node} has no {name}'
                    table.parse({name: yaml.safe_load(text)})
        k += 1
