"""``catenary-monitor bench-fleet``: the fleet replay on one worker against two, same fleet.

Generates (seeded) ``--docks`` dock folders of ``--files`` rotated node-shaped logs each (the
paper dock's 12 lines at 10 Hz, the tide at 1 Hz, zstd chunks; ``--messages-per-file``; the
folder's ``catenary_monitor.yaml``), then replays the fleet with ``catenary-monitor fleet`` on
a fresh local cluster of 1 worker and of 2 workers (``--workers-list``), each into a fresh
results folder, in the same run. Reports per run the cluster's start (the workers' imports
included) and the replay after it, the replay's messages per second, the speed-up against 1
worker, and checks that every run's messages dataset is identical to the first's (row for
row). From the measured rate per worker it prints what 100 docks x 1 year of 12 lines at 20 Hz
would cost on N workers.

The machines are shared: run it when nothing else is running and read the ratio first.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

__all__ = ['register', 'run']

#: One dock at 12 lines x 20 Hz and its tide at 1 Hz, for a year: the messages.
YEAR_MESSAGES = (12 * 20 + 1) * 86_400 * 365


def generate_fleet(root: Path, docks: int, files: int, per_file: int) -> dict[str, Any]:
    """``docks`` folders of ``files`` consecutive logs each (a storm in the middle of the
    dock's time) and their params files; returns the facts."""
    from catenary_monitor.core.config.parameters import config_to_params, params_file_text
    from catenary_monitor_study.bench_replay import T0_NS, dock_config, generate_log

    config = dock_config(12)
    per_second = len(config.lines) * 10.0 + 1.0
    seconds = per_file / per_second
    facts = {'docks': docks, 'files': docks * files, 'messages': 0, 'bytes': 0}
    for d in range(docks):
        folder = root / f'dock_{d:02d}'
        folder.mkdir(parents=True, exist_ok=True)
        (folder / 'catenary_monitor.yaml').write_text(params_file_text(config_to_params(config)))
        for k in range(files):
            part = generate_log(
                folder / f'catenary_monitor_{k:04d}.mcap',
                per_file,
                config,
                seed=100 * d + k + 1,
                start_ns=T0_NS + int(k * seconds * 1e9),
                storm_at=files * seconds / 2 - k * seconds,
                storm_width=files * seconds / 10,
            )
            facts['messages'] += part['messages']
            facts['bytes'] += part['bytes']
    return facts


def _same_rows(first: Path, other: Path) -> bool:
    """Whether two runs' messages datasets hold the same rows: every part file (one per dock,
    day and task) read back and compared, table equals table (one part in memory at a time)."""
    import pyarrow.parquet as pq

    a = sorted(p.relative_to(first) for p in (first / 'messages').rglob('*.parquet'))
    b = sorted(p.relative_to(other) for p in (other / 'messages').rglob('*.parquet'))
    if a != b:
        return False
    return all(pq.read_table(first / p).equals(pq.read_table(other / p)) for p in a)


def run(
    docks: int = 3,
    files: int = 4,
    per_file: int = 200_000,
    workers_list: tuple[int, ...] = (1, 2),
    keep: Optional[Path] = None,
    repeat: int = 3,
) -> dict[str, Any]:
    """Generate the fleet, replay it ``repeat`` times per worker count (in turn); returns the
    figures (per worker count, the median round)."""
    tmp = Path(keep) if keep else Path(tempfile.mkdtemp(prefix='bench_fleet_'))
    load = os.getloadavg()
    try:
        facts = generate_fleet(tmp / 'docks', docks, files, per_file)
        folders = sorted((tmp / 'docks').iterdir())
        rounds: dict[int, list[dict[str, Any]]] = {n: [] for n in workers_list}
        first = tmp / f'results_{workers_list[0]}_0'
        for k in range(repeat):  # the worker counts in turn: a change of load hits both
            for n in workers_list:
                rounds[n].append(_one_run(folders, tmp / f'results_{n}_{k}', n, first))
        runs = [_median_run(n, rounds[n]) for n in workers_list]
        base = runs[0]['replay_s'] * runs[0]['workers']
        for r in runs:
            r['speedup'] = round(runs[0]['replay_s'] / r['replay_s'], 3)
            r['efficiency'] = round(base / (r['replay_s'] * r['workers']), 3)
        per_cpu = statistics.median(
            x['messages'] / x['worker_cpu_s'] for n in workers_list for x in rounds[n]
        )
        return {
            'fleet': facts,
            'cpus': len(os.sched_getaffinity(0)),
            'load_average': [list(load), list(os.getloadavg())],
            'repeat': repeat,
            'runs': runs,
            'rounds': rounds,
            'per_worker_messages_per_cpu_s': round(per_cpu),
            'year_100_docks': _cost(per_cpu),
        }
    finally:
        if keep is None:
            shutil.rmtree(tmp, ignore_errors=True)


def _one_run(folders: list[Path], results: Path, workers: int, first: Path) -> dict[str, Any]:
    """One fleet run on a fresh local cluster into a fresh folder, compared with the first."""
    from catenary_monitor.replay.fleet_cluster import run_fleet

    shutil.rmtree(results, ignore_errors=True)
    t0 = time.perf_counter()
    fleet = run_fleet(folders, results, workers=workers)
    wall = time.perf_counter() - t0
    if fleet.failed:
        raise RuntimeError(f'fleet failed: {fleet.failed}')
    same = _same_rows(first, results)
    if results != first:
        shutil.rmtree(results, ignore_errors=True)
    return {
        'workers': workers,
        'wall_s': round(wall, 3),
        'startup_s': round(fleet.startup_seconds, 3),
        'replay_s': round(fleet.seconds, 3),
        'worker_cpu_s': round(fleet.worker_cpu_seconds, 3),
        'messages': fleet.messages,
        'messages_per_s': round(fleet.messages / fleet.seconds),
        'identical_to_first': same,
    }


def _median_run(workers: int, rounds: list[dict[str, Any]]) -> dict[str, Any]:
    """The round with the median replay time (and whether every round was identical)."""
    ordered = sorted(rounds, key=lambda r: r['replay_s'])
    out = dict(ordered[(len(ordered) - 1) // 2])
    out['identical_to_first'] = all(r['identical_to_first'] for r in rounds)
    out['replay_s_all'] = [r['replay_s'] for r in rounds]
    return out


def _cost(per_worker: float) -> dict[str, Any]:
    """100 docks x 1 year (12 lines at 20 Hz) at the measured rate per worker (messages per
    CPU second: a worker with a core of its own): worker-hours, and hours on N workers (ideal
    scaling across docks: one chain per dock, 100 chains)."""
    total = 100 * YEAR_MESSAGES
    worker_hours = total / per_worker / 3600.0
    return {
        'messages': total,
        'worker_hours': round(worker_hours, 1),
        'hours_on': {str(n): round(worker_hours / n, 2) for n in (2, 16, 100)},
        'note': 'at most 100 workers help: one chain per dock',
    }


def _text(out: dict[str, Any]) -> str:
    f = out['fleet']
    lines = [
        f'fleet: {f["docks"]} docks, {f["files"]} files, {f["messages"] / 1e6:.1f} M messages, '
        f'{f["bytes"] / 1e6:.0f} MB; {out["cpus"]} CPUs, load average '
        f'{out["load_average"][0][0]:.1f} before, {out["load_average"][1][0]:.1f} after',
        f'median of {out["repeat"]} rounds (the worker counts in turn):',
        'workers  start s  replay s  M msg/s  speed-up  efficiency  identical  rounds: replay s',
    ]
    for r in out['runs']:
        lines.append(
            f'{r["workers"]:>7}  {r["startup_s"]:>7.2f}  {r["replay_s"]:>8.2f}  '
            f'{r["messages_per_s"] / 1e6:>7.2f}  {r["speedup"]:>8.2f}  {r["efficiency"]:>10.2f}'
            f'  {"yes" if r["identical_to_first"] else "NO":>9}  '
            + ' '.join(f'{x:.2f}' for x in r['replay_s_all'])
        )
    c = out['year_100_docks']
    per = out['per_worker_messages_per_cpu_s']
    lines.append(
        f'per worker: {per / 1e6:.2f} M messages per CPU second; 100 docks x 1 year '
        f'({c["messages"] / 1e12:.2f} T messages): {c["worker_hours"]:.0f} worker-hours = '
        + ', '.join(f'{h:.1f} h on {n}' for n, h in c['hours_on'].items())
    )
    return '\n'.join(lines)


def cmd_bench_fleet(args: argparse.Namespace) -> int:
    out = run(
        docks=args.docks,
        files=args.files,
        per_file=args.messages_per_file,
        workers_list=tuple(args.workers_list),
        keep=Path(args.keep) if args.keep else None,
        repeat=args.repeat,
    )
    print(json.dumps(out) if args.json else _text(out))
    return 0 if all(r['identical_to_first'] for r in out['runs']) else 1


def _workers(text: str) -> list[int]:
    try:
        values = [int(t) for t in text.split(',')]
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a list of integers: {text!r}') from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f'worker counts must be at least 1: {text!r}')
    return values


def register(sub: Any) -> None:
    """Add ``bench-fleet`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-fleet',
        help='the fleet replay on 1 worker against 2 (same fleet, identical results)',
        description=__doc__.split('\n\n')[1] if __doc__ else None,
    )
    p.add_argument('--docks', type=int, default=3, help='dock folders (default 3)')
    p.add_argument('--files', type=int, default=4, help='log files per dock (default 4)')
    p.add_argument(
        '--messages-per-file', type=int, default=200_000, help='messages per file (default 2e5)'
    )
    p.add_argument(
        '--workers-list', type=_workers, default=[1, 2], metavar='N,M',
        help='worker counts to run, the first the baseline (default 1,2)',
    )  # fmt: skip
    p.add_argument(
        '--repeat', type=int, default=3, help='rounds of every worker count (default 3)'
    )
    p.add_argument('--keep', metavar='DIR', help='generate and keep the fleet and results here')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_fleet)
