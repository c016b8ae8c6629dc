"""``catenary-monitor fleet``: three generated docks replayed on a local Dask cluster equal
serial replays of each folder row for row; damaged input named with its task and skipped; a
worker killed mid-run changes nothing; a run started again resumes; docs/fleet.md's DuckDB
queries answer over the dataset.

The reference is the one driver's serial replay of each folder (``replay_log``, every window
of the log at once), its rows as :func:`message_columns` gives them to the CSV, its episodes as
the replay summary lists them. Small docks (60 s of log at 10 Hz, three lines) keep it short.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from fleet_data import damage_middle, write_dock

pa = pytest.importorskip('pyarrow')
pytest.importorskip('distributed')
import pyarrow.compute as pc  # noqa: E402
import pyarrow.dataset as ds  # noqa: E402

from catenary_monitor.cli.main import main  # noqa: E402
from catenary_monitor.replay import outputs as out  # noqa: E402
from catenary_monitor.replay.driver import replay_log  # noqa: E402
from catenary_monitor.replay.fleet_cluster import run_fleet  # noqa: E402
from catenary_monitor.replay.fleet_dataset import message_table, window_columns  # noqa: E402
from catenary_monitor.replay.fleet_tasks import plan_dock, run_piece  # noqa: E402

DOCS = Path(__file__).resolve().parents[1] / 'docs' / 'fleet.md'
MIDNIGHT = (42_400 - 30) * 10**9  # the generator's epoch is 12:13:20 UTC: 30 s before 00:00


def _wrong_type(path: Path, stamp: int) -> None:
    """A recording whose line_01 tension topic is a std_msgs/String: the reader refuses it."""
    from catenary_monitor.io.cdr import string_message
    from catenary_monitor.io.mcap_log import McapLogger

    log = McapLogger(path.parent, prefix='other', fsync=False, bag_metadata=False)
    log.register('/mooring/line_01/tension', 'std_msgs/msg/String', 'sensor_data')
    for k in range(5):
        log.write('/mooring/line_01/tension', string_message('372e3'), stamp + k * 10**8)
    log.close()
    log.files[0].rename(path)


@pytest.fixture(scope='module')
def cluster() -> Any:
    """One local cluster of two one-core workers for the module's runs (``--scheduler``):
    each run's client connects in a moment, where a cluster of its own takes seconds."""
    import logging

    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.CRITICAL) as c:  # fmt: skip
        yield c.scheduler_address


@pytest.fixture(scope='module')
def fleet(tmp_path_factory: Any) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp('fleet')
    a = write_dock(tmp / 'in' / 'dock_a', seconds=60.0, files=3, seed=1)
    b = write_dock(tmp / 'in' / 'dock_b', seconds=60.0, files=3, seed=2, node=False)
    damage_middle(b / 'dock_001.mcap')
    c = write_dock(tmp / 'in' / 'dock_c', seconds=60.0, files=3, seed=3, offset_ns=MIDNIGHT)
    refs = {name: _reference(folder) for name, folder in (('dock_a', a), ('dock_b', b))}
    refs['dock_c'] = _reference(c)  # before the files the reader refuses are added
    last = int(refs['dock_c']['columns']['time'].max())
    _wrong_type(c / 'zz_other.mcap', last + 10**9)
    (c / 'notes.mcap').write_text('not a log\n')
    return dict(tmp=tmp, folders=[a, b, c], refs=refs)


def _reference(folder: Path) -> dict[str, Any]:
    """The serial replay of the folder: its rows and its summary."""
    plan = plan_dock(folder)
    paths = [Path(f) for f in plan.files]
    replayed = replay_log(paths, plan.config, follow_log=plan.follow_log)
    summary = out.summary_dict(replayed.result, replayed.report)
    return dict(columns=window_columns(replayed.result), summary=summary)


def _plain(table: Any) -> dict[str, np.ndarray]:
    """Columns as numpy (words as str)."""
    cols = {}
    for name in table.column_names:
        column = table.column(name)
        if pa.types.is_dictionary(column.type):
            column = column.cast(pa.string())
        cols[name] = column.to_numpy(zero_copy_only=False)
    return cols


def _dataset(root: Path, name: str, dock: str) -> dict[str, np.ndarray]:
    table = ds.dataset(root / name, format='parquet', partitioning='hive').to_table()
    table = table.filter(pc.field('dock') == dock)
    if name == 'messages':
        table = table.take(pc.sort_indices(table, [('time', 'ascending')]))
    return _plain(table)


def _assert_rows_equal(root: Path, dock: str, ref: dict[str, Any]) -> None:
    got = _dataset(root, 'messages', dock)
    want = _plain(message_table(ref['columns']))
    assert set(got) == set(want) | {'dock', 'date'}
    assert len(got['time']) == len(want['time']) > 1000
    assert got['time'].dtype == np.int64 and np.all(np.diff(got['time']) >= 0)
    for name, column in want.items():
        if column.dtype.kind == 'f':
            assert np.array_equal(got[name], column, equal_nan=True), name  # bit for bit
        else:
            assert (got[name].astype(str) == column.astype(str)).all(), name
    days = (got['time'] // (86_400 * 10**9)).astype('datetime64[D]').astype(str)
    assert (got['date'].astype(str) == days).all()


def _assert_episodes_equal(root: Path, dock: str, ref: dict[str, Any]) -> None:
    got = _dataset(root, 'episodes', dock)
    rows = sorted(zip(got['name'].astype(str), got['start'], got['worst'].astype(str),
                      got['message'].astype(str)))  # fmt: skip
    summary = ref['summary']
    want = [(n, e['start'], e['worst'], e['message'])
            for n, ln in summary['lines'].items() for e in ln['episodes']]  # fmt: skip
    want += [(n, e['start'], e['worst'], e['message'])
             for n, c in summary['components'].items() for e in c['episodes']]  # fmt: skip
    assert rows == sorted(want) and len(want) > 3


def test_fleet_equals_serial_replays_and_names_the_damage(fleet, cluster, tmp_path, capsys):
    results = tmp_path / 'results'
    code = main(['fleet', *map(str, fleet['folders']), '--out', str(results),
                 '--scheduler', cluster])  # fmt: skip
    text = capsys.readouterr()
    assert code == 0, text.err
    for dock, ref in fleet['refs'].items():
        _assert_rows_equal(results, dock, ref)
        _assert_episodes_equal(results, dock, ref)
    # the damage, each named once: the corrupt chunk (the reader's own skip, as replay says
    # it), the file it refused with its task, the file that is not MCAP at all
    assert re.search(r'dock_b: \S*dock_001\.mcap @ byte \d+: corrupt', text.out), text.out
    assert re.search(r'dock_c: \S*zz_other\.mcap: skipped \(task 3 of dock dock_c\): '
                     r'.*std_msgs/msg/String', text.out), text.out  # fmt: skip
    assert re.search(r'dock_c: \S*notes\.mcap is not an MCAP file', text.out), text.out
    # a dock's midnight: two days, two partitions
    dates = sorted(p.name for p in (results / 'messages' / 'dock=dock_c').iterdir())
    assert dates == ['date=2025-11-23', 'date=2025-11-24']
    # daily extremes equal those of the messages (per line and day)
    daily = _dataset(results, 'daily', 'dock_c')
    msgs = _dataset(results, 'messages', 'dock_c')
    for line, date, low, n in zip(daily['line'], daily['date'], daily['anchor_margin_min'],
                                  daily['messages']):  # fmt: skip
        rows = (msgs['line'].astype(str) == line) & (msgs['date'].astype(str) == str(date))
        assert n == rows.sum() and low == np.nanmin(msgs['anchor_margin'][rows])
    assert np.nansum(daily['seconds_error']) > 0
    # every second of the log at one level, per line (across the midnight)
    span = fleet['refs']['dock_c']['summary']['duration']
    spent = sum(daily[f'seconds_{lv}'] for lv in ('ok', 'warn', 'error', 'stale'))
    for line in ('line_01', 'line_02', 'line_03'):
        assert spent[daily['line'].astype(str) == line].sum() == pytest.approx(span, abs=1e-6)


def test_the_rows_are_those_of_the_replay_command_s_csv(fleet, cluster, tmp_path, capsys):
    """What a user would otherwise run, a serial loop of ``catenary-monitor replay DIR --csv``:
    every column of every row the same (at the CSV's printed precision), as bench-fleet
    checks on its fleet."""
    from catenary_monitor_study.bench_fleet import same_as_csv

    folders = fleet['folders'][:2]  # a node's log, and a damaged sensor recording
    results = tmp_path / 'results'
    assert not run_fleet(folders, results, scheduler=cluster).failed
    for folder in folders:
        csv = tmp_path / f'{folder.name}.csv'
        args = ['replay', str(folder), '--csv', str(csv), '--csv-columns', 'all', '--quiet']
        own = folder / 'catenary_monitor.yaml'
        code = main(args + (['--params-file', str(own)] if own.exists() else []))
        assert code == 0, capsys.readouterr().err
        assert same_as_csv(results, folder.name, csv), folder.name


def test_columns_keeps_those_of_the_messages_and_the_daily_table_whole(fleet, cluster, tmp_path):
    """``--columns``: the messages dataset has those (with time and line), each equal to the
    serial replay's; the daily table is the one of a run with every column."""
    folder = fleet['folders'][0]
    results = tmp_path / 'results'
    wanted = ['anchor_margin', 'level']
    code = main(['fleet', str(folder), '--out', str(results), '--scheduler', cluster,
                 '--columns', ','.join(wanted), '--quiet'])  # fmt: skip
    assert code == 0
    got = _dataset(results, 'messages', 'dock_a')
    assert list(got) == ['time', 'line', *wanted, 'dock', 'date']
    want = _plain(message_table(fleet['refs']['dock_a']['columns']))
    assert np.array_equal(got['time'], want['time'])
    assert np.array_equal(got['anchor_margin'], want['anchor_margin'], equal_nan=True)
    assert (got['level'].astype(str) == want['level'].astype(str)).all()
    full = tmp_path / 'full'
    assert not run_fleet([folder], full, scheduler=cluster).failed
    for name in ('daily', 'episodes'):
        a, b = _dataset(results, name, 'dock_a'), _dataset(full, name, 'dock_a')
        assert list(a) == list(b) and all(
            np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == 'f') for k in a
        ), name
    assert main(['fleet', str(folder), '--out', str(results), '--columns', 'nope']) == 2


def test_a_killed_worker_loses_and_duplicates_nothing(fleet, cluster, tmp_path):
    """Kill the worker that is replaying a piece, once the first piece is done."""
    from distributed import get_client

    killed = []

    def kill_one(progress: Any) -> None:
        """Mid-run: after the first piece and before the last, SIGKILL a worker (one replaying
        a piece if there is one; any holds finished pieces' results that later ones need)."""
        if killed or not 1 <= progress.tasks_done < progress.tasks_total:
            return
        client = get_client()
        busy = [w for w, keys in client.processing().items()
                if any(str(k).startswith('fleet-piece') for k in keys)]  # fmt: skip
        worker = (busy or sorted(client.scheduler_info()['workers']))[0]
        pid = client.run(os.getpid, workers=[worker])[worker]
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    results = tmp_path / 'results'
    run = run_fleet(fleet['folders'], results, scheduler=cluster, progress=kill_one)
    assert killed and not run.failed, run.failed
    assert run.workers_lost >= 1
    for dock, ref in fleet['refs'].items():
        _assert_rows_equal(results, dock, ref)
    assert not list((results / '_fleet').glob('tmp/*'))


def test_an_interrupted_run_resumes(fleet, cluster, tmp_path):
    a = fleet['folders'][0]
    results = tmp_path / 'results'
    plan = plan_dock(a)
    carry = run_piece(plan, 0, None, str(results))  # a run stopped after dock_a's first piece
    first = sorted((results / 'messages').rglob('*.parquet'))
    stamp = [p.stat().st_mtime_ns for p in first]
    run = run_fleet(fleet['folders'], results, scheduler=cluster)
    assert run.tasks_reused == 1 and not run.failed
    assert [p.stat().st_mtime_ns for p in first] == stamp  # the finished part not redone
    for dock, ref in fleet['refs'].items():
        _assert_rows_equal(results, dock, ref)
    again = run_fleet(fleet['folders'], results, scheduler=cluster)
    assert again.tasks_run == 0 and sorted(again.docks_up_to_date) == sorted(fleet['refs'])
    assert carry.task == 0


def test_a_dock_s_next_file_is_one_more_task(cluster, tmp_path):
    """A dock's log goes on (the node wrote another file): the next run replays that file
    alone, from the checkpoint, and the dataset is the serial replay of the whole folder
    (sensor recordings: the grid ticks of the gap between the files come with the new one)."""
    full = write_dock(tmp_path / 'full' / 'dock_d', seconds=60.0, files=4, seed=4, node=False)
    work = tmp_path / 'work' / 'dock_d'
    work.mkdir(parents=True)
    for name in ('catenary_monitor.yaml', 'dock_000.mcap', 'dock_001.mcap', 'dock_002.mcap'):
        shutil.copy2(full / name, work / name)
    results = tmp_path / 'results'
    assert run_fleet([work], results, scheduler=cluster).tasks_run == 3
    shutil.copy2(full / 'dock_003.mcap', work / 'dock_003.mcap')
    run = run_fleet([work], results, scheduler=cluster)
    assert (run.tasks_run, run.tasks_reused) == (1, 3)
    _assert_rows_equal(results, 'dock_d', _reference(full))
    _assert_episodes_equal(results, 'dock_d', _reference(full))


def test_docs_duckdb_queries_answer_over_the_dataset(fleet, tmp_path):
    """Also the local cluster of the command's default (``--workers``)."""
    duckdb = pytest.importorskip('duckdb')
    results = tmp_path / 'results'
    folders = [str(f) for f in fleet['folders'][:2]]
    assert main(['fleet', *folders, '--out', str(results), '--workers', '1', '--quiet']) == 0
    queries = re.findall(r'```sql\n(.*?)```', DOCS.read_text(), re.S)
    assert len(queries) >= 3
    con = duckdb.connect()
    answers = []
    for sql in queries:
        answers.append(con.sql(sql.replace('RESULTS', str(results))).fetchall())
    closest = {row[0]: row for row in answers[0]}
    for dock in ('dock_a', 'dock_b'):
        margin = fleet['refs'][dock]['columns']['anchor_margin']
        assert closest[dock][2] == pytest.approx(np.nanmin(margin), abs=1e-9)
    assert all(answers), answers


def test_files_that_overlap_in_time_make_the_dock_one_task(cluster, tmp_path):
    """Two recorders in one folder (the tensions in one file, the tide in another, the same
    hours): the chain finds the overlap and the dock is replayed again as one task, as
    ``replay DIR`` does it."""
    from replay_data import dock_config, generate, params_yaml, write_log

    folder = tmp_path / 'dock_e'
    folder.mkdir()
    config = dock_config(3)
    tensions, depth = generate(config, seconds=40.0, seed=5)
    write_log(folder / 'a_tension.mcap', config, tensions, (np.zeros(0, np.int64), np.zeros(0)))
    write_log(folder / 'b_tide.mcap', config, {}, depth)
    params_yaml(config, folder / 'catenary_monitor.yaml')
    assert len(plan_dock(folder).pieces) == 2
    results = tmp_path / 'results'
    run = run_fleet([folder], results, scheduler=cluster)
    assert not run.failed and run.docks['dock_e']['one_task']
    _assert_rows_equal(results, 'dock_e', _reference(folder))


def test_a_free_worker_takes_the_piece_with_the_most_work_behind_it(cluster, tmp_path):
    """A piece is submitted when a worker is free: the ready piece whose chain has the most
    bytes left (its own included). With two workers, the smallest dock (named first) starts
    only after one of the two larger docks has run its last piece."""
    from catenary_monitor.replay.fleet_cluster import chain_priorities

    folders = [
        write_dock(tmp_path / 'in' / 'a_small', seconds=10.0, files=1, seed=6),
        write_dock(tmp_path / 'in' / 'b_mid', seconds=40.0, files=2, seed=7),
        write_dock(tmp_path / 'in' / 'c_large', seconds=90.0, files=3, seed=8),
    ]
    left = chain_priorities(plan_dock(folders[2]))
    sizes = [p.stat().st_size for p in sorted(folders[2].glob('*.mcap'))]
    assert left == [sum(sizes), sizes[1] + sizes[2], sizes[2]]
    results = tmp_path / 'results'
    assert not run_fleet(folders, results, scheduler=cluster).failed

    def written(dock: str) -> list[int]:
        parts = (results / 'messages' / f'dock={dock}').rglob('part-*.parquet')
        return sorted(p.stat().st_mtime_ns for p in parts)

    assert written('a_small')[0] > min(written('b_mid')[-1], written('c_large')[-1])


class _Future:
    """What :func:`fleet_cluster._collect` reads of a Dask future."""

    def __init__(self, status: str) -> None:
        self.status, self.key = status, f'fleet-count-t-0-dock_x-{status}'

    def exception(self) -> None:
        raise AssertionError('a lost or cancelled future has no exception to wait for')


@pytest.mark.parametrize('status', ['lost', 'pending'])
def test_a_result_lost_after_it_was_done_is_waited_for_again(status):
    """A piece done, then its worker killed before the count was read: Dask computes it again
    (the future is ``lost``, then ``pending``); the run waits for it, the dock does not fail
    (CI saw 'dock_c: NoneType: None' once)."""
    from catenary_monitor.replay import fleet_cluster

    dock = fleet_cluster._Dock(SimpleNamespace(name='dock_x', pieces=()))
    run, owner, pending = fleet_cluster.FleetRun(), {}, []

    class _Pending:
        add = pending.append

    future = _Future(status)
    fleet_cluster._collect(None, future, dock, Path('.'), 't', run,
                           fleet_cluster.Progress(), owner, _Pending())  # fmt: skip
    assert pending == [future] and owner == {future.key: (dock, 0)}
    assert not run.failed and not dock.failed


def test_a_future_cancelled_elsewhere_fails_its_dock_in_words():
    from catenary_monitor.replay import fleet_cluster

    class _Client:
        cancelled: list[Any] = []
        cancel = cancelled.append

    dock = fleet_cluster._Dock(SimpleNamespace(name='dock_x', pieces=()))
    run = fleet_cluster.FleetRun()
    fleet_cluster._collect(_Client(), _Future('cancelled'), dock, Path('.'), 't', run,
                           fleet_cluster.Progress(), {}, None)  # fmt: skip
    assert dock.failed and 'cancelled (not by this run)' in run.failed['dock_x']


def test_workers_are_counted_lost_only_when_the_scheduler_no_longer_has_them():
    """The client's cached ``scheduler_info()`` can hold cluster totals only (its periodic
    update asks for no workers): a loaded machine reported every worker lost of a run that
    lost none. The look asks the scheduler for its workers now."""
    from catenary_monitor.replay import fleet_cluster

    class _Client:
        workers = {'tcp://a': 1, 'tcp://b': 1}

        def scheduler_info(self) -> dict[str, Any]:
            return {'workers': {}}  # the totals-only cache

        def nthreads(self) -> dict[str, int]:
            return dict(self.workers)

    client, run, state = _Client(), fleet_cluster.FleetRun(), fleet_cluster.Progress()
    addresses = fleet_cluster._look_for_lost(client, {'tcp://a', 'tcp://b'}, run, state)
    assert addresses == {'tcp://a', 'tcp://b'} and run.workers_lost == 0 and not state.notes
    client.workers = {'tcp://b': 1}
    fleet_cluster._look_for_lost(client, addresses, run, state)
    assert run.workers_lost == 1
    assert state.notes == ['worker tcp://a lost: its tasks are done again']
