"""The fleet replay's tasks: a dock's folder planned as a chain of pieces, each piece the
command's streamed replay of one file carrying the core on, and the dock's end.

Plain functions of plain data (no scheduler here: :mod:`.fleet_cluster` runs them on Dask).

**Why a chain.** What the monitor decides at a message depends on everything before it
(latches, hold timers, the tide's trend, Miner's sum), so a dock's log is replayed in time
order. It is cut at its files (a node rotates its log, so a year is thousands of files):
piece K replays file K with the state piece K-1 handed on (:class:`Carry`: the core in the
stream's state, the summary's tally, the daily extremes), exactly as the one streamed replay of
the folder would (:func:`catenary_monitor.replay.driver.stream`, ``resume``), provided every
stamp of a file comes after every stamp of the file before it (checked as the piece goes).
The docks' chains run side by side; a chain's pieces may run on different workers (the carry
travels). Files that overlap
in time, or a log the stream cannot take in pieces, make the dock one task (:func:`plan_dock`
``serial``), replayed as ``catenary-monitor replay DIR`` would.

**Idempotent and resumable.** A piece writes its message parts under names of its own
(``part-K``) and renamed into place, then its checkpoint (``RESULTS/_fleet/dock=D/task-K``:
the carry, and a digest of everything it depends on: the package version, the parameters,
the files of pieces 0..K by name, size and mtime). A piece done again (a retry, a worker lost
with the result in its memory) finds its checkpoint and returns it; a run started again resumes
after the last piece whose digest still holds.

**Damage.** A damaged part of a file is skipped by the reader and named (the replay's own
rules); a file the reader refuses (not MCAP, a hostile record) is named with its task and
skipped: the chain goes on from the state before it (the results are those of a replay of the
folder without that file).
"""

from __future__ import annotations

import copy
import ctypes
import errno
import hashlib
import json
import os
import pickle
import sys
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np

from catenary_monitor import __version__
from catenary_monitor.core.config.parameters import (
    ConfigError,
    MonitorConfig,
    config_from_params,
    config_hash,
)
from catenary_monitor.core.physics import fused_kernel
from catenary_monitor.io import mcap_read
from catenary_monitor.io.mcap_read import first_log_time, not_mcap
from catenary_monitor.io.mcap_scan import McapReadError, ReadReport
from catenary_monitor.replay.driver import (
    ReplayError,
    Restart,
    StreamState,
    load_config,
    log_parameters,
    stamp_figures,
    stamp_lines,
    stream,
)
from catenary_monitor.replay.fleet_dataset import (
    MESSAGE_COLUMNS,
    DailyExtremes,
    PartWriter,
    episodes_table,
    level_seconds,
    message_table,
    replace_dock_tables,
    window_columns,
)
from catenary_monitor.replay.outputs import Tally
from catenary_monitor.core.twin.window import LineResult

__all__ = [
    'PARAMS_FILE',
    'Carry',
    'DockPlan',
    'FleetError',
    'PieceRestart',
    'dock_name',
    'finish_dock',
    'plan_dock',
    'resume_point',
    'run_piece',
]

#: A dock folder's own params file, used instead of the parameters recorded in its log.
PARAMS_FILE = 'catenary_monitor.yaml'


class FleetError(Exception):
    """A dock that cannot be replayed (no log, no parameters): ``str()`` is one line."""


def dock_name(folder: Path) -> str:
    """The dock a folder is (its resolved name). Raises :class:`FleetError` for a folder that
    cannot be resolved: a symlink loop (RuntimeError in Python < 3.13, ELOOP after)."""
    try:
        return Path(folder).resolve().name
    except RuntimeError:
        raise FleetError(f'{folder}: a symlink loop (the folder cannot be resolved)') from None
    except OSError as err:
        why = 'a symlink loop' if err.errno == errno.ELOOP else (err.strerror or str(err))
        raise FleetError(f'{folder}: {why} (the folder cannot be resolved)') from None


class PieceRestart(Exception):
    """The dock's log cannot be replayed in pieces (files overlap in time, ...): replay it
    as one task."""


@dataclass(frozen=True)
class DockPlan:
    """One dock's work: its files in time order and the pieces (tasks) that replay them."""

    name: str
    folder: str
    files: tuple[str, ...]
    identity: tuple[tuple[str, int, int], ...]  # per file: name, size B, mtime ns
    pieces: tuple[tuple[int, ...], ...]  # per task: its files (indexes into files)
    config: MonitorConfig
    follow_log: bool
    params_source: str
    refused: tuple[str, ...] = ()  # files that are not MCAP: one line each, never replayed
    columns: tuple[str, ...] = MESSAGE_COLUMNS  # the messages dataset's (fleet --columns)

    @property
    def serial(self) -> bool:
        """The dock is one task (its files overlap in time, or it was asked)."""
        return len(self.pieces) == 1 and len(self.files) > 1

    def digest(self, task: int) -> str:
        """What piece ``task``'s results depend on: version, parameters, its files and those
        of the pieces before it (name, size, mtime), the cut."""
        h = hashlib.sha256()
        facts: list[Any] = [__version__, config_hash(self.config), self.follow_log]
        if self.columns != MESSAGE_COLUMNS:
            facts.append(list(self.columns))
        h.update(json.dumps(facts).encode())
        for k in range(task + 1):
            h.update(json.dumps([self.identity[i] for i in self.pieces[k]]).encode())
        return h.hexdigest()


def _identity(path: Path) -> tuple[str, int, int]:
    st = path.stat()
    return (path.name, int(st.st_size), int(st.st_mtime_ns))


def dock_config(folder: Path, files: list[Path]) -> tuple[MonitorConfig, bool, str]:
    """(configuration, follow the recorded changes, where it came from) of a dock: the
    folder's :data:`PARAMS_FILE`, else the parameters its node recorded (as replay takes a
    ``--params-file`` and the recorded ones)."""
    recorded = log_parameters(files)
    own = folder / PARAMS_FILE
    if own.is_file():
        try:
            config = load_config(str(own))
        except ReplayError as err:
            raise FleetError(str(err)) from None
        same = None if recorded is None else config_hash(config) == recorded[0]
        return config, same is not False, str(own)
    if recorded is None:
        raise FleetError(
            f'{folder}: no {PARAMS_FILE} and no catenary_monitor parameters recorded in '
            'its log (they name the topics and the lines)'
        )
    try:
        return config_from_params(recorded[1]), True, 'recorded in the log'
    except ConfigError as err:
        raise FleetError(f'{folder}: the parameters recorded in the log are invalid: {err}')


def plan_dock(
    folder: Path, serial: bool = False, columns: tuple[str, ...] = MESSAGE_COLUMNS
) -> DockPlan:
    """The dock in ``folder`` (its name: the folder's): its ``*.mcap`` files in time order, a
    piece per file (``serial``, or files without a known first stamp: one piece); ``columns``
    those of its messages dataset (:func:`.fleet_dataset.dataset_columns`). Raises
    :class:`FleetError`."""
    folder = Path(folder).absolute()  # the workers may run elsewhere: absolute paths
    if not folder.is_dir():
        raise FleetError(f'{folder}: not a folder')
    candidates = sorted(folder.glob('*.mcap'))
    refused = [why for why in map(not_mcap, candidates) if why]
    paths = [p for p in candidates if not_mcap(p) is None]
    if not paths:
        raise FleetError(f'{folder}: no MCAP file' + (f' ({refused[0]})' if refused else ''))
    config, follow, source = dock_config(folder, paths)
    firsts = [first_log_time(p) for p in paths]
    if all(f is not None for f in firsts):
        order = sorted(range(len(paths)), key=lambda i: (firsts[i], i))
        paths, firsts = [paths[i] for i in order], [firsts[i] for i in order]
    else:
        serial = True
    if serial or len(paths) == 1:
        pieces: tuple[tuple[int, ...], ...] = (tuple(range(len(paths))),)
    else:
        pieces = tuple((i,) for i in range(len(paths)))
    return DockPlan(
        name=dock_name(folder),
        folder=str(folder),
        files=tuple(str(p) for p in paths),
        identity=tuple(_identity(p) for p in paths),
        pieces=pieces,
        config=config,
        follow_log=follow,
        params_source=source,
        refused=tuple(refused),
        columns=tuple(columns),
    )


@dataclass
class Carry:
    """What a dock's chain hands from one piece to the next."""

    dock: str
    task: int = -1  # the newest piece done
    digest: str = ''  # its DockPlan.digest
    stream: Optional[StreamState] = None  # the core goes on in it
    tally: Optional[Tally] = None
    daily: Optional[DailyExtremes] = None
    last_ns: Optional[int] = None  # the newest stamp replayed
    messages: int = 0  # input messages replayed
    rows: int = 0  # message rows written
    notes: list[str] = field(default_factory=list)  # damage and skipped files, a line each
    piece_messages: int = 0  # the newest piece's input messages (for progress)


def _checkpoint(root: Path, dock: str, task: int) -> Path:
    return root / '_fleet' / f'dock={dock}' / f'task-{task:06d}.pkl'


def _write_atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f'.{path.name}.{uuid.uuid4().hex[:8]}')
    with open(tmp, 'wb') as f:
        f.write(data)
    os.replace(tmp, path)


def load_checkpoint(root: Path, plan: DockPlan, task: int) -> Optional[Carry]:
    """Piece ``task``'s carry when its checkpoint is there and still holds, else None."""
    path = _checkpoint(root, plan.name, task)
    digest = plan.digest(task)
    side = path.with_suffix('.json')
    try:
        if json.loads(side.read_text()).get('digest') != digest:
            return None
        with open(path, 'rb') as f:
            carry = pickle.load(f)  # the results folder is trusted as the program is
    except (OSError, ValueError, EOFError, pickle.UnpicklingError, AttributeError):
        return None
    return carry if isinstance(carry, Carry) and carry.digest == digest else None


def resume_point(root: Path, plan: DockPlan) -> int:
    """The first piece to do: every piece before it has a checkpoint that still holds (read
    from the small ``.json`` beside each)."""
    for task in range(len(plan.pieces)):
        side = _checkpoint(root, plan.name, task).with_suffix('.json')
        try:
            if json.loads(side.read_text()).get('digest') != plan.digest(task):
                return task
        except (OSError, ValueError):
            return task
    return len(plan.pieces)


def forget_from(root: Path, plan: DockPlan, task: int) -> None:
    """Remove the checkpoints of pieces ``task`` and later (they are done again)."""
    folder = root / '_fleet' / f'dock={plan.name}'
    for path in folder.glob('task-*.*'):
        try:
            k = int(path.stem.split('-', 1)[1])
        except ValueError:
            continue
        if k >= task:
            path.unlink(missing_ok=True)


def one_core() -> None:
    """A worker runs one task at a time on one core: no read-ahead thread, one kernel
    thread (N workers use N cores); the memory its windows free kept for the next
    (:func:`keep_freed_memory`)."""
    mcap_read.READ_AHEAD = 0
    if fused_kernel.AVAILABLE:
        fused_kernel.set_threads(1)
    keep_freed_memory()


#: The messages of a piece's windows: twice the ``replay`` command's window (``WINDOW_MESSAGES``
#: of :mod:`catenary_monitor.replay.driver`), so that a node's file of 200 000 messages is one
#: window, not one of 131 072 and a tail: the replay's per-window work (every line's alarm
#: series, bounds, picks) paid once per file; the pieces of 4 docks of 4 such files took
#: 4.19-4.35 CPU s against 4.79-5.07 in one process (in turn, at a load of 5), the whole
#: ``fleet`` command 4 % less CPU quiet; a stream of 800 000 messages in one piece 5 % less. A
#: worker's peak memory 43 MB more (265 MB where it was 222, in one process).
PIECE_WINDOW = 1 << 18


#: What a worker's C heap keeps of the memory freed (B): a window's rows (38 columns of
#: 100 000 values, 30 MB) and the replay's own arrays are freed window after window; glibc
#: gave them back to the system (arrays of a MB and more are mapped apart, and a heap's free
#: top above twice the adaptive threshold is trimmed), and the next window faulted the same
#: pages in again: the rows' gather took 40 ms per 200 000 rows where it takes 17 with them
#: kept. A worker's memory thus stays at its peak (a few hundred MB) between windows.
KEEP_FREED = 256 << 20
_KEPT: list[bool] = []


def keep_freed_memory() -> None:
    """glibc's ``mallopt``: arrays up to 32 MB from the heap, its free top kept up to
    :data:`KEEP_FREED` (once per process; nothing elsewhere)."""
    if _KEPT or not sys.platform.startswith('linux'):
        return
    _KEPT.append(True)
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc (musl has it as a no-op)
        return
    mallopt(-1, KEEP_FREED)  # M_TRIM_THRESHOLD
    mallopt(-3, 32 << 20)  # M_MMAP_THRESHOLD (its largest)


class _PieceSink:
    """Takes a piece's windows: the tally, the daily extremes, the message parts; checks
    that the piece follows the one before it in time."""

    def __init__(self, carry: Carry, writer: PartWriter, names: tuple[str, ...]) -> None:
        self.carry, self.writer, self.names = carry, writer, names
        self.after = carry.last_ns

    def __call__(self, result: Any, window: Any) -> None:
        stamps = [c[0] for c in (*window.tensions, window.depth) if len(c[0])]
        stamps += [window.ticks] if len(window.ticks) else []
        stamps += [np.array([e.stamp_ns for e in result.events], np.int64)]
        stamps = [s for s in stamps if len(s)]
        if stamps:
            lo = min(int(s.min()) for s in stamps)
            hi = max(int(s.max()) for s in stamps)
            if self.after is not None and lo <= self.after:
                raise Restart(
                    f'files overlap in time (a message at {lo} ns, the file before ends at '
                    f'{self.after} ns)'
                )
            self.carry.last_ns = hi if self.carry.last_ns is None else max(hi, self.carry.last_ns)
        assert self.carry.tally is not None and self.carry.daily is not None
        self.carry.tally.add(result)
        columns = window_columns(result, self.names)
        self.carry.daily.add(columns)
        self.writer.add(message_table(columns, self.names))


def _damage_notes(report: ReadReport, where: str) -> list[str]:
    notes = [f'{f.path}: not finished by its writer (no summary; killed?) [{where}]'
             for f in report.files if not f.finished]  # fmt: skip
    for s in report.skips:
        lost = '' if s.messages_lost is None else f', {s.messages_lost} messages lost'
        notes.append(f'{s.path} @ byte {s.offset}: {s.kind}: {s.reason}{lost} [{where}]')
    return notes


def _next_carry(before: Carry) -> Carry:
    """A copy of ``before`` for the next piece to change (``before`` may be another task's
    result: never changed): its tally, daily extremes and notes copied; its stream state
    shared, as :func:`~catenary_monitor.replay.driver.stream` copies the state it resumes (a
    deep copy of it here too took 5 % of a piece)."""
    carry = copy.copy(before)
    carry.tally, carry.daily = copy.deepcopy((before.tally, before.daily))
    carry.notes = list(before.notes)
    return carry


def run_piece(plan: DockPlan, task: int, before: Any, root: str) -> Carry:
    """Replay piece ``task`` of ``plan`` after ``before`` (the previous piece's
    :class:`Carry`, ``('checkpoint', K)`` to load piece K's, or None for the first piece);
    write its message parts under ``root``; return the carry for the next piece. Raises
    :class:`PieceRestart` when the log cannot be replayed in pieces."""
    out = Path(root)
    done = load_checkpoint(out, plan, task)
    if done is not None:
        return done
    if isinstance(before, tuple):
        loaded = load_checkpoint(out, plan, before[1])
        if loaded is None:
            raise PieceRestart(f'{plan.name}: the checkpoint of task {before[1]} is gone')
        before = loaded
    if before is None:
        names = [line.name for line in plan.config.lines]
        before = Carry(plan.name, tally=Tally(names), daily=DailyExtremes(names))
    one_core()
    carry = _next_carry(before)
    files = [Path(plan.files[i]) for i in plan.pieces[task]]
    where = f'task {task} of dock {plan.name}'
    writer = PartWriter(out, plan.name, task)
    report = ReadReport()
    state: Optional[StreamState]
    try:
        state = _stream_piece(plan, task, carry, writer, files, report)
    except McapReadError as err:
        writer.abandon()
        if plan.serial or len(plan.pieces) == 1:
            raise FleetError(f'{plan.name}: {err}') from None
        carry = _next_carry(before)
        carry.notes.append(f'{files[0]}: skipped ({where}): {err}')
        state = carry.stream
        report = ReadReport()
    except BaseException:
        writer.abandon()
        raise
    else:
        writer.commit()
        carry.notes += _damage_notes(report, where)
    carry.stream, carry.task, carry.digest = state, task, plan.digest(task)
    carry.piece_messages = sum(report.messages.values())
    carry.messages += carry.piece_messages
    carry.rows += writer.rows
    path = _checkpoint(out, plan.name, task)
    _write_atomic(path, pickle.dumps(carry, protocol=pickle.HIGHEST_PROTOCOL))
    _write_atomic(path.with_suffix('.json'), json.dumps({'digest': carry.digest}).encode())
    return carry


def _stream_piece(
    plan: DockPlan,
    task: int,
    carry: Carry,
    writer: PartWriter,
    files: list[Path],
    report: ReadReport,
) -> StreamState:
    """The stream of one piece into the sink (the dock as one task: as ``replay`` does, in
    one window when it cannot be streamed)."""
    window: Optional[int] = PIECE_WINDOW
    goes_on = task < len(plan.pieces) - 1
    # The next piece's first stamp: whether this piece's last sample is a bad stamp.
    next_ns = first_log_time(Path(plan.files[plan.pieces[task + 1][0]])) if goes_on else None
    while True:
        sink = _PieceSink(carry, writer, plan.columns)
        try:
            return stream(
                files,
                plan.config,
                sink,
                follow_log=plan.follow_log,
                window_messages=window,
                report=report,
                resume=carry.stream,
                goes_on=goes_on,
                next_ns=next_ns,
            )
        except Restart as err:
            if len(plan.pieces) > 1:
                raise PieceRestart(f'{plan.name}: {err}') from None
            if window is None:
                raise FleetError(f'{plan.name}: cannot replay: {err}') from None
            window = None
            names = [line.name for line in plan.config.lines]
            carry.tally, carry.daily, carry.last_ns = Tally(names), DailyExtremes(names), None
            writer.abandon()
            report.files.clear()
            report.skips.clear()
            report.messages.clear()
            report.missing_topics.clear()
        except ReplayError as err:
            raise FleetError(f'{plan.name}: {err}') from None


def _episodes(dock: str, tally: Tally, end_ns: int) -> list[dict[str, Any]]:
    """Every alarm episode of the dock, as the replay summary lists them, with ``component``
    (``line`` or the component: tide, sensors, alarms, dock, ...) and ``name``."""
    rows: list[dict[str, Any]] = []
    for line in tally.lines:
        for e in line.as_dict(end_ns)['episodes']:
            rows.append({'component': 'line', 'name': line.name, **e})
    empty = np.zeros(0)
    for name, transitions in tally.components.items():
        result = LineResult('', empty, empty, {}, empty, empty, empty, empty, empty, transitions)
        for e in result.episodes(end_ns):
            rows.append({'component': name, 'name': name, **e})
    return rows


def finish_dock(plan: DockPlan, carry: Carry, root: str) -> dict[str, Any]:
    """Write the dock's ``episodes`` and ``daily`` datasets from the chain's end; returns the
    dock's summary (counts, the closest approach to uplift, the damage notes)."""
    out = Path(root)
    tally, daily = carry.tally, carry.daily
    assert tally is not None and daily is not None
    start, end = tally.start_ns or 0, tally.end_ns or 0
    episodes = _episodes(plan.name, tally, end)
    days = np.array(
        [str(np.datetime64(int(e['start'] * 1e9), 'ns').astype('datetime64[D]'))
         for e in episodes], dtype=object)  # fmt: skip
    seconds = {}
    for k, line in enumerate(tally.lines):
        for day, spent in level_seconds(line.transitions, start * 1e-9, end * 1e-9).items():
            seconds[(k, day)] = spent
    tables = {
        'episodes': (episodes_table(episodes), days),
        'daily': (daily.table(seconds), None),
    }
    replace_dock_tables(out, plan.name, tables)
    summary = {
        'dock': plan.name,
        'folder': plan.folder,
        'parameters': plan.params_source,
        'files': len(plan.files),
        'tasks': len(plan.pieces),
        'one_task': len(plan.pieces) == 1,
        'messages': carry.messages,
        'rows': carry.rows,
        'start': start * 1e-9,
        'end': end * 1e-9,
        'episodes': len(episodes),
        'closest': _closest(daily),
        'damage': [*plan.refused, *carry.notes, *_bad_stamps(carry.stream)],
    }
    _write_atomic(
        out / '_fleet' / f'dock={plan.name}' / 'done.json',
        json.dumps({'digest': plan.digest(len(plan.pieces) - 1), 'summary': summary}).encode(),
    )
    return summary


def _bad_stamps(state: Optional[StreamState]) -> list[str]:
    """The line on the samples the dock's replay left out as bad stamps (none: [])."""
    figures = {} if state is None else stamp_figures(state)
    return stamp_lines({'bad_stamps': figures.get('bad_stamps')})


def _closest(daily: DailyExtremes) -> Optional[dict[str, Any]]:
    """The dock's smallest anchor margin: line, value (m), time (s)."""
    best = None
    for (k, _), cell in daily.cells.items():
        value = cell.get('anchor_margin_min')
        if value is None:
            continue
        key = (value, cell['anchor_margin_min_time'])
        if best is None or key < best[0]:
            best = (key, k)
    if best is None:
        return None
    (value, t), k = best
    return {'line': daily.lines[k], 'anchor_margin': value, 'time': t * 1e-9}


def finished_summary(root: Path, plan: DockPlan) -> Optional[dict[str, Any]]:
    """The dock's summary when a finished run left it and nothing it depends on changed."""
    try:
        done = json.loads((root / '_fleet' / f'dock={plan.name}' / 'done.json').read_text())
    except (OSError, ValueError):
        return None
    if done.get('digest') != plan.digest(len(plan.pieces) - 1):
        return None
    return done.get('summary')
