"""The layering of the package, checked from the source: who may import whom, and no cycles.

Layers: the core's rooms ``physics`` <- ``config`` <- ``body`` <- ``rules`` <- ``alarms`` <-
``monitor`` <- ``twin`` (pure numpy), and ``io`` (MCAP, CDR, CSV; independent of the core) <-
``replay`` (core + io) <- ``ros`` (rclpy) <- the shells ``cli`` and ``console``, which never
import each other; ``sim`` (the demo's episode and MoorDyn, core only, no rclpy) under ``ros`` and
the shells; the methods study (``catenary_monitor_study``) sits on top and the monitor never
imports it. Imports are read with ``ast``: module-level and function-level, absolute and
relative; ``from pkg import name`` counts as an import of the submodule ``pkg.name`` when there
is one, else of ``pkg`` (a package ``__init__`` is a module of the graph under the package's
name). No module imports another's private name (``from x import _y``) but a C extension beside
it.
"""

import ast
import json
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ('catenary_monitor', 'catenary_monitor_study')
#: rclpy and the ROS message packages: core and io must work without any of them.
ROS_PACKAGES = ('rclpy', 'std_msgs', 'diagnostic_msgs', 'rcl_interfaces', 'builtin_interfaces')


def _find_modules() -> dict[str, Path]:
    """Module name -> source file, for every module of both packages."""
    out: dict[str, Path] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob('*.py')):
            parts = list(path.relative_to(ROOT).with_suffix('').parts)
            if parts[-1] == '__init__':
                parts.pop()
            out['.'.join(parts)] = path
    return out


MODULES = _find_modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == '__init__.py'


def _within(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + '.')


@lru_cache(maxsize=None)
def imports_of(name: str) -> frozenset[str]:
    """Every module ``name`` imports anywhere in its source (any package, resolved)."""
    tree = ast.parse(MODULES[name].read_text(encoding='utf-8'), str(MODULES[name]))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split('.') if _is_package(name) else name.split('.')[:-1]
                if node.level - 1 > 0:
                    base = base[: -(node.level - 1)]
                target = '.'.join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ''
            for alias in node.names:
                sub = f'{target}.{alias.name}'
                found.add(sub if sub in MODULES else target)
    return frozenset(found)


def _layer(name: str) -> str:
    """``top`` (the package __init__), a room of the core (:data:`CORE_ROOMS`), ``io``, ``sim``,
    ``replay``, ``ros``, ``cli``, ``console`` or ``study``."""
    if _within(name, 'catenary_monitor_study'):
        return 'study'
    if name == 'catenary_monitor':
        return 'top'
    if name == 'catenary_monitor.__main__':
        return 'cli'  # ``python -m catenary_monitor``: the command line
    if name == 'catenary_monitor.core':
        return 'physics'  # the core's docstring only
    for room in CORE_ROOMS:
        if _within(name, f'catenary_monitor.core.{room}'):
            return room
    for layer in ('io', 'sim', 'replay', 'ros', 'cli', 'console'):
        if _within(name, f'catenary_monitor.{layer}'):
            return layer
    raise AssertionError(f'{name}: module outside the known layers')


#: The core's rooms, bottom first: each may import those before it (its floors), never one
#: after it: the chain models, the parameters, the dock as a body, the per-line rules, alarm
#: management, the event schedule (MonitorCore), the vectorized twin.
CORE_ROOMS = ('physics', 'config', 'body', 'rules', 'alarms', 'monitor', 'twin')
CORE = set(CORE_ROOMS)

#: What each layer may import of the project. The top level is the numerical core's face
#: (``catenary_monitor.solve``, ``whatif``); io imports nothing from the core.
ALLOWED = {
    'top': {'top', *CORE},
    **{room: set(CORE_ROOMS[: i + 1]) for i, room in enumerate(CORE_ROOMS)},
    'io': {'io'},
    'sim': {*CORE, 'sim'},
    'replay': {'top', *CORE, 'io', 'replay'},
    'ros': {'top', *CORE, 'io', 'sim', 'ros'},
    'cli': {'top', *CORE, 'io', 'sim', 'replay', 'ros', 'cli'},
    'console': {'top', *CORE, 'io', 'sim', 'replay', 'ros', 'console'},
    'study': {'top', *CORE, 'io', 'sim', 'replay', 'ros', 'cli', 'console', 'study'},
}


def _project_imports(name: str) -> list[str]:
    return sorted(t for t in imports_of(name) if t.split('.')[0] in PACKAGES)


def test_modules_found_and_imports_resolved():
    """Guards the parser itself: known edges of each kind are seen."""
    assert {
        'catenary_monitor',
        'catenary_monitor.core.physics.solve',
        'catenary_monitor.io.cdr',
    } <= set(MODULES)
    # the package __init__ (package-level edge)
    assert 'catenary_monitor.core.physics.solve' in imports_of('catenary_monitor')
    # ``from catenary_monitor.core import catenary as cat``: the submodule
    assert 'catenary_monitor.core.physics.catenary' in imports_of(
        'catenary_monitor.core.physics.elastic'
    )
    # function-level import
    assert 'catenary_monitor.core.config.params_file' in imports_of(
        'catenary_monitor.core.config.parameters'
    )
    # relative imports, ``from .base import Method`` and ``from . import closed``
    assert 'catenary_monitor_study.methods.base' in imports_of(
        'catenary_monitor_study.methods.closed'
    )
    assert 'catenary_monitor_study.methods.closed' in imports_of('catenary_monitor_study.methods')


def test_layering():
    bad = []
    for name in MODULES:
        layer = _layer(name)
        for target in _project_imports(name):
            if _layer(target) not in ALLOWED[layer]:
                bad.append(f'{name} ({layer}) imports {target} ({_layer(target)})')
    assert not bad, 'layering violated:\n' + '\n'.join(bad)


def test_core_and_io_import_no_ros_package_anywhere():
    """Not even inside a function (the import test below sees module-level imports only)."""
    bad = [
        f'{name} imports {target}'
        for name in MODULES
        if _layer(name) in (*CORE, 'io', 'sim', 'replay')
        for target in sorted(imports_of(name))
        if target.split('.')[0] in ROS_PACKAGES
    ]
    assert not bad, '\n'.join(bad)


_IMPORT_ALL = """
import importlib, json, sys
for blocked in sys.argv[1].split(','):
    sys.modules[blocked] = None  # ``import blocked`` (and its submodules) raises ImportError
failed = {}
for name in sys.argv[2:]:
    try:
        importlib.import_module(name)
    except BaseException as exc:
        failed[name] = f'{type(exc).__name__}: {exc}'
print(json.dumps({'failed': failed, 'file': sys.modules['catenary_monitor'].__file__}))
"""


def test_core_and_io_import_without_ros():
    names = [n for n in MODULES if _layer(n) in (*CORE, 'io', 'sim', 'replay')]
    assert len(names) > 10
    p = subprocess.run(
        [sys.executable, '-c', _IMPORT_ALL, ','.join(ROS_PACKAGES), *names],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    out = json.loads(p.stdout.splitlines()[-1])
    assert Path(out['file']).resolve() == ROOT / 'catenary_monitor' / '__init__.py'
    assert not out['failed'], '\n'.join(f'{k}: {v}' for k, v in out['failed'].items())


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle (``[a, b, ..., a]``) per strongly connected component that has one."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []

    def visit(v: str) -> None:  # Tarjan
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            components.append(component)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    cycles = []
    for component in components:
        start = min(component)
        if len(component) == 1 and start not in graph.get(start, ()):
            continue
        # shortest way back to ``start`` inside the component (breadth first)
        parent: dict[str, str] = {}
        frontier = [start]
        while frontier and start not in parent:
            nxt = []
            for v in frontier:
                for w in sorted(graph.get(v, ())):
                    if w in component and w not in parent:
                        parent[w] = v
                        nxt.append(w)
            frontier = nxt
        path = [start]
        v = parent[start]
        while v != start:
            path.append(v)
            v = parent[v]
        path.append(start)
        cycles.append(path[:1] + path[1:-1][::-1] + path[-1:])
    return sorted(cycles)


def test_cycle_finder():
    assert find_cycles({'a': {'b'}, 'b': {'c'}, 'c': set()}) == []
    assert find_cycles({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == [['a', 'b', 'c', 'a']]
    assert find_cycles({'a': {'a'}}) == [['a', 'a']]
    assert find_cycles({'a': {'b'}, 'b': {'a'}, 'c': {'d'}, 'd': {'c'}}) == [
        ['a', 'b', 'a'],
        ['c', 'd', 'c'],
    ]


def test_no_import_cycles():
    """Between the modules of both packages, function-level imports included."""
    names = list(MODULES)
    graph = {n: {t for t in imports_of(n) if t in names} for n in names}
    cycles = find_cycles(graph)
    assert not cycles, 'import cycles:\n' + '\n'.join(' -> '.join(c) for c in cycles)


def test_every_package_says_what_it_holds_and_may_import():
    """Each sub-package of the core, sim and replay open with a paragraph naming its rooms."""
    for name in MODULES:
        if not _is_package(name) or not _within(name, 'catenary_monitor'):
            continue
        doc = ast.get_docstring(ast.parse(MODULES[name].read_text(encoding='utf-8')))
        assert doc and len(doc) > 80, f'{name}: no docstring saying what it holds'
        if _layer(name) in (*CORE, 'sim', 'replay') and name != 'catenary_monitor.core':
            assert (
                'may import' in doc.lower()
            ), f'{name}: its docstring does not say what it may import'


def test_no_two_modules_share_a_name():
    """A reader never confuses two modules: each module's own name is unique in the package
    (``__init__``, ``__main__`` and ``command`` aside)."""
    seen: dict[str, str] = {}
    clash = []
    for name in MODULES:
        if not _within(name, 'catenary_monitor') or _is_package(name):
            continue
        base = name.rsplit('.', 1)[-1]
        if base in ('__main__',):
            continue
        if base in seen:
            clash.append(f'{seen[base]} and {name}')
        seen[base] = name
    assert not clash, 'modules with the same name:\n' + '\n'.join(clash)


def test_cli_and_console_never_import_each_other():
    bad = [
        f'{name} imports {target}'
        for name in MODULES
        for target in _project_imports(name)
        if {_layer(name), _layer(target)} == {'cli', 'console'}
    ]
    assert not bad, '\n'.join(bad)


def _c_extension(package: str, name: str) -> bool:
    """``package.name`` is one of the C accelerators built from ``name.c`` beside its wrapper."""
    return package in MODULES and (MODULES[package].parent / f'{name}.c').is_file()


def private_imports(name: str) -> list[str]:
    """``from x import _y`` (and ``import x._y``) in ``name``'s source, where ``_y`` is a private
    name of another module, resolved as :func:`imports_of` does. A C extension imported by a
    module of its own package is its wrapper's, not another module's private name."""
    tree = ast.parse(MODULES[name].read_text(encoding='utf-8'), str(MODULES[name]))
    package = name if _is_package(name) else name.rpartition('.')[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split('.')
                for i, part in enumerate(parts[1:], 1):
                    if part.startswith('_') and not part.startswith('__'):
                        owner = '.'.join(parts[:i])
                        if not (owner == package and _c_extension(owner, part)):
                            found.append(f'import {alias.name}')
                        break
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split('.') if _is_package(name) else name.split('.')[:-1]
                if node.level - 1 > 0:
                    base = base[: -(node.level - 1)]
                target = '.'.join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ''
            for alias in node.names:
                if not alias.name.startswith('_') or alias.name.startswith('__'):
                    continue
                if target == package and _c_extension(target, alias.name):
                    continue
                found.append(f'from {target} import {alias.name}')
    return found


def test_no_private_imports_across_modules():
    """No module takes another module's private name (``from x import _y``): what two modules
    share is public, named once where it belongs."""
    assert private_imports('catenary_monitor.io.mcap_scan') == []  # its own _scan is allowed
    bad = [f'{name}: {line}' for name in MODULES for line in private_imports(name)]
    assert not bad, 'private names imported across modules:\n' + '\n'.join(bad)
