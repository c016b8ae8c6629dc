"""``catenary-monitor bench-fleet``: the fleet replay against the shell loop of ``replay`` it
replaces, same folders, same run.

Generates (seeded) ``--docks`` dock folders of ``--files`` rotated node-shaped logs each (the
paper dock's 12 lines at 10 Hz, the tide at 1 Hz, zstd chunks; ``--messages-per-file``; the
folder's ``catenary_monitor.yaml``), then times, as commands in their own processes, rounds in
turn: the baseline, what a user would otherwise run (a serial loop of ``catenary-monitor replay
DIR --params-file DIR/catenary_monitor.yaml --csv DOCK.csv`` over the folders); the same loop
without the CSV (the summary only: the least a replay does); ``catenary-monitor fleet`` on
a local cluster of its own of 1 worker and of 2 (``--workers-list``); the same of 2 writing the
columns the baseline's CSV has (``fleet --columns``: what the loop writes, as Parquet); and
``fleet --scheduler`` on a cluster of 2 started once for all the rounds (``reused``), each into
a fresh results folder; and, in the first round, the loop of ``replay --csv --csv-columns all``
(the rows of the fleet's default dataset, every column, as text). Each fleet mode's ratio to
the loop writing the same rows ("same-columns loop") is the fair one both ways.
Reports per mode the median wall time and its ratio to the baseline, the fleet's fixed cost
(its wall time minus its replay: the imports, the cluster's start and stop), and checks that
every fleet run's messages dataset is identical to the first's (row for row) and holds the
serial replays' CSV rows (every row, each value equal at the CSV's printed precision). From
the workers' CPU time it prints what 100 docks x 1 year of 12 lines at 20 Hz would cost on N
workers.

The machines are shared: the load average before and after is printed with the figures; read
the ratios (same run, rounds in turn), not the seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

__all__ = ['compile_package', 'register', 'run', 'same_as_csv', 'same_columns_loop']

#: One dock at 12 lines x 20 Hz and its tide at 1 Hz, for a year: the messages.
YEAR_MESSAGES = (12 * 20 + 1) * 86_400 * 365

#: The baseline's mode name, and the loop without outputs.
LOOP_CSV, LOOP_BARE = 'replay --csv loop', 'replay loop'
#: The loop writing every column (``replay --csv --csv-columns all``): the rows the fleet's
#: default dataset holds, as text. Its CSVs are 60 bytes a message: timed in the first round
#: only (ten times the fleet's wall time: the other rounds would add minutes, not precision).
LOOP_ALL = 'replay --csv all loop'
#: The fleet's mode writing the columns the baseline's CSV has (``fleet --columns``).
CSV_MODE = 'CSV columns'


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


def same_as_csv(results: Path, dock: str, csv: Path) -> bool:
    """Whether the fleet's rows of ``dock`` are the rows of ``catenary-monitor replay --csv``
    (any of its columns): as many, in time order, the same words, the time to the us (the CSV
    prints s) and every value within half the CSV's last printed decimal (``nan``: null)."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.dataset as ds
    from pyarrow import csv as pacsv

    from catenary_monitor.replay.outputs import CSV_ALL

    decimals = dict(CSV_ALL)
    want = pacsv.read_csv(csv).to_pydict()
    table = ds.dataset(results / 'messages' / f'dock={dock}', format='parquet').to_table()
    table = table.take(pc.sort_indices(table, [('time', 'ascending')]))
    if table.num_rows != len(want['time']):
        return False
    for name, values in want.items():
        got = table.column(name)
        if name == 'time':
            ns = np.round(np.asarray(values, np.float64) * 1e9)
            ok = np.abs(got.to_numpy() - ns) <= 1e3  # a float64 of s holds about a us
        elif pa.types.is_dictionary(got.type) or pa.types.is_string(got.type):
            words = np.asarray(got.cast(pa.string()).to_pylist(), dtype=object)
            ok = words == np.asarray([str(v) for v in values], dtype=object)
        else:
            x = got.to_numpy(zero_copy_only=False).astype(np.float64)
            y = np.asarray(values, np.float64)  # None (the CSV's nan) -> NaN
            tol = 0.5 * 10.0 ** -(decimals[name] or 0) * (1 + 1e-9) + 1e-9 * np.abs(y)
            ok = (np.isnan(x) & np.isnan(y)) | (x == y) | (np.abs(x - y) <= tol)
        if not bool(np.all(ok)):
            return False
    return True


def _children_cpu() -> float:
    """CPU s (user and system) of this process's finished children and theirs."""
    import resource

    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def _command(args: list[str]) -> tuple[float, float, str]:
    """``catenary-monitor ARGS`` in its own process (this tree's package): wall s, CPU s (the
    command's and its workers'), stdout."""
    import catenary_monitor

    tree = str(Path(catenary_monitor.__file__).resolve().parents[1])
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([tree, *filter(None, [env.get('PYTHONPATH')])])
    cpu, t0 = _children_cpu(), time.perf_counter()
    done = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor', *args],
        env=env,
        capture_output=True,
        text=True,
    )
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu
    if done.returncode != 0:
        raise RuntimeError(f'catenary-monitor {" ".join(args)}: exit {done.returncode}: '
                           f'{done.stderr.strip()[-500:]}')  # fmt: skip
    return wall, cpu, done.stdout


def compile_package() -> None:
    """Write the bytecode of this tree's package, as ``pip install`` does: each command then
    starts as from an installed package. Without it (``PYTHONDONTWRITEBYTECODE``, a source
    tree) every command compiles the modules it imports again: 0.15 CPU s more per
    ``replay``, paid four times by the loop and once by the fleet."""
    import compileall

    import catenary_monitor

    compileall.compile_dir(
        str(Path(catenary_monitor.__file__).resolve().parent), quiet=2, workers=1
    )


def _replay_loop(
    folders: list[Path], csv_dir: Optional[Path], every_column: bool = False
) -> dict[str, Any]:
    """The serial loop of ``replay`` over the folders (``csv_dir``: each writes DOCK.csv;
    ``every_column``: with ``--csv-columns all``)."""
    wall = cpu = 0.0
    for folder in folders:
        args = ['replay', str(folder), '--params-file', str(folder / 'catenary_monitor.yaml')]
        if csv_dir is not None:
            args += ['--csv', str(csv_dir / f'{folder.name}.csv')]
            args += ['--csv-columns', 'all'] if every_column else []
        w, c, _ = _command(args + ['--quiet'])
        wall, cpu = wall + w, cpu + c
    mode = LOOP_BARE if csv_dir is None else LOOP_ALL if every_column else LOOP_CSV
    return {'mode': mode, 'wall_s': round(wall, 3), 'cpu_s': round(cpu, 3)}


def _fleet(
    folders: list[Path],
    results: Path,
    workers: int,
    first: Path,
    scheduler: str = '',
    columns: str = '',
) -> dict[str, Any]:
    """One ``fleet`` command into a fresh folder, compared with the first: on a fresh local
    cluster of ``workers``, or on the running cluster at ``scheduler`` (started once);
    ``columns``: its ``--columns``."""
    shutil.rmtree(results, ignore_errors=True)
    args = ['fleet', *map(str, folders), '--out', str(results)]
    args += ['--scheduler', scheduler] if scheduler else ['--workers', str(workers)]
    args += ['--columns', columns] if columns else []
    wall, cpu, text = _command(args + ['--quiet', '--json'])
    fleet = json.loads(text)
    if scheduler:  # the workers are not the command's children: their CPU from the run
        cpu += fleet['worker_cpu_seconds']
    same = _same_rows(first, results)
    if results != first:
        shutil.rmtree(results, ignore_errors=True)
    mode = f'fleet, {workers} worker{"s" if workers > 1 else ""}'
    mode += ', reused' if scheduler else ''
    return {
        'mode': mode + (f', {CSV_MODE}' if columns else ''),
        'workers': workers,
        'wall_s': round(wall, 3),
        'cpu_s': round(cpu, 3),
        'fixed_s': round(wall - fleet['seconds'], 3),
        'startup_s': fleet['startup_seconds'],
        'replay_s': fleet['seconds'],
        'worker_cpu_s': fleet['worker_cpu_seconds'],
        'messages': fleet['messages'],
        'identical_to_first': same,
    }


def pieces_cpu(folders: list[Path], root: Path) -> dict[str, float]:
    """Every dock's chain of pieces run in this process, one after the other, as a worker
    runs them (no Dask): CPU s in all, and of it the message parts' steps (the rows' columns
    in time order, their Arrow table, the Parquet writing, the daily extremes)."""
    from catenary_monitor.replay import fleet_dataset, fleet_tasks

    spent = {'rows': 0.0, 'table': 0.0, 'parquet': 0.0, 'daily': 0.0}
    timed = [(fleet_tasks, 'window_columns', 'rows'), (fleet_tasks, 'message_table', 'table'),
             (fleet_dataset.PartWriter, 'add', 'parquet'),
             (fleet_dataset.DailyExtremes, 'add', 'daily')]  # fmt: skip
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in timed]

    def clocked(f: Any, what: str) -> Any:
        def g(*args: Any) -> Any:
            t = time.process_time()
            try:
                return f(*args)
            finally:
                spent[what] += time.process_time() - t

        return g

    for (owner, name, what), (_, _, f) in zip(timed, saved):
        setattr(owner, name, clocked(f, what))
    try:
        fleet_tasks.one_core()
        t0 = time.process_time()
        for folder in folders:
            plan = fleet_tasks.plan_dock(folder)
            before = None
            for task in range(len(plan.pieces)):
                before = fleet_tasks.run_piece(plan, task, before, str(root))
        total = time.process_time() - t0
    finally:
        for owner, name, f in saved:
            setattr(owner, name, f)
        shutil.rmtree(root, ignore_errors=True)
    return {'cpu_s': round(total, 3), **{k: round(v, 3) for k, v in spent.items()}}


def run(
    docks: int = 4,
    files: int = 4,
    per_file: int = 200_000,
    workers_list: tuple[int, ...] = (1, 2),
    keep: Optional[Path] = None,
    repeat: int = 3,
    reuse: bool = True,
    all_columns: bool = True,
) -> dict[str, Any]:
    """Generate the fleet, time every mode ``repeat`` times (in turn); returns the figures
    (per mode, the median round). ``reuse``: also the fleet on a cluster of the largest
    worker count started once for every round (``fleet --scheduler``). ``all_columns``: also
    the loop of ``replay --csv --csv-columns all`` (:data:`LOOP_ALL`, the first round)."""
    tmp = Path(keep) if keep else Path(tempfile.mkdtemp(prefix='bench_fleet_'))
    compile_package()
    load = os.getloadavg()
    try:
        facts = generate_fleet(tmp / 'docks', docks, files, per_file)
        folders = sorted((tmp / 'docks').iterdir())
        csv_dir = tmp / 'csv'
        csv_dir.mkdir(exist_ok=True)
        all_dir = tmp / 'csv_all'
        all_dir.mkdir(exist_ok=True)
        rounds: dict[str, list[dict[str, Any]]] = {}
        first = tmp / f'results_{workers_list[0]}_0'
        first_csv = tmp / 'csv_columns_0'
        from catenary_monitor.replay.outputs import CSV_COLUMNS

        csv_columns = ','.join(CSV_COLUMNS)
        reused = _cluster(max(workers_list)) if reuse else None
        try:
            for k in range(repeat):  # the modes in turn: a change of load hits each
                modes = [_replay_loop(folders, csv_dir), _replay_loop(folders, None)]
                modes += [_fleet(folders, tmp / f'results_{n}_{k}', n, first)
                          for n in workers_list]  # fmt: skip
                modes.append(_fleet(folders, tmp / f'csv_columns_{k}', max(workers_list),
                                    first_csv, columns=csv_columns))  # fmt: skip
                if reused is not None:
                    n = len(reused.scheduler_info['workers'])
                    address = reused.scheduler_address
                    modes.append(_fleet(folders, tmp / f'reused_{k}', n, first, address))
                if k == 0 and all_columns:
                    modes.append(_replay_loop(folders, all_dir, every_column=True))
                for r in modes:
                    rounds.setdefault(r['mode'], []).append(r)
        finally:
            if reused is not None:
                reused.close()
        same_csv = all(same_as_csv(res, f.name, csv_dir / f'{f.name}.csv')
                       for f in folders for res in (first, first_csv))  # fmt: skip
        if all_columns:  # the default dataset holds the rows of replay --csv-columns all
            same_csv = same_csv and all(
                same_as_csv(first, f.name, all_dir / f'{f.name}.csv') for f in folders
            )
            shutil.rmtree(all_dir, ignore_errors=True)
        in_process = pieces_cpu(folders, tmp / 'pieces')
        runs = [_median(rounds[mode]) for mode in rounds]
        base = {r['mode']: r['wall_s'] for r in runs}
        for r in runs:
            r['vs_replay_csv_loop'] = round(base[LOOP_CSV] / r['wall_s'], 3)
            r['vs_replay_loop'] = round(base[LOOP_BARE] / r['wall_s'], 3)
            same = same_columns_loop(r['mode'])
            if same in base:
                r['vs_same_columns_loop'] = round(base[same] / r['wall_s'], 3)
        fleets = [x for mode, xs in rounds.items() for x in xs
                  if 'workers' in x and CSV_MODE not in mode]  # fmt: skip
        per_cpu = statistics.median(x['messages'] / x['worker_cpu_s'] for x in fleets)
        return {
            'fleet': facts,
            'cpus': len(os.sched_getaffinity(0)),
            'load_average': [list(load), list(os.getloadavg())],
            'repeat': repeat,
            'runs': runs,
            'rounds': rounds,
            'identical_to_replay_csv': same_csv,
            'pieces_in_one_process': in_process,
            'per_worker_messages_per_cpu_s': round(per_cpu),
            'year_100_docks': _cost(per_cpu),
        }
    finally:
        if keep is None:
            shutil.rmtree(tmp, ignore_errors=True)


def same_columns_loop(mode: str) -> str:
    """The loop that writes the rows a mode writes (what a user would run for its results):
    the fleet's default dataset, every column, against :data:`LOOP_ALL`; the fleet with the
    CSV's columns (``--columns``) against :data:`LOOP_CSV`; a loop: none ('')."""
    if not mode.startswith('fleet'):
        return ''
    return LOOP_CSV if CSV_MODE in mode else LOOP_ALL


def _cluster(workers: int) -> Any:
    """The local cluster the ``reused`` rounds share, started once, as the command starts its
    own (:func:`catenary_monitor.replay.fleet_cluster.local_cluster`)."""
    from catenary_monitor.replay.fleet_cluster import local_cluster

    return local_cluster(workers)


def _median(rounds: list[dict[str, Any]]) -> dict[str, Any]:
    """The round with the median wall time (and whether every round was identical)."""
    ordered = sorted(rounds, key=lambda r: r['wall_s'])
    out = dict(ordered[(len(ordered) - 1) // 2])
    if 'identical_to_first' in out:
        out['identical_to_first'] = all(r['identical_to_first'] for r in rounds)
    out['wall_s_all'] = [r['wall_s'] for r in rounds]
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
        f'median of {out["repeat"]} rounds (the modes in turn), wall time of the commands:',
        f'{"mode":<29}  wall s   CPU s  x same-columns loop  x replay --csv loop'
        '  x replay loop  fixed s  identical  rounds: wall s',
    ]
    for r in out['runs']:
        fleet = 'workers' in r
        same = r.get('vs_same_columns_loop')
        lines.append(
            f'{r["mode"]:<29}  {r["wall_s"]:>6.2f}  {r["cpu_s"]:>6.2f}  '
            + (f'{same:>19.2f}  ' if same is not None else f'{"-":>19}  ')
            + f'{r["vs_replay_csv_loop"]:>19.2f}  '
            f'{r["vs_replay_loop"]:>13.2f}  '
            + (f'{r["fixed_s"]:>7.2f}  {"yes" if r["identical_to_first"] else "NO":>9}'
               if fleet else f'{"-":>7}  {"-":>9}')
            + '  ' + ' '.join(f'{x:.2f}' for x in r['wall_s_all'])
        )  # fmt: skip
    lines.append(
        'same-columns loop: the loop writing the rows the mode writes (every column: '
        f'{LOOP_ALL}, first round; CSV columns: {LOOP_CSV})'
    )
    lines.append(
        'the fleet\'s rows are the serial replays\' CSV rows: '
        + ('yes' if out['identical_to_replay_csv'] else 'NO')
    )
    p = out['pieces_in_one_process']
    lines.append(
        f'the pieces in one process (no Dask): {p["cpu_s"]:.2f} CPU s, of it the rows\' '
        f'columns {p["rows"]:.2f}, their table {p["table"]:.2f}, the Parquet parts '
        f'{p["parquet"]:.2f}, the daily extremes {p["daily"]:.2f}'
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
        reuse=not args.no_reuse,
        all_columns=not args.no_all_columns,
    )
    print(json.dumps(out) if args.json else _text(out))
    fleets = [r for r in out['runs'] if 'workers' in r]
    same = all(r['identical_to_first'] for r in fleets) and out['identical_to_replay_csv']
    return 0 if same else 1


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
        help='the fleet replay (1 and 2 workers) against a serial loop of replay',
        description=__doc__.split('\n\n')[1] if __doc__ else None,
    )
    p.add_argument('--docks', type=int, default=4, help='dock folders (default 4)')
    p.add_argument('--files', type=int, default=4, help='log files per dock (default 4)')
    p.add_argument(
        '--messages-per-file', type=int, default=200_000, help='messages per file (default 2e5)'
    )
    p.add_argument(
        '--workers-list', type=_workers, default=[1, 2], metavar='N,M',
        help='worker counts of the fleet runs (default 1,2)',
    )  # fmt: skip
    p.add_argument(
        '--repeat', type=int, default=3, help='rounds of every worker count (default 3)'
    )
    p.add_argument(
        '--no-reuse', action='store_true',
        help='no rounds on a cluster started once (fleet --scheduler)',
    )  # fmt: skip
    p.add_argument(
        '--no-all-columns', action='store_true',
        help='no loop of replay --csv-columns all (the default dataset\'s rows as text)',
    )  # fmt: skip
    p.add_argument('--keep', metavar='DIR', help='generate and keep the fleet and results here')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_fleet)
