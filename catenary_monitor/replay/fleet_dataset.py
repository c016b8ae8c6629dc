"""The fleet's results as Parquet datasets (pyarrow), partitioned hive style by dock and day.

``RESULTS/messages/dock=NAME/date=YYYY-MM-DD/part-K.parquet``: the replay CSV's rows
(:func:`catenary_monitor.replay.outputs.message_columns`, every ``--csv-columns all``
column; ``time`` int64 ns since the epoch, values float64 in SI at full precision, ``status``
the solver code as an integer, the words as strings); K is the task that wrote the part, so a
task done again replaces its own files and never adds rows. An unknown value (NaN in the CSV)
is null, so that SQL aggregates skip it (a NaN sorts above every number there).
``RESULTS/episodes`` (the alarm episodes as the replay summary lists them, by the day they
started) and ``RESULTS/daily`` (per line and UTC day: extremes with their times, and the
seconds at each level) are written once per dock when its last task is done.

Every file is written under ``RESULTS/_fleet/tmp`` (in a folder named :data:`TMP_PREFIX`...)
and renamed into place (atomic on one file system), so a reader or a killed task never sees
half a file. Names starting with ``_`` or ``.`` are not part of the datasets (pyarrow and DuckDB
globs of ``*.parquet`` skip them). Nothing the fleet did not write is ever deleted: it replaces
and removes only its own file names (``part-K.parquet``), and clears only its own temporary
folders; a user's file in ``RESULTS`` (``episodes/dock=D/notes.txt``, ``_fleet/tmp/x``) stays.
"""

from __future__ import annotations

import os
import shutil
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from catenary_monitor.core.rules.level import Level
from catenary_monitor.replay.outputs import CSV_ALL, message_columns

__all__ = [
    'DAILY_FIELDS',
    'DailyExtremes',
    'KEY_COLUMNS',
    'MESSAGE_COLUMNS',
    'PartWriter',
    'TMP_PREFIX',
    'clear_tmp',
    'dataset_columns',
    'day_of',
    'episodes_table',
    'level_seconds',
    'message_table',
    'remove_parts',
    'replace_dock_tables',
    'window_columns',
]

DAY_NS = 86_400 * 10**9
#: The fleet's temporary folders under ``RESULTS/_fleet/tmp`` (no other entry there is its).
TMP_PREFIX = 'fleet-tmp-'


def _tmp_dir(root: Path, what: str) -> Path:
    return root / '_fleet' / 'tmp' / f'{TMP_PREFIX}{what}-{uuid.uuid4().hex[:8]}'


def clear_tmp(root: Path) -> None:
    """Remove the fleet's temporary folders (what killed tasks left), nothing else; then
    ``_fleet/tmp`` itself when that leaves it empty."""
    tmp = root / '_fleet' / 'tmp'
    try:
        entries = list(os.scandir(tmp))
    except OSError:
        return
    for entry in entries:
        if entry.name.startswith(TMP_PREFIX) and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
    try:
        tmp.rmdir()
    except OSError:
        pass


#: Every column of the messages dataset: the replay CSV's, all of them.
MESSAGE_COLUMNS = tuple(name for name, _ in CSV_ALL)

#: The daily table's per-line extremes: (column, message field, 'min' or 'max', with its time).
DAILY_FIELDS: tuple[tuple[str, str, str, bool], ...] = (
    ('top_tension_max', 'top_tension', 'max', True),
    ('uplift_force_max', 'uplift_force', 'max', True),
    ('anchor_margin_min', 'anchor_margin', 'min', True),
    ('tide_margin_min', 'tide_margin', 'min', True),
    ('load_margin_min', 'load_margin', 'min', False),
    ('safety_factor_min', 'safety_factor', 'min', False),
    ('time_to_uplift_min', 'time_to_uplift', 'min', False),
    ('uplift_force_upper_max', 'uplift_force_upper', 'max', False),
    ('anchor_margin_lower_min', 'anchor_margin_lower', 'min', False),
    ('drag_margin_min', 'drag_margin', 'min', False),
    ('depth_min', 'depth', 'min', False),
    ('depth_max', 'depth', 'max', False),
    ('fatigue_damage_max', 'fatigue_damage', 'max', False),
)
#: The message parts' compression. On 200 000 rows of the paper dock a part took 0.057 CPU s
#: and 17.8 MB with LZ4_RAW (DuckDB and pyarrow read it), 0.082-0.086 s and 14.8 MB with zstd
#: (level 1; its fast levels -1 to -7: 0.072-0.076 s, 15.7-17.0 MB), 0.051 s and 31 MB
#: without: a fleet task is CPU-bound, and the part is a fifth of it.
COMPRESSION = 'lz4_raw'
#: The columns whose row groups carry min/max statistics (a reader skips row groups by time or
#: line with them); on every float column they cost an eighth of the Parquet writing.
STATISTICS = ['time', 'line']
#: The message parts' pages: one data page per column of a window's row group (up to 2^18
#: rows, 2 MB of float64), values handed to the encoder 65 536 at a time. Arrow's defaults
#: (pages of 20 000 rows or 1 MB, batches of 1 024) cut a window of 200 000 rows into 10 pages
#: per column, each compressed and headed apart: that part took 52.8 ms (median of 11, in
#: turn), 39.6 with these (the same bytes within 0.5 %, the same values). A reader reads a
#: column's row group as one page (no page index is written).
PAGES = {
    'data_page_size': 8 << 20,
    'max_rows_per_page': 1 << 18,
    'write_batch_size': 1 << 16,
}
_LEVEL_COLUMNS = [(f'seconds_{lv.name.lower()}', lv) for lv in Level]


def day_of(t_ns: np.ndarray) -> np.ndarray:
    """UTC day numbers (days since 1970-01-01) of times in ns."""
    return np.floor_divide(np.asarray(t_ns, np.int64), DAY_NS)


def _date(day: int) -> str:
    return str(np.datetime64(int(day), 'D'))


#: The columns every messages dataset has, whatever ``fleet --columns`` names: the row's time
#: (its date partition) and line.
KEY_COLUMNS = ('time', 'line')
#: The columns the daily table is computed from.
DAILY_SOURCES = tuple(sorted({source for _, source, _, _ in DAILY_FIELDS}))


def dataset_columns(names: Optional[Sequence[str]] = None) -> tuple[str, ...]:
    """The messages dataset's columns (in :data:`MESSAGE_COLUMNS` order): ``names`` and the
    :data:`KEY_COLUMNS`; every column when ``names`` is None. Raises ValueError for a name
    that is not a column."""
    if names is None:
        return MESSAGE_COLUMNS
    unknown = [n for n in names if n not in MESSAGE_COLUMNS]
    if unknown:
        raise ValueError(
            f'unknown column {unknown[0]!r}; known: ' + ', '.join(MESSAGE_COLUMNS)
        )
    wanted = set(names) | set(KEY_COLUMNS)
    return tuple(n for n in MESSAGE_COLUMNS if n in wanted)


def window_columns(result: Any, names: Sequence[str] = MESSAGE_COLUMNS) -> dict[str, Any]:
    """One window's rows (:func:`message_columns`): the columns ``names`` and those the daily
    table needs."""
    if len(names) == len(MESSAGE_COLUMNS):
        return message_columns(result, MESSAGE_COLUMNS)
    return message_columns(result, sorted({*names, *KEY_COLUMNS, *DAILY_SOURCES}))


def message_table(
    columns: dict[str, Any], names: Sequence[str] = MESSAGE_COLUMNS
) -> pa.Table:
    """The columns ``names`` of one window's rows (:func:`window_columns`) as an Arrow
    table."""
    arrays = {}
    for name in names:
        column = columns[name]
        if name == 'status':
            codes, labels = column
            arrays[name] = pa.array(np.asarray([int(x) for x in labels], np.int64)[codes])
        elif isinstance(column, tuple):
            codes, labels = column
            arrays[name] = pa.DictionaryArray.from_arrays(
                pa.array(np.asarray(codes, np.int32)), pa.array(labels, pa.string())
            )
        elif name == 'time':
            arrays[name] = pa.array(column, pa.int64())
        else:  # unknown (NaN) is null: SQL aggregates skip it (NaN sorts above +inf)
            arrays[name] = _nan_null(np.asarray(column, np.float64))
    return pa.table(arrays)


def _nan_null(values: np.ndarray) -> pa.Array:
    """A float64 array with NaN as null, over ``values``' own memory (the validity bitmap
    packed from ``isnan``: half the CPU of ``pa.array(from_pandas=True)``, the same array)."""
    values = np.ascontiguousarray(values)
    nan = np.isnan(values)
    nulls = int(nan.sum())
    if not nulls:
        return pa.array(values, pa.float64())
    valid = np.packbits(~nan, bitorder='little')
    buffers = [pa.py_buffer(valid), pa.py_buffer(values)]
    return pa.Array.from_buffers(pa.float64(), len(values), buffers, null_count=nulls)


def _atomic_place(tmp: Path, final: Path) -> None:
    final.parent.mkdir(parents=True, exist_ok=True)
    os.replace(tmp, final)


class PartWriter:
    """The message parts of one task: a Parquet file per UTC day it touches, a row group per
    window, written under ``tmp`` and moved into ``root/messages`` by :meth:`commit`. Only
    the newest day's file is open (the rows come in time order), however many days a task
    spans."""

    def __init__(self, root: Path, dock: str, task: int) -> None:
        self.root, self.dock, self.task = root, dock, task
        self.tmp = _tmp_dir(root, f'{dock}-{task:06d}')
        self.writers: dict[int, tuple[Path, Any]] = {}
        self.rows = 0

    def add(self, table: pa.Table) -> None:
        """Append one window's rows (in time order) to the files of their days."""
        if not table.num_rows:
            return
        days = day_of(table.column('time').to_numpy())
        cuts = np.flatnonzero(np.diff(days)) + 1
        for lo, hi in zip([0, *cuts.tolist()], [*cuts.tolist(), len(days)]):
            day = int(days[lo])
            if day not in self.writers:
                self.tmp.mkdir(parents=True, exist_ok=True)
                path = self.tmp / f'{_date(day)}.parquet'
                words = [f.name for f in table.schema if pa.types.is_dictionary(f.type)]
                writer = pq.ParquetWriter(
                    path,
                    table.schema,
                    use_dictionary=words,
                    compression=COMPRESSION,
                    write_statistics=STATISTICS,
                    **PAGES,
                )  # dictionaries for the words only: on the floats they cost 7 times the time
                self.writers[day] = (path, writer)
            self.writers[day][1].write_table(table.slice(lo, hi - lo))
        self.rows += table.num_rows
        newest = int(days[-1])
        for day, (path, writer) in list(self.writers.items()):
            if day < newest and writer is not None:  # the rows come in time order: done
                writer.close()
                self.writers[day] = (path, None)

    def commit(self) -> list[str]:
        """Close the files and move each to ``messages/dock=D/date=Y/part-K.parquet``; returns
        the dates written."""
        dates = []
        for day, (path, writer) in sorted(self.writers.items()):
            if writer is not None:
                writer.close()
            date = _date(day)
            _atomic_place(path, self.final(date))
            dates.append(date)
        self.writers = {}
        shutil.rmtree(self.tmp, ignore_errors=True)
        return dates

    def final(self, date: str) -> Path:
        return (
            self.root / 'messages' / f'dock={self.dock}' / f'date={date}'
            / f'part-{self.task:06d}.parquet'
        )  # fmt: skip

    def abandon(self) -> None:
        """Drop what was written (the task is skipped or done again)."""
        for _, writer in self.writers.values():
            if writer is not None:
                writer.close()
        self.writers, self.rows = {}, 0
        shutil.rmtree(self.tmp, ignore_errors=True)


def remove_parts(root: Path, dock: str, first_task: int) -> int:
    """Remove the dock's message parts written by tasks ``first_task`` and later (they are
    done again); returns how many."""
    n = 0
    base = root / 'messages' / f'dock={dock}'
    for path in base.glob('date=*/part-*.parquet'):
        try:
            task = int(path.stem.split('-', 1)[1])
        except ValueError:
            continue
        if task >= first_task:
            path.unlink(missing_ok=True)
            n += 1
    for folder in base.glob('date=*'):
        try:
            folder.rmdir()  # only when empty
        except OSError:
            pass
    return n


@dataclass
class DailyExtremes:
    """Per line and UTC day, the extremes of the message rows (and when the first was
    reached), gathered window by window: the same figures as over all rows at once."""

    lines: list[str]
    #: (line index, day) -> {column: value}, {column + '_time': ns}, 'messages': count
    cells: dict[tuple[int, int], dict[str, Any]] = field(default_factory=dict)

    def add(self, columns: dict[str, Any]) -> None:
        """Take one window's :func:`message_columns` (all columns): the rows sorted once by
        (line, day), each field's extremes by group at once (``fmin``/``fmax`` skip NaN)."""
        t = columns['time']
        if not len(t):
            return
        line = np.asarray(columns['line'][0], np.int64)
        days = day_of(t)
        key = line * (int(days.max() - days.min()) + 1) + (days - days.min())
        if int(key.max()) < 1 << 16:  # numpy's stable sort of 16-bit keys is a radix sort
            key = key.astype(np.uint16)
        order = np.argsort(key, kind='stable')  # within a cell: time order
        key = np.take(key, order)
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        ends = np.r_[starts[1:], len(key)]
        cells = []
        for lo, hi in zip(starts.tolist(), ends.tolist()):
            i = int(order[lo])
            cell = self.cells.setdefault((int(line[i]), int(days[i])), {'messages': 0})
            cell['messages'] += hi - lo
            cells.append(cell)
        for column, source, kind, timed in DAILY_FIELDS:
            values = np.take(columns[source], order)
            reduce = np.fmin if kind == 'min' else np.fmax
            best = reduce.reduceat(values, starts)  # NaN only where the cell's all are
            first = None
            if timed:  # the first row of each cell at its extreme
                hits = np.flatnonzero(values == np.repeat(best, ends - starts))
                at = np.searchsorted(hits, starts).clip(max=len(hits) - 1)  # all-NaN cells: unused
                first = hits[at] if len(hits) else None
            for g, cell in enumerate(cells):
                value = float(best[g])
                if value != value:  # no value in this cell (all unknown)
                    continue
                old = cell.get(column)
                if old is None or (value < old if kind == 'min' else value > old):
                    cell[column] = value
                    if timed:
                        assert first is not None
                        cell[column + '_time'] = int(t[order[first[g]]])

    def table(self, seconds: dict[tuple[int, int], dict[Level, float]]) -> pa.Table:
        """The dock's daily rows (``date`` string, ``line``, ``messages``, the extremes, the
        seconds at each level from ``seconds``), in (date, line) order."""
        keys = sorted(set(self.cells) | set(seconds), key=lambda key: (key[1], key[0]))
        cols: dict[str, list[Any]] = {'date': [], 'line': [], 'messages': []}
        for column, _, _, timed in DAILY_FIELDS:
            cols[column] = []
            if timed:
                cols[column + '_time'] = []
        for name, _ in _LEVEL_COLUMNS:
            cols[name] = []
        for k, day in keys:
            cell = self.cells.get((k, day), {'messages': 0})
            cols['date'].append(_date(day))
            cols['line'].append(self.lines[k])
            cols['messages'].append(cell['messages'])
            for column, _, _, timed in DAILY_FIELDS:
                cols[column].append(cell.get(column))
                if timed:
                    cols[column + '_time'].append(cell.get(column + '_time'))
            spent = seconds.get((k, day), {})
            for name, lv in _LEVEL_COLUMNS:
                cols[name].append(float(spent.get(lv, 0.0)))
        types = {'date': pa.string(), 'line': pa.string(), 'messages': pa.int64()}
        for column, _, _, timed in DAILY_FIELDS:
            types[column] = pa.float64()
            if timed:
                types[column + '_time'] = pa.int64()
        return pa.table({k: pa.array(v, types.get(k, pa.float64())) for k, v in cols.items()})


def level_seconds(
    transitions: Sequence[Any], start_s: float, end_s: float
) -> dict[int, dict[Level, float]]:
    """Seconds spent at each level per UTC day between ``start_s`` and ``end_s`` (s since the
    epoch), from a line's transitions (each says the level before it and after it; before the
    first, the level it left; without any, STALE: blind)."""
    out: dict[int, dict[Level, float]] = {}
    level = transitions[0].old if transitions else Level.STALE
    t = start_s
    for tr in [*transitions, None]:
        stop = end_s if tr is None else min(max(tr.time, start_s), end_s)
        _spread(out, level, t, stop)
        if tr is None:
            break
        t, level = max(t, stop), tr.new
    return out


def _spread(out: dict[int, dict[Level, float]], level: Level, a: float, b: float) -> None:
    """Add [a, b) s at ``level`` to the days it covers."""
    while b > a:
        day = int(a // 86_400)
        edge = min(b, (day + 1) * 86_400.0)
        cell = out.setdefault(day, {})
        cell[level] = cell.get(level, 0.0) + (edge - a)
        a = edge


EPISODE_TYPES = {
    'component': pa.string(),
    'name': pa.string(),
    'start': pa.float64(),
    'end': pa.float64(),
    'duration': pa.float64(),
    'worst': pa.string(),
    'message': pa.string(),
}


def episodes_table(rows: list[dict[str, Any]]) -> pa.Table:
    """Episode rows (``component``, ``name`` and a summary episode's fields) as a table."""
    return pa.table(
        {key: pa.array([r.get(key) for r in rows], kind) for key, kind in EPISODE_TYPES.items()}
    )


def replace_dock_tables(
    root: Path, dock: str, tables: dict[str, tuple[pa.Table, Optional[np.ndarray]]]
) -> None:
    """Write the dock's ``episodes`` and ``daily`` datasets anew: for each, a file per date
    (``dates``: each row's date string, or the table's ``date`` column), each renamed into
    ``NAME/dock=D/date=Y/part-0.parquet``; then the dock's ``part-0.parquet`` of dates no
    longer there are removed (with their folders when that empties them). Anything else in
    those folders is left as it is."""
    for name, (table, dates) in tables.items():
        if dates is None:
            dates = np.asarray(table.column('date').to_pylist(), dtype=object)
            table = table.drop_columns(['date'])
        base = root / name / f'dock={dock}'
        fresh = _tmp_dir(root, f'{name}-{dock}')
        fresh.mkdir(parents=True, exist_ok=True)
        written = set()
        for date in sorted(set(dates.tolist())):
            rows = np.flatnonzero(dates == date)
            part = fresh / f'date={date}.parquet'
            pq.write_table(table.take(pa.array(rows)), part)
            _atomic_place(part, base / f'date={date}' / 'part-0.parquet')
            written.add(f'date={date}')
        for old in base.glob('date=*/part-0.parquet'):
            if old.parent.name not in written:
                old.unlink(missing_ok=True)
                try:
                    old.parent.rmdir()  # only when empty
                except OSError:
                    pass
        shutil.rmtree(fresh, ignore_errors=True)
