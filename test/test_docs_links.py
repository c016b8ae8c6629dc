"""The docs point at things that exist: every relative link of README.md and docs/*.md reaches
a file (and a heading of it, as GitHub slugs headings), every source path they name exists, and
every module or attribute they name in inline code (``catenary_monitor.x.y``, ``core.x.y``, or
``engine.advance`` by a module's last name) is defined; a module name retired when the core was
sorted by role (``batch``, ``kernels``, ...) is reported with its new name.

Read from the Markdown text and the sources' syntax trees, with no import of the package (no
ROS needed): links ``[t](target)``, ``![t](target)`` and ``<img src=...>`` outside fenced code
blocks; paths such as ``core/alarms/latches.py`` or ``test/test_batch.py::test_x`` anywhere
outside fenced code blocks. docs/CHANGES.md is history (it names modules as they were called):
its links only. The shipped params files (config/*.yaml) are held to the same in their comments.
Web links are not fetched.
"""

import ast
import re
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]
#: pages whose names are history (what a module was called then): their links only
HISTORY = {ROOT / 'docs' / 'CHANGES.md'}
PACKAGE = ROOT / 'catenary_monitor'

_FENCE = re.compile(r'^\s*(```|~~~)')
_LINK = re.compile(r'!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)')
_IMG = re.compile(r'<img\s[^>]*\bsrc="([^"]+)"')
_CODE = re.compile(r'`([^`]+)`')
#: a path into the repository: a known top folder (or a room of the package), then a file
_PATH = re.compile(
    r'(?<![\w./-])((?:catenary_monitor_study|catenary_monitor|core|io|sim|ros|cli|console|replay'
    r'|test|docs|config|tools)/[\w./-]*\.(?:py|c|h|md|yaml|sh|js|json|png|csv))(?![\w-])'
    r'(?:::(\w+))?'
)
_DOTTED = re.compile(r'^((?:catenary_monitor_study|catenary_monitor|core)(?:\.\w+)+)(?:\(.*\))?$')
#: a dotted name from a module named by its last part alone (``engine.advance``)
_SHORT = re.compile(r'^([A-Za-z_]\w*(?:\.\w+)+)(?:\(.*\))?$')
#: module names retired when the core was sorted by role: the docs use the new ones
RETIRED = {
    'batch': 'core.twin.engine',
    'kernels': 'core.physics.fused_kernel',
    '_kernels': 'core.physics._fused_kernel',
    '_steps': 'core.twin._twin_loops',
    'replay_stream': 'replay.driver',
    'replay_output': 'replay.outputs',
    'mcap_fast': 'io.mcap_column_writer',
    'fastcsv': 'io.csv_columns',
    'sensor': 'core.rules.sensor_state',
    'alarm_flood': 'core.alarms.flood',
    'alarm_journal': 'core.alarms.journal',
}


def _entry_point_groups() -> frozenset[str]:
    """setup.py's entry-point groups (``catenary_monitor.commands``): dotted, not modules."""
    for node in ast.walk(ast.parse((ROOT / 'setup.py').read_text(encoding='utf-8'))):
        if isinstance(node, ast.keyword) and node.arg == 'entry_points':
            assert isinstance(node.value, ast.Dict)
            return frozenset(k.value for k in node.value.keys if isinstance(k, ast.Constant))
    return frozenset()


ENTRY_POINT_GROUPS = _entry_point_groups()


def _leaf_modules() -> dict[str, str]:
    """Last part of a module's name -> its full name, where only one module has it."""
    found: dict[str, list[str]] = {}
    for package in ('catenary_monitor', 'catenary_monitor_study'):
        for path in (ROOT / package).rglob('*.py'):
            parts = list(path.relative_to(ROOT).with_suffix('').parts)
            if parts[-1] == '__init__':
                parts.pop()
            found.setdefault(parts[-1], []).append('.'.join(parts))
    return {leaf: names[0] for leaf, names in found.items() if len(names) == 1}


LEAF_MODULES = _leaf_modules()


def _prose(text: str) -> list[tuple[int, str]]:
    """(line number, line) of every line outside fenced code blocks."""
    out, fenced = [], False
    for n, line in enumerate(text.splitlines(), 1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append((n, line))
    return out


def github_slug(heading: str) -> str:
    """A heading's anchor as GitHub makes it: the text without Markdown (code ticks, emphasis,
    link targets), lower case, every character but letters, digits, spaces, ``-`` and ``_``
    dropped, spaces made ``-``."""
    text = re.sub(r'\[([^\]]*)\]\([^)]*\)', r'\1', heading)
    text = re.sub(r'<[^>]+>', '', text).strip().lower()
    text = ''.join(c for c in text if c.isalnum() or c in ' -_')
    return text.replace(' ', '-')


@lru_cache(maxsize=None)
def anchors(page: Path) -> frozenset[str]:
    """Every heading anchor of a Markdown page (repeats get GitHub's ``-1``, ``-2``)."""
    seen: dict[str, int] = {}
    out = set()
    for _, line in _prose(page.read_text(encoding='utf-8')):
        match = re.match(r'^#{1,6}\s+(.*?)\s*#*\s*$', line)
        if not match:
            continue
        slug = github_slug(match.group(1))
        out.add(slug if slug not in seen else f'{slug}-{seen[slug]}')
        seen[slug] = seen.get(slug, 0) + 1
    return frozenset(out)


def _links(page: Path) -> list[tuple[int, str]]:
    found = []
    for n, line in _prose(page.read_text(encoding='utf-8')):
        for rx in (_LINK, _IMG):
            found.extend((n, m.group(1)) for m in rx.finditer(line))
    return found


def _check_link(page: Path, target: str) -> str:
    """'' when the link reaches its file and heading, else what is wrong."""
    if re.match(r'^[a-z][a-z0-9+.-]*:', target):  # http:, https:, mailto:
        return ''
    path, _, anchor = target.partition('#')
    file = (page.parent / path).resolve() if path else page
    if not file.exists():
        return f'{target}: no file {_shown(file)}'
    if anchor and file.suffix == '.md' and anchor not in anchors(file):
        return f'{target}: no heading with the anchor #{anchor} in {_shown(file)}'
    return ''


def _shown(file: Path) -> str:
    return str(file.relative_to(ROOT)) if ROOT in file.parents else file.name


def _resolve_path(path: str) -> Path | None:
    """A path as the docs write it: from the repository's root, or inside the package
    (``core/...``, ``io/...``: the package's rooms)."""
    for base in (ROOT, PACKAGE):
        if (base / path).exists():
            return base / path
    return None


@lru_cache(maxsize=None)
def _defined(source: Path) -> frozenset[str]:
    """Names a module defines at its top level (functions, classes, assignments, imports)."""
    tree = ast.parse(source.read_text(encoding='utf-8'))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split('.')[0] for a in node.names)
    return frozenset(names)


def _class_members(source: Path, cls: str) -> frozenset[str]:
    for node in ast.parse(source.read_text(encoding='utf-8')).body:
        if isinstance(node, ast.ClassDef) and node.name == cls:
            names = {n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
            names |= {
                t.id
                for n in node.body
                if isinstance(n, (ast.Assign, ast.AnnAssign))
                for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
                if isinstance(t, ast.Name)
            }
            return frozenset(names)
    return frozenset()


def _module_file(parts: list[str]) -> Path | None:
    base = ROOT.joinpath(*parts)
    if (base / '__init__.py').exists():
        return base / '__init__.py'
    if base.with_suffix('.py').exists():
        return base.with_suffix('.py')
    return None


def resolve_dotted(name: str) -> str:
    """'' when ``name`` (``catenary_monitor....``, or ``core....`` inside the package) is a
    module, or a name defined in one (a class's member one level down), else what is missing."""
    parts = name.split('.')
    if parts[0] == 'core':
        parts = ['catenary_monitor', *parts]
    for i in range(len(parts), 0, -1):
        source = _module_file(parts[:i])
        if source is None:
            continue
        rest = parts[i:]
        if not rest:
            return ''
        if rest[0] not in _defined(source):
            return f'{name}: {".".join(parts[:i])} defines no {rest[0]}'
        if len(rest) > 1 and _class_members(source, rest[0]):
            if rest[1] not in _class_members(source, rest[0]):
                return f'{name}: {rest[0]} has no {rest[1]}'
        return ''
    return f'{name}: no such module'


def _problems(page: Path) -> list[str]:
    rel = _shown(page)
    out = [f'{rel}:{n}: link {why}' for n, t in _links(page) if (why := _check_link(page, t))]
    if page in HISTORY:
        return out
    for n, line in _prose(page.read_text(encoding='utf-8')):
        for m in _PATH.finditer(line):
            file = _resolve_path(m.group(1))
            if file is None:
                out.append(f'{rel}:{n}: no file {m.group(1)}')
            elif m.group(2) and not re.search(
                rf'^\s*def {m.group(2)}\b', file.read_text(encoding='utf-8'), re.M
            ):
                out.append(f'{rel}:{n}: {m.group(1)} has no test {m.group(2)}')
        for code in _CODE.findall(line):
            if why := _check_name(code.strip()):
                out.append(f'{rel}:{n}: {why}')
    return out


def _check_name(code: str) -> str:
    """'' unless inline code names a module or attribute of the package that does not exist:
    ``catenary_monitor.x.y``, ``core.x.y``, or ``leaf.y`` with ``leaf`` a module's last name."""
    if re.search(r'\.(?:py|c|h|md|yaml|png|csv|json|mcap|html|js)$', code):
        return ''  # a file name, not a module's attribute
    dotted = _DOTTED.match(code)
    if dotted:
        name = dotted.group(1)
        if name == 'core.state' or name.startswith('core.state.'):
            return ''  # a MonitorCore object's state (CoreState), not a module
        return '' if name in ENTRY_POINT_GROUPS else resolve_dotted(name)
    short = _SHORT.match(code)
    if not short:
        return ''
    first, _, rest = short.group(1).partition('.')
    if first in RETIRED:
        return f'{short.group(1)}: {first} is now {RETIRED[first]}'
    if first in LEAF_MODULES and first != 'catenary_monitor':
        return resolve_dotted(f'{LEAF_MODULES[first]}.{rest}')
    return ''


@pytest.mark.parametrize('page', PAGES, ids=[p.name for p in PAGES])
def test_every_link_path_and_name_in_the_docs_exists(page):
    problems = _problems(page)
    assert not problems, '\n'.join(problems)


CONFIGS = sorted((ROOT / 'config').glob('*.yaml'))


@pytest.mark.parametrize('config', CONFIGS, ids=[p.name for p in CONFIGS])
def test_the_example_params_name_files_and_modules_that_exist(config):
    """The shipped params files' comments: their paths and ``catenary_monitor.x.y`` names."""
    problems = []
    for n, line in enumerate(config.read_text(encoding='utf-8').splitlines(), 1):
        comment = line.partition('#')[2]
        problems += [
            f'{config.name}:{n}: no file {m.group(1)}'
            for m in _PATH.finditer(comment)
            if _resolve_path(m.group(1)) is None
        ]
        for name in re.findall(r'\bcatenary_monitor(?:\.\w+)+', comment):
            if why := resolve_dotted(name):
                problems.append(f'{config.name}:{n}: {why}')
    assert not problems, '\n'.join(problems)


def test_the_checker_sees_what_is_broken(tmp_path):
    """The checker itself: GitHub's slugs, and a broken link, anchor, path and name found."""
    assert github_slug('Sensor sanity (`core/rules/sensor_state.py`)') == (
        'sensor-sanity-corerulessensor_statepy'
    )
    assert github_slug('A common cause is one alarm: `catenary_monitor: sensors`') == (
        'a-common-cause-is-one-alarm-catenary_monitor-sensors'
    )
    assert github_slug('The C kernel, 8× [the floor](x.md)') == 'the-c-kernel-8-the-floor'
    page = tmp_path / 'page.md'
    page.write_text(
        '# Title\n\n## Title\n\n[ok](#title-1) [bad](#nowhere) [gone](missing.md)\n'
        '```\n[in a code block](ignored.md) core/none.py\n```\n'
        'see `core/alarms/latches.py`, core/monitor/nothing.py and '
        'test/test_docs_links.py::test_not_here; `core.alarms.latches.LineAlarm`, '
        '`catenary_monitor.core.alarms.latches.NoSuch`, `catenary_monitor.nothing.x`, '
        '`batch.advance`, `engine.advance(core, window)`, `engine.nothing`, `np.empty`\n',
        encoding='utf-8',
    )
    problems = '\n'.join(_problems(page))
    assert '#nowhere' in problems and 'missing.md' in problems and '#title-1' not in problems
    assert 'ignored' not in problems and 'core/none.py' not in problems  # in a code block
    assert 'no file core/monitor/nothing.py' in problems
    assert 'has no test test_not_here' in problems
    assert 'latches defines no NoSuch' in problems
    assert 'catenary_monitor defines no nothing' in problems
    assert 'core/alarms/latches.py' not in problems
    assert 'LineAlarm' not in problems and 'np.empty' not in problems
    assert 'batch.advance: batch is now core.twin.engine' in problems
    assert 'engine defines no nothing' in problems and 'engine.advance' not in problems
    assert resolve_dotted('catenary_monitor.core.monitor.monitor_core.MonitorCore.step') == ''
    assert 'has no nope' in resolve_dotted('core.monitor.monitor_core.MonitorCore.nope')


def test_readme_is_a_newcomers_page():
    """The README stays short (the depth lives in docs/) and names the Pythons setup.py allows."""
    readme = ROOT.joinpath('README.md').read_text(encoding='utf-8')
    assert len(readme.encode('utf-8')) <= 10_000
    assert 'Python 3.10 to 3.13' in readme
