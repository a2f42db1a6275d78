"""
Every command of README.md and doc/ runs as written, where no robot is needed.

The shell blocks of the documents are read line by line (comments and
continuations joined):

- each of the ``orthoglide`` tool's commands that need no robot and no DDS
  (paper, solve, batch, plan, excitation, urdf, mjcf, draw, animate,
  identify, validate, calibration-poses, calibrate) is a test of its own,
  named by its document and line. It runs in the test's process
  (``cli.main``; ``test_cli.py`` runs the console script) in a scratch
  folder with the clone's ``config`` and ``doc/programs``, after the
  earlier commands of its document that write what it reads (the last
  writer of each file, each run once per test process): exit 0, no error
  line. identify and validate of a log that only a robot gives (a bag
  ``record`` writes) are skipped, once the document is seen to record it;
- the nodes' commands (``.venv/bin/NODE ...``, ``ros2 run orthoglide_ros
  NODE ...``) are checked against the node's parameter table: every
  ``-p``/``-r``/``--params-file`` after ``--ros-args`` (rcl takes one
  before it for a remapping), every parameter one the node declares, its
  value one the node takes, every file given one the clone has.
"""

from collections import namedtuple
import contextlib
from pathlib import Path
import re
import shlex
import shutil
import tempfile

import pytest
import yaml

from orthoglide_ros.cores import (feedforward, mechanism_state_publisher,
                                  planner, setpoint_publisher, simulator,
                                  tracking_controller)
from orthoglide_ros.tools import cli
from orthoglide_ros.tools.cli.common import INPUT_OPTIONS, OUTPUT_OPTIONS

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
           'draw', 'animate', 'identify', 'validate', 'calibration-poses',
           'calibrate'}
LOGS = {'identify', 'validate'}
NODE = re.compile(r'^(?:\.venv/bin/|ros2 run orthoglide_ros )(\w+)(.*)$')


def numbered_commands(path):
    """Return (line number, line) of ``path``'s bash blocks, comments off."""
    text = path.read_text()
    lines = []
    for block in re.finditer(r'```bash\n(.*?)```', text, re.S):
        number = text.count('\n', 0, block.start(1)) + 1
        for joined in re.split(r'(?<!\\)\n', block.group(1)):
            line = re.sub(r'\s+#.*$', '', joined.replace('\\\n', ' ')).strip()
            if line and not line.startswith('#'):
                lines.append((number, line))
            number += joined.count('\n') + 1
    return lines


def commands(path):
    """Return the shell lines of ``path``'s bash blocks, comments off."""
    return [line for _, line in numbered_commands(path)]


Step = namedtuple('Step', 'document number line writes sources')
Step.__doc__ = """An offline tool command (or a ``mkdir -p``) of a document.

``number``: its line in the document; ``writes``: the files its output
options name (the folder, for mkdir); ``sources``: (file, step) for each
file it reads or writes into whose last writer is an earlier step.
"""


def _files(words, options):
    """Return the values of the words ``--option`` of ``options``."""
    flags = {'--' + name.replace('_', '-') for name in options}
    return [words[k + 1] for k, word in enumerate(words[:-1])
            if word in flags]


def tool_steps(path):
    """Return the offline tool steps of ``path``, in order."""
    steps = []
    for number, line in numbered_commands(path):
        if not line.startswith((TOOL, 'mkdir -p ')):
            continue
        words = shlex.split(line)
        if words[0] == 'mkdir' and len(words) == 3:
            reads, writes = [], [words[2]]
        elif line.startswith(TOOL) and words[1] in OFFLINE:
            reads = _files(words, INPUT_OPTIONS)
            writes = _files(words, OUTPUT_OPTIONS)
        else:
            continue
        needed = reads + [str(Path(file).parent) for file in writes]
        sources = tuple((file, writer) for file in dict.fromkeys(needed)
                        for writer in [_last_writer(steps, file)] if writer)
        steps.append(Step(path, number, line, tuple(writes), sources))
    return steps


def _last_writer(steps, file):
    return next((step for step in reversed(steps) if file in step.writes),
                None)


def tool_commands():
    """Yield every document's tool steps (its mkdir lines are sources)."""
    for path in DOCUMENTS:
        for step in tool_steps(path):
            if step.line.startswith(TOOL):
                words = step.line.split()
                # 1.5 s of CPU or more, one process, 2026-12-06: a GIF
                # (animate 5.0 s), an optimisation (excitation 5.4 s).
                slow = words[1] == 'animate' or '--optimize' in words
                yield pytest.param(
                    step, id=f'{path.name}:{step.number} {words[1]}',
                    marks=[pytest.mark.slow] if slow else [])


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


class Scratch:
    """Steps run in folders of their own, each once per test process."""

    def __init__(self, base):
        self.base = base
        self.folders = {}

    def run(self, step, capfd):
        """Run ``step`` after the steps it needs; return its folder."""
        if step in self.folders:
            return self.folders[step]
        folder = Path(tempfile.mkdtemp(
            prefix=f'{step.document.stem}-{step.number}-', dir=self.base))
        (folder / 'config').symlink_to(ROOT / 'config')
        for name in ('urdf', 'mjcf', 'doc'):     # the committed pictures' own
            (folder / name).mkdir()
        (folder / 'doc' / 'programs').symlink_to(ROOT / 'doc' / 'programs')
        for file, writer in step.sources:
            if writer.line.startswith(TOOL):
                source = self.run(writer, capfd) / file
                (folder / file).parent.mkdir(parents=True, exist_ok=True)
                copy = shutil.copytree if source.is_dir() else shutil.copy
                copy(source, folder / file)
            else:
                (folder / file).mkdir(parents=True, exist_ok=True)
        words = shlex.split(step.line)
        if words[0] == 'mkdir':
            (folder / words[2]).mkdir(parents=True, exist_ok=True)
        else:
            self._skip_a_recorded_log(step, folder, words)
            with contextlib.chdir(folder):
                code = cli.main(words[1:])
            _, err = capfd.readouterr()
            where = f'{step.document.name}:{step.number}: {step.line}'
            assert code == 0, (where, err)
            assert 'error' not in err, (where, err)
        self.folders[step] = folder
        return folder

    @staticmethod
    def _skip_a_recorded_log(step, folder, words):
        if words[1] not in LOGS:
            return
        log = words[words.index('--input') + 1]
        if not (folder / log).exists():
            recorded = {word for line in commands(step.document)
                        for word in re.findall(r'record --output (\S+)',
                                               line)}
            assert log in recorded, f'{step.line}: nothing writes {log}'
            pytest.skip(f'{log}: a bag that record writes from the robot')


@pytest.fixture(scope='module')
def scratch(tmp_path_factory):
    """Give the module's tests one :class:`Scratch`."""
    return Scratch(tmp_path_factory.mktemp('documents'))


@pytest.mark.parametrize('step', list(tool_commands()))
def test_tool_commands_run_as_written(scratch, capfd, step):
    """After the earlier commands that write what it reads: exit 0."""
    scratch.run(step, capfd)


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
