"""
The documentation agrees with the code: parameter tables, links, size.

Pure: no DDS, no rclpy (the cores' modules never import it).

**Parameters.** For each node page, every row of the node's
``PARAMETERS`` table (``spec.name`` for ``spec`` in ``PARAMETERS.specs``)
must have a row in a Markdown table of that page (the ``robot.*`` rows:
of doc/model.md's, which the page links to) whose first cell holds the
name in backticks (`` `rate_hz` ``) and whose ``default`` column holds
the default as a ROS 2 parameters file writes it, in backticks:

- a float as Python's ``repr`` (`` `0.1` ``, `` `1000.0` ``,
  `` `0.7853981633974483` ``);
- an integer as ``str`` (`` `1` ``); a bool in lower case (`` `true` ``,
  `` `false` ``); a string bare (`` `base_link` ``);
- a list in flow style with the same rules for its items
  (`` `[0.0, 0.0, -9.81]` ``, `` `[slider_a, slider_b, slider_c]` ``).

A row declared without a default (``spec.default is None``: ``robot.m4``,
``robot.m6``) follows another parameter, named in its description in the
code ("defaults to m2"): its default cell must name that parameter in
backticks with its prefix (`` `robot.m2` ``). A row whose description names
no such parameter must say ``none`` in its default cell.

**Model tables.** doc/model.md's tables of the ``robot.*`` parameters
and of the terms are what ``test/model_tables.py`` writes from the code
(``.venv/bin/python test/model_tables.py --write`` after a change).

**Links.** Every relative link and image of README.md and doc/*.md
(outside code) points to an existing file; a ``#fragment`` must match a
heading of the target page (GitHub's anchors).

**Named paths.** Every file or folder a page, a docstring or a comment
names by its path from the repository's root (`` `test/test_docs.py` ``,
``doc/model.md#bodies``, ``config/``, in any top-level folder of the
repository that git does not ignore), every bare ``<name>.py``, every
dotted module name of the package (and the name that follows it in that
module) and every ``test_*`` name exists; an anchor after a page
matches one of its headings.

**No project history.** No page, docstring or comment names an issue of
this project by its number or as the source of a rule: the documents are
references,
and git keeps how they came. An upstream issue is named with its project
(`` Fast-DDS issue 6535 ``, `` issue #1615 ``).

**Layout.** README.md's Layout table is the tree's: each row names its
folders in its first cell; every ``<name>.py`` (or ``<pattern>.py``, a
``<placeholder>`` standing for any name) and ``<name>/`` in backticks in
its second cell exists there (a row of ``orthoglide_ros/``: in that folder
or below it; another: anywhere in the repository), and every module of the
package (but ``__init__.py`` and ``__main__.py``) is named in its folder's
row.

**Text.** README.md has at most 250 lines, and no page speaks of the
machines the project was developed on ("these machines") or links to the
development-only ``shared/`` directory.
"""

import ast
import fnmatch
import importlib
import io
import os
import re
import tokenize

import model_tables
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, 'doc')
README = os.path.join(ROOT, 'README.md')
README_MAX_LINES = 250
FORBIDDEN = ('these machines', 'shared/')
# The robot.* parameters, every node's, have their table on the model's page.
ROBOT_PREFIX = 'robot.'
MODEL_PAGE = 'model.md'
MODEL_ANCHOR = 'parameters'

# Node page -> module holding the node's PARAMETERS table.
NODE_PAGES = {
    'feedforward.md': 'orthoglide_ros.cores.feedforward',
    'simulator.md': 'orthoglide_ros.cores.simulator',
    'tracking_controller.md': 'orthoglide_ros.cores.tracking_controller',
    'setpoint_publisher.md': 'orthoglide_ros.cores.setpoint_publisher',
    'mechanism_state_publisher.md': 'orthoglide_ros.cores.mechanism_state_publisher',
    'planner.md': 'orthoglide_ros.cores.planner',
}


def pages():
    """Return the paths of README.md and every doc/*.md."""
    return [README] + sorted(
        os.path.join(DOC, name) for name in os.listdir(DOC)
        if name.endswith('.md'))


def page_id(path):
    """Return a path relative to the repository, for messages and ids."""
    return os.path.relpath(path, ROOT)


def read(path):
    with open(path, encoding='utf-8') as stream:
        return stream.read()


def file_default(value):
    """Write a default as a ROS 2 parameters file does (see the docstring)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (int, float, str)):
        return repr(value) if isinstance(value, float) else str(value)
    if isinstance(value, (list, tuple)):
        return '[' + ', '.join(file_default(v) for v in value) + ']'
    raise TypeError(f'no parameters-file form for {value!r}')


def split_row(line):
    """Split a Markdown table row into its cells; an escaped pipe stays."""
    body = line.strip()
    body = body[1:] if body.startswith('|') else body
    body = body[:-1] if body.endswith('|') and not body.endswith('\\|') \
        else body
    return [cell.strip() for cell in re.split(r'(?<!\\)\|', body)]


def tables(text):
    """
    Yield ``(header, rows)`` of every Markdown table of ``text``.

    A table is a run of lines starting with ``|`` whose second line is the
    ``|---|`` separator; code blocks are skipped.
    """
    lines = strip_code_blocks(text).split('\n')
    i = 0
    while i < len(lines):
        if (lines[i].lstrip().startswith('|') and i + 1 < len(lines)
                and re.fullmatch(r'\s*\|?[\s:|-]+\|?\s*', lines[i + 1])
                and '-' in lines[i + 1]):
            header = [h.lower() for h in split_row(lines[i])]
            rows = []
            i += 2
            while i < len(lines) and lines[i].lstrip().startswith('|'):
                rows.append(split_row(lines[i]))
                i += 1
            yield header, rows
        else:
            i += 1


def strip_code_blocks(text):
    """Blank out fenced code blocks, keeping the line count."""
    out, fenced = [], False
    for line in text.split('\n'):
        if line.lstrip().startswith('```'):
            fenced = not fenced
            out.append('')
        else:
            out.append('' if fenced else line)
    return '\n'.join(out)


def parameter_rows(text, name):
    """Return the default cells of the table rows documenting ``name``."""
    found = []
    for header, rows in tables(text):
        if 'default' not in header:
            continue
        column = header.index('default')
        for cells in rows:
            first = re.match(r'`([^`]*)`', cells[0])
            if first and first.group(1) == name:
                found.append(cells[column] if column < len(cells) else '')
    return found


def followed_parameter(spec):
    """Return the ``robot.*`` name a spec without default follows, or None."""
    match = re.search(r'defaults to (\w+)', spec.description)
    if match is None:
        return None
    prefix = spec.name.rpartition('.')[0]
    return f'{prefix}.{match.group(1)}' if prefix else match.group(1)


def node_specs():
    """Yield ``(page, spec)`` for every row of every node's table."""
    for page, module in sorted(NODE_PAGES.items()):
        table = importlib.import_module(module).PARAMETERS
        for spec in table.specs:
            yield page, spec


def documenting_page(page, spec):
    """Return the page whose table documents ``spec`` of ``page``'s node."""
    return MODEL_PAGE if spec.name.startswith(ROBOT_PREFIX) else page


@pytest.mark.parametrize('page,spec', list(node_specs()),
                         ids=lambda x: x if isinstance(x, str) else x.name)
def test_every_parameter_is_on_its_page_with_its_default(page, spec):
    if spec.name.startswith(ROBOT_PREFIX):
        assert f'model.md#{MODEL_ANCHOR}' in read(os.path.join(DOC, page)), (
            f'doc/{page}: no link to the robot.* table '
            f'(model.md#{MODEL_ANCHOR})')
    page = documenting_page(page, spec)
    path = os.path.join(DOC, page)
    assert os.path.exists(path), f'doc/{page}: the page does not exist'
    cells = parameter_rows(read(path), spec.name)
    assert cells, (
        f'doc/{page}: parameter {spec.name} has no row in a table with a '
        f'"default" column (first cell `{spec.name}`)')
    if spec.default is None:
        follows = followed_parameter(spec)
        expected = f'`{follows}`' if follows else 'none'
    else:
        expected = f'`{file_default(spec.default)}`'
    wrong = [cell for cell in cells if expected not in cell]
    assert not wrong, (
        f'doc/{page}: parameter {spec.name}: the default cell says '
        f'{wrong[0]!r}, expected it to hold {expected} (the code\'s '
        f'default is {spec.default!r})')


def test_rows_with_the_same_name_agree_across_tables():
    # A parameter documented twice on one page must not say two things.
    for page in NODE_PAGES:
        text = read(os.path.join(DOC, page))
        for header, rows in tables(text):
            names = [r[0] for r in rows if r and r[0].startswith('`')]
            repeated = {n for n in names if names.count(n) > 1}
            assert not repeated, (
                f'doc/{page}: rows repeat in one table: {sorted(repeated)}')


def test_the_model_tables_are_the_codes():
    text = read(os.path.join(DOC, MODEL_PAGE))
    for name in model_tables.TABLES:
        assert model_tables.block(name).search(text), (
            f'doc/{MODEL_PAGE}: no generated block {name!r}')
    assert text == model_tables.written(text), (
        f'doc/{MODEL_PAGE}: its tables are not the code\'s: run '
        '.venv/bin/python test/model_tables.py --write')


def test_file_default_writes_what_a_parameters_file_holds():
    assert file_default(0.1) == '0.1'
    assert file_default(1000.0) == '1000.0'
    assert file_default(1) == '1'
    assert file_default(False) == 'false'
    assert file_default('base_link') == 'base_link'
    assert file_default([0.0, 0.0, -9.81]) == '[0.0, 0.0, -9.81]'
    assert file_default(['a', 'b']) == '[a, b]'


# Links -----------------------------------------------------------------------
LINK = re.compile(r'!?\[(?:[^\]\\]|\\.)*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')


def links(text):
    """Yield the targets of the inline links and images outside code."""
    prose = strip_code_blocks(text)
    prose = re.sub(r'`[^`\n]*`', '', prose)     # inline code spans
    for match in LINK.finditer(prose):
        yield match.group(1)


def slug(heading):
    """Return GitHub's anchor of a heading's text (before de-duplication)."""
    text = re.sub(r'\[([^\]]*)\]\([^)]*\)', r'\1', heading.strip().lower())
    text = re.sub(r'[^\w\- ]', '', text)
    return text.replace(' ', '-')


def anchors(path):
    """Return the anchors of every heading of a Markdown file."""
    seen = {}
    result = set()
    for line in strip_code_blocks(read(path)).split('\n'):
        match = re.match(r'#{1,6}\s+(.*?)\s*#*\s*$', line)
        if not match:
            continue
        base = slug(match.group(1))
        count = seen.get(base, 0)
        seen[base] = count + 1
        result.add(base if count == 0 else f'{base}-{count}')
    return result


@pytest.mark.parametrize('path', pages(), ids=page_id)
def test_relative_links_point_to_existing_files(path):
    broken = []
    for target in links(read(path)):
        if re.match(r'[a-z][a-z0-9+.-]*:', target):     # http:, mailto:
            continue
        file_part, _, fragment = target.partition('#')
        resolved = path if not file_part else os.path.normpath(
            os.path.join(os.path.dirname(path), file_part))
        if not os.path.exists(resolved):
            broken.append(f'{target} (no file {page_id(resolved)})')
        elif fragment and resolved.endswith('.md') and \
                fragment not in anchors(resolved):
            broken.append(f'{target} (no heading #{fragment} in '
                          f'{page_id(resolved)})')
    assert not broken, f'{page_id(path)}: broken links: ' + '; '.join(broken)


def test_slug_follows_github():
    assert slug('Wiring into ros2_control') == 'wiring-into-ros2_control'
    assert slug('The `orthoglide` command-line tool') == \
        'the-orthoglide-command-line-tool'
    assert slug('`--params`') == '--params'
    assert slug('Inputs, pairing and time') == 'inputs-pairing-and-time'


# Layout ----------------------------------------------------------------------
PACKAGE = 'orthoglide_ros'
# A file or folder the Layout table names: `plant.py`, `<node>_node.py`, `cli/`.
LAYOUT_NAME = re.compile(r'`([\w<>.-]+(?:\.\w+|/))`')


def layout_rows():
    """Return ``[(folders, text)]``: the README's Layout table, row by row."""
    layout = read(README).split('\n## Layout\n', 1)[1].split('\n## ', 1)[0]
    (header, rows), = tables(layout)
    assert header[:2] == ['path', 'what'], header
    return [(re.findall(r'`([^`]+/)`', cells[0]), cells[1])
            for cells in rows]


def name_pattern(name):
    """Return the regular expression of a named file (``<x>``: any name)."""
    return re.compile(''.join('[^/]+' if part.startswith('<') else
                              re.escape(part) for part in
                              re.split(r'(<[^>]*>)', name.rstrip('/'))))


def layout_misses(rows, files):
    """
    Yield what the Layout ``rows`` name and ``files`` (paths) do not hold.

    A name of a row of the package holds in the row's folders or below
    them; of another row, anywhere; then every module of the package
    missing from its folder's row.
    """
    folders = {os.path.dirname(f) + '/' for f in files}
    folders |= {'/'.join(f.split('/')[:k]) + '/' for f in folders
                for k in range(1, f.count('/'))}
    for first, text in rows:
        for folder in first:
            if folder not in folders:
                yield f'{folder} (no such folder)'
        package = all(f.startswith(PACKAGE + '/') for f in first)
        for name in LAYOUT_NAME.findall(text):
            pattern = name_pattern(name)
            where = [p for p in (folders if name.endswith('/') else files)
                     if not package or p.startswith(tuple(first))]
            if not any(pattern.fullmatch(p.rstrip('/').rsplit('/', 1)[-1])
                       for p in where):
                yield f'{name} (not in {", ".join(first)})'
    for module in files:
        if not (module.startswith(PACKAGE + '/') and module.endswith('.py')) \
                or module.endswith(('/__init__.py', '/__main__.py')):
            continue
        row = [text for first, text in rows
               if any(module.startswith(f) for f in first)]
        stem = module.rsplit('/', 1)[1]
        if not any(name_pattern(n).fullmatch(stem)
                   for text in row for n in LAYOUT_NAME.findall(text)):
            yield f'{module} (not named in its row)'


def test_the_readme_layout_is_the_tree():
    files = [f for f in repository_files()
             if '__pycache__' not in f and '.egg-info' not in f]
    missing = list(layout_misses(layout_rows(), files))
    assert not missing, 'README.md, Layout: ' + '; '.join(missing)


def test_layout_misses_are_found():
    files = ['orthoglide_ros/model/plant.py', 'orthoglide_ros/model/urdf.py',
             'orthoglide_ros/ros/feedforward_node.py',
             'orthoglide_ros/tools/cli/common.py', 'scripts/test.sh']
    rows = [(['orthoglide_ros/model/'], '`plant.py` (RK4), `gone.py`'),
            (['orthoglide_ros/ros/'], '`<node>_node.py` for each core'),
            (['orthoglide_ros/tools/'], '`cli/` (`common.py`), `scripts/`'),
            (['scripts/', 'nowhere/'], '`test.sh`, `plant.py`')]
    assert sorted(layout_misses(rows, files)) == [
        'gone.py (not in orthoglide_ros/model/)',
        'nowhere/ (no such folder)',
        'orthoglide_ros/model/urdf.py (not named in its row)',
        'scripts/ (not in orthoglide_ros/tools/)']


# Text ------------------------------------------------------------------------
def test_readme_is_short():
    count = len(read(README).splitlines())
    assert count <= README_MAX_LINES, (
        f'README.md has {count} lines, at most {README_MAX_LINES}: move '
        'reference text to doc/')


@pytest.mark.parametrize('path', pages(), ids=page_id)
def test_no_development_machine_notes(path):
    text = read(path).lower()
    found = [phrase for phrase in FORBIDDEN if phrase in text]
    assert not found, (
        f'{page_id(path)}: contains {found}: state facts as "tested with '
        '..." and link only to files of the repository')


# Named paths -----------------------------------------------------------------
def top_folders():
    """Return the repository's top-level folders that git does not ignore."""
    with open(os.path.join(ROOT, '.gitignore'), encoding='utf-8') as stream:
        ignored = [line.strip().rstrip('/') for line in stream
                   if line.strip() and not line.startswith('#')]
    return sorted(
        name for name in os.listdir(ROOT)
        if os.path.isdir(os.path.join(ROOT, name))
        and not name.startswith('.')
        and not any(fnmatch.fnmatch(name, pattern) for pattern in ignored))


TOP_FOLDERS = top_folders()
# A path from the root: a top-level folder, then anything a path holds; a
# ``../`` prefix (a docstring's link to doc/) is allowed, a folder before it
# is not (``share/orthoglide_ros/config`` is an installed path).
PATH = re.compile(r'(?<![\w./*-])(?:\.\./)*((?:%s)/[\w./-]*(?:#[\w-]+)?)'
                  % '|'.join(map(re.escape, TOP_FOLDERS)))
BARE_MODULE = re.compile(r'(?<![\w./*<>{-])(\w+\.py)\b')
DOTTED = re.compile(r'(?<![\w.])orthoglide_ros(?:\.\w+)+')
TEST_NAME = re.compile(r'(?<![\w./-])(test_\w+)\b(?!\.py)')


def repository_files():
    """Return the paths of every file in the top-level folders, relative."""
    found = []
    for top in TOP_FOLDERS:
        for folder, folders, files in os.walk(os.path.join(ROOT, top)):
            folders[:] = [f for f in folders if not f.startswith(('.', '__'))]
            found += [os.path.relpath(os.path.join(folder, f), ROOT)
                      for f in files]
    return found + [f for f in os.listdir(ROOT)
                    if os.path.isfile(os.path.join(ROOT, f))]


def top_level_names(path):
    """Return the names a module defines or imports at its top level."""
    tree = ast.parse(read(path))
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef,
                             ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split('.')[0]
                         for a in node.names)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) \
                else [node.target]
            for target in targets:
                names.update(n.id for n in ast.walk(target)
                             if isinstance(n, ast.Name))
    return names


def module_file(parts):
    """Return the file of the module ``parts`` names, or None."""
    base = os.path.join(ROOT, *parts)
    for path in (base + '.py', os.path.join(base, '__init__.py')):
        if os.path.exists(path):
            return path
    return None


def missing_dotted(name):
    """Say why a dotted module name (and its name) names nothing, or None."""
    parts = name.split('.')
    for count in range(len(parts), 0, -1):
        path = module_file(parts[:count])
        if path is not None:
            break
    else:
        return 'no such module'
    rest = parts[count:]
    if not rest or rest[0] in top_level_names(path):
        return None
    return f'{".".join(parts[:count])} defines no {rest[0]}'


class References:
    """What the files of the repository are: their paths, modules, tests."""

    def __init__(self):
        files = repository_files()
        self.basenames = {os.path.basename(f) for f in files}
        self.tests = {os.path.basename(f)[:-3] for f in files
                      if f.startswith('test' + os.sep) and f.endswith('.py')}
        for path in files:
            if path.startswith('test' + os.sep) and path.endswith('.py'):
                self.tests.update(re.findall(
                    r'^\s*(?:async )?def (test_\w+)',
                    read(os.path.join(ROOT, path)), re.M))

    def missing(self, text):
        """Yield ``(name, why)`` for every reference of ``text`` to nothing."""
        for match in PATH.finditer(text):
            path, _, fragment = match.group(1).rstrip('.,:;').partition('#')
            full = os.path.join(ROOT, path)
            if not os.path.exists(full):
                yield match.group(1), 'no such file or folder'
            elif fragment and path.endswith('.md') and \
                    fragment not in anchors(full):
                yield match.group(1), f'no heading #{fragment} in {path}'
        for match in BARE_MODULE.finditer(text):
            if match.group(1) not in self.basenames:
                yield match.group(1), 'no file of that name'
        for match in DOTTED.finditer(text):
            why = missing_dotted(match.group(0))
            if why:
                yield match.group(0), why
        for match in TEST_NAME.finditer(text):
            if match.group(1) not in self.tests:
                yield match.group(1), 'no test and no test file of that name'


def prose_of_source(path):
    """Yield ``(line, text)`` of the docstrings and comments of a file."""
    text = read(path)
    if path.endswith('.sh'):
        for number, line in enumerate(text.split('\n'), 1):
            if line.lstrip().startswith('#'):
                yield number, line
        return
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                             ast.AsyncFunctionDef)):
            docstring = ast.get_docstring(node, clean=False)
            if docstring:
                first = node.body[0].lineno
                for offset, line in enumerate(docstring.split('\n')):
                    yield first + offset, line
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.COMMENT:
            yield token.start[0], token.string


@pytest.fixture(scope='module')
def references():
    return References()


@pytest.mark.parametrize('path', pages(), ids=page_id)
def test_paths_named_by_the_pages_exist(references, path):
    stale = [f'line {number}: {name} ({why})'
             for number, line in enumerate(read(path).split('\n'), 1)
             for name, why in references.missing(line)]
    assert not stale, f'{page_id(path)} names what is not there: ' + \
        '; '.join(stale)


def test_paths_named_by_docstrings_and_comments_exist(references):
    stale = [f'{source}:{number}: {name} ({why})'
             for source in repository_files()
             if source.endswith(('.py', '.sh'))
             for number, line in prose_of_source(os.path.join(ROOT, source))
             for name, why in references.missing(line)]
    assert not stale, 'docstrings and comments name what is not there: ' + \
        '; '.join(stale)


def test_stale_references_are_found(references):
    # The check fails where it should: each line names one thing that is
    # not there (or, last, only things that are).
    text = ['see `test/closed_loop_harness.py`',
            'as ../../doc/measurements.md#no-such-heading says',
            'closed_loop_harness.py runs it',
            'orthoglide_ros.model.no_such_module',
            'orthoglide_ros.model.robot.NO_SUCH_NAME',
            'test_that_nobody_wrote',
            'config/ and `doc/model.md#bodies`, orthoglide_ros.model.robot.Robot'
            ' and test_docs.py::test_stale_references_are_found']
    found = [list(references.missing(line)) for line in text]
    assert [len(f) for f in found] == [1, 1, 1, 1, 1, 1, 0], found


# No project history ----------------------------------------------------------
ISSUE = re.compile(r"\b(?:[Ii]ssues? (?=\d)|[Tt]he issue's\b)")


def issue_numbers(line):
    """Yield the references of ``line`` to an issue of this project."""
    for match in ISSUE.finditer(line):
        before = line[:match.start()].split()
        project = before[-1] if before else ''
        # "Fast-DDS issue 6535", "eProsima/Fast-DDS issue 12": upstream.
        if match.group(0).startswith(('issue', 'Issue')) and \
                re.search(r'[A-Z/-]', project[1:]):
            continue
        yield line[match.start():match.start() + 24].strip()


@pytest.mark.parametrize('path', pages(), ids=page_id)
def test_pages_name_no_issue_of_the_project(path):
    found = [f'line {number}: {found}'
             for number, line in enumerate(read(path).split('\n'), 1)
             for found in issue_numbers(line)]
    assert not found, f'{page_id(path)} tells history: ' + '; '.join(found)


def test_docstrings_and_comments_name_no_issue_of_the_project():
    found = [f'{source}:{number}: {found}'
             for source in repository_files()
             if source.endswith(('.py', '.sh'))
             for number, line in prose_of_source(os.path.join(ROOT, source))
             for found in issue_numbers(line)]
    assert not found, 'docstrings and comments tell history: ' + \
        '; '.join(found)


def test_issue_numbers_are_found():
    lines = ['as issue 33 found', '(issue 20)', "the issue's case",
             'Issue 33, item 7', 'eProsima Fast-DDS issue 6535',
             'PR #699, issue #1615', 'an issue of rclpy']
    assert [len(list(issue_numbers(line))) for line in lines] == \
        [1, 1, 1, 1, 0, 0, 0]
