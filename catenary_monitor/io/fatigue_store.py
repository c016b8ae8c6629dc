"""The fatigue store: each line's cumulative chain fatigue kept beside the MCAP log, so the
count survives restarts (the node reads it at start and writes it every
:data:`SAVE_PERIOD` and at its end; docs/fatigue.md).

One JSON file, ``chain_fatigue.json`` in the log folder, written atomically: a temporary file
in the same folder, flushed and fsync'ed, renamed over the store (the folder fsync'ed), the
previous store kept as ``chain_fatigue.json.prev``. What :func:`load` finds is named, never a
silent reset:

``loaded``   the store read;
``new``      no store and no log in the folder (a new dock): each line from
             ``NAME.fatigue_damage_initial``;
``missing``  no store beside MCAP logs: the count restarts from ``NAME.fatigue_damage_initial``
             (replay the folder to recount it), or from the previous store where one is left;
``damaged``  the store (or a line's record in it) unreadable: set aside as
             ``chain_fatigue.json.damaged-N``, the previous store read instead where it is sound,
             else the lines start from ``NAME.fatigue_damage_initial``.

No decisions here (the monitor core takes each line's record); no rclpy.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path
from typing import Any, NamedTuple, Optional

__all__ = ['STORE_NAME', 'SAVE_PERIOD', 'VERSION', 'Loaded', 'load', 'save', 'store_path']

STORE_NAME = 'chain_fatigue.json'
#: The node saves the store this often (s of wall time) and when it stops.
SAVE_PERIOD = 60.0
VERSION = 1


class Loaded(NamedTuple):
    """What :func:`load` found: ``state`` (see the module docstring), a one-line ``message``
    and the stored record of each line it holds (line name -> record)."""

    state: str
    message: str
    lines: dict[str, Any]


def store_path(directory: str | Path) -> Path:
    """The store's path in a log folder."""
    return Path(os.path.expanduser(str(directory))) / STORE_NAME


def _read(path: Path) -> tuple[Optional[dict[str, Any]], str]:
    """The store's lines, or None and why not."""
    try:
        data = json.loads(path.read_text(encoding='utf-8'))
    except (OSError, UnicodeDecodeError) as err:
        return None, f'unreadable: {err}'
    except ValueError as err:
        return None, f'not JSON: {err}'
    if not isinstance(data, dict) or data.get('version') != VERSION:
        return None, f'not a version {VERSION} fatigue store'
    lines = data.get('lines')
    if not isinstance(lines, dict):
        return None, 'no lines in it'
    bad = [name for name, record in lines.items() if not _sound(record)]
    if bad:
        return None, f'damaged record of {", ".join(sorted(map(str, bad)))}'
    return lines, ''


def _sound(record: Any) -> bool:
    """A line's record has the shape the monitor reads (finite numbers)."""
    try:
        numbers = [float(record['closed'])]
        numbers += [float(v) for v in record['residue']]
        numbers += [float(v) for mark in record['marks'] for v in mark]
    except (KeyError, TypeError, ValueError):
        return False
    return all(math.isfinite(v) for v in numbers) and numbers[0] >= 0.0


def _set_aside(path: Path) -> str:
    """Rename a damaged store to ``NAME.damaged-N`` (never over another); its new name."""
    for n in range(1, 1000):
        target = path.with_name(f'{path.name}.damaged-{n}')
        if not target.exists():
            try:
                path.rename(target)
            except OSError as err:
                return f'left in place ({err})'
            return f'kept as {target.name}'
    return 'left in place'


def load(directory: str | Path, names: list[str]) -> Loaded:
    """The store of the log folder ``directory`` for the lines ``names`` (never raises)."""
    path = store_path(directory)
    if path.exists():
        lines, why = _read(path)
        if lines is not None:
            absent = [n for n in names if n not in lines]
            more = f'; {", ".join(absent)} not in it: from NAME.fatigue_damage_initial'
            return Loaded('loaded', f'fatigue store {path} read' + (more if absent else ''), lines)
        aside = _set_aside(path)
        previous, _ = _read(path.with_name(path.name + '.prev'))
        if previous is not None:
            return Loaded(
                'damaged',
                f'fatigue store {path} {why} ({aside}): its previous copy read instead '
                f'(up to {SAVE_PERIOD:g} s of counting older)',
                previous,
            )
        return Loaded(
            'damaged',
            f'fatigue store {path} {why} ({aside}): damage restarted from '
            'NAME.fatigue_damage_initial (replay the log folder to recount it)',
            {},
        )
    previous, _ = _read(path.with_name(path.name + '.prev'))
    if previous is not None:
        return Loaded(
            'missing',
            f'fatigue store {path} missing: its previous copy read instead (up to '
            f'{SAVE_PERIOD:g} s of counting older)',
            previous,
        )
    logs = sorted(path.parent.glob('*.mcap')) if path.parent.is_dir() else []
    if logs:
        return Loaded(
            'missing',
            f'no fatigue store beside the {len(logs)} MCAP log(s) in {path.parent}: damage '
            'restarted from NAME.fatigue_damage_initial (replay the log folder to recount it)',
            {},
        )
    return Loaded('new', f'new fatigue store {path}: damage from NAME.fatigue_damage_initial', {})


def save(
    directory: str | Path, lines: dict[str, Any], extra: Optional[dict[str, Any]] = None
) -> Path:
    """Write the store atomically (raises OSError, e.g. a full disk, or ValueError for a
    non-finite number: the old store stays)."""
    path = store_path(directory)
    data = {'version': VERSION, **(extra or {}), 'lines': lines}
    text = json.dumps(data, sort_keys=True, allow_nan=False)
    tmp = path.with_name(f'.{path.name}.tmp-{os.getpid()}')
    try:
        with open(tmp, 'w', encoding='utf-8') as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        if path.exists():  # the previous store, for a store damaged later
            shutil.copyfile(path, path.with_name(path.name + '.prev'))
        os.replace(tmp, path)
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path
