"""``catenary-monitor fleet``: replay many docks' log folders on Dask, results as a dataset.

::

    catenary-monitor fleet DIR [DIR ...] --out RESULTS [--workers N | --scheduler ADDRESS]
        [--columns LIST] [--json] [--quiet | --progress]

Each DIR is a dock (its name: the folder's), replayed with the parameters its node recorded,
or with the folder's ``catenary_monitor.yaml`` when there is one; the results equal a serial
``catenary-monitor replay DIR`` of each folder. RESULTS holds Parquet datasets partitioned
``dock=NAME/date=YYYY-MM-DD``: ``messages`` (the replay CSV's rows, every column),
``episodes`` and ``daily`` (docs/fleet.md); ``--columns`` keeps some of the messages' columns
(``time`` and ``line`` always). Needs the ``fleet`` extra (dask[distributed],
pyarrow).

Exit status: 0 every dock replayed (damaged input is named and skipped, as replay does); 2 a
dock could not be replayed (one line each: no log, no parameters, bad options), the others are
written; 1 unexpected failure.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import sys
from pathlib import Path
from typing import Any

from catenary_monitor.cli.replay import count_arg
from catenary_monitor.cli.status_line import StatusLine
from catenary_monitor.cli.table import format_table

__all__ = ['register', 'cmd_fleet']


class _ProgressLine:
    """Tasks done and messages per second on stderr (in place on a terminal)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.line = StatusLine('fleet: ')

    def __call__(self, state: Any) -> None:
        for note in state.notes:
            if self.enabled:
                self.line.show(note)
                self.line.end()
        if not (self.enabled and self.line.due()):
            return
        rate = state.messages / state.elapsed if state.elapsed > 0 else 0.0
        left = state.tasks_total - state.tasks_done
        eta = (
            f', ETA {state.elapsed * left / state.tasks_done:.0f} s'
            if state.tasks_done and left
            else ''
        )
        self.line.show(
            f'{state.tasks_done}/{state.tasks_total} tasks, {state.messages / 1e6:.2f} M '
            f'messages, {rate / 1e6:.2f} M msg/s ({state.elapsed:.0f} s{eta})'
        )

    def done(self, run: Any) -> None:
        if self.enabled:
            self.line.show(
                f'done: {run.tasks_run} tasks on {run.workers} worker(s) in {run.seconds:.1f} s'
            )
            self.line.end()


def _utc(t: Any) -> str:
    if t is None or not math.isfinite(t):
        return '-'
    return _dt.datetime.fromtimestamp(t, _dt.timezone.utc).strftime('%Y-%m-%d %H:%M:%S')


def _table(run: Any) -> str:
    rows: list[tuple[str, ...]] = []
    for name, d in sorted(run.docks.items()):
        closest = d.get('closest')
        where = (
            '-'
            if not closest
            else f'{closest["anchor_margin"]:+.2f} m {closest["line"]} {_utc(closest["time"])}'
        )
        counts = (d['files'], d['tasks'], d['messages'], d['rows'], d['episodes'])
        rows.append((name, *map(str, counts), str(len(d['damage'])), where))
    header = ('dock', 'files', 'tasks', 'messages', 'rows', 'episodes', 'damaged', 'closest')
    out = [format_table(rows, header)] if rows else []
    damage = [(name, line) for name, d in sorted(run.docks.items()) for line in d['damage']]
    if damage:
        out += ['', 'DAMAGED INPUT: named and skipped, everything readable was used:']
        out += [f'  {name}: {line}' for name, line in damage]
    if run.failed:
        out += ['', 'NOT REPLAYED:'] + [f'  {name}: {why}' for name, why in run.failed.items()]
    reused = f', {run.tasks_reused} done by an earlier run' if run.tasks_reused else ''
    fresh = f', up to date: {" ".join(run.docks_up_to_date)}' if run.docks_up_to_date else ''
    out += [
        '',
        f'{run.tasks_run} tasks on {run.workers} worker(s) in {run.seconds:.1f} s (cluster '
        f'start {run.startup_seconds:.1f} s){reused}{fresh}'
        + (f'; {run.workers_lost} worker(s) lost, their tasks done again' if run.workers_lost
           else ''),  # fmt: skip
    ]
    return '\n'.join(out)


def cmd_fleet(args: argparse.Namespace) -> int:
    """Entry point of ``catenary-monitor fleet``."""
    try:
        from catenary_monitor.replay.fleet_cluster import run_fleet
        from catenary_monitor.replay.fleet_dataset import dataset_columns
    except ImportError as err:
        print(
            f'catenary-monitor fleet: needs the fleet extra ({err.name} is missing): '
            "pip install 'catenary_monitor[fleet]'",
            file=sys.stderr,
        )
        return 2
    out = Path(args.out)
    try:
        out.resolve()
    except (RuntimeError, OSError) as err:  # a symlink loop (RuntimeError before 3.13)
        why = getattr(err, 'strerror', None) or 'a symlink loop'
        print(f'catenary-monitor fleet: --out {out}: {why}', file=sys.stderr)
        return 2
    if out.exists() and not out.is_dir():
        print(f'catenary-monitor fleet: --out {out} is a file, not a folder', file=sys.stderr)
        return 2
    columns = None
    if args.columns and args.columns != 'all':
        columns = [t.strip() for t in args.columns.split(',') if t.strip()]
        try:
            dataset_columns(columns)
        except ValueError as err:
            print(f'catenary-monitor fleet: --columns: {err}', file=sys.stderr)
            return 2
    progress = _ProgressLine(args.progress or not args.quiet)
    run = run_fleet(
        [Path(d) for d in args.dirs],
        out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=progress,
        columns=columns,
    )
    progress.done(run)
    for name, why in run.failed.items():
        print(f'catenary-monitor fleet: {why}', file=sys.stderr)
    if args.json:
        print(json.dumps({
            'results': str(out),
            'docks': run.docks,
            'failed': run.failed,
            'tasks_run': run.tasks_run,
            'tasks_reused': run.tasks_reused,
            'up_to_date': run.docks_up_to_date,
            'workers': run.workers,
            'workers_lost': run.workers_lost,
            'startup_seconds': round(run.startup_seconds, 3),
            'seconds': round(run.seconds, 3),
            'worker_cpu_seconds': round(run.worker_cpu_seconds, 3),
            'messages': run.messages,
        }, allow_nan=False, default=lambda v: None))  # fmt: skip
    else:
        print(_table(run))
    return 2 if run.failed else 0


def register(sub: Any) -> None:
    """Add the ``fleet`` sub-command to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'fleet',
        help='replay many docks\' log folders on Dask; results as a Parquet dataset',
        description='Replay each dock folder (the results of a serial replay of each) as tasks '
        'on Dask distributed and write RESULTS/messages, RESULTS/episodes and RESULTS/daily as '
        'Parquet datasets partitioned dock=NAME/date=YYYY-MM-DD (docs/fleet.md). A run started '
        'again resumes where the last one stopped.',
    )
    p.add_argument(
        'dirs', nargs='+', metavar='DIR', help='a dock\'s log folder (its name: the dock)'
    )
    p.add_argument('--out', required=True, metavar='RESULTS', help='the results folder')
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        '--workers',
        type=count_arg,
        metavar='N',
        help='a local cluster of N one-core worker processes (default: the usable CPUs)',
    )
    where.add_argument(
        '--scheduler',
        metavar='ADDRESS',
        help='an existing Dask cluster (tcp://host:8786); its workers must see the folders and '
        'RESULTS at the same paths',
    )
    p.add_argument(
        '--columns',
        metavar='LIST',
        default='all',
        help='the messages dataset\'s columns: comma-separated names of replay --csv-columns '
        '(time and line always), or "all" (default)',
    )
    p.add_argument('--json', action='store_true', help='print the run as one JSON object')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.add_argument('--progress', action='store_true', help='progress on stderr even with --quiet')
    p.set_defaults(func=cmd_fleet)
