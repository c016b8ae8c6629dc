"""Logs whose stamps span far more time than their bytes (test/span_logs.py): every command
that reads logs works in memory and time bounded by the bytes it reads, whatever the stamps.

A log without recorded ticks is stepped on a grid of ticks at ``diagnostic_rate``. The grid
is generated window by window and only within ``quiet_span`` after an input: a silence of
days costs what one of ten minutes does, and (tested here against the core ticking through the
whole silence, as a running node would) decides the same. A sample more than a year from every
other is a bad stamp: left out, counted, one line.

``replay``, ``alarms``, ``console --log`` and ``fleet`` run each file in a child process inside
a wrapper measuring its peak RSS and CPU time (as test_hostile_commands.py): under 300 MB and
10 s of CPU, no traceback, one line where refused.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import span_logs
from replay_data import T0_NS, core_steps, dock_config, generate
from ros_harness import child_env
from test_batch import assert_same_state, assert_statuses_agree, compare, ticks_for
from test_hostile_commands import WRAP
from test_stamped_inputs import events, plain, stamped_scene, window

from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.rules import readings
from catenary_monitor.core.rules.readings import STAMP_FAR, far_stamps
from catenary_monitor.core.twin.engine import advance
from catenary_monitor.core.twin.window import grid_ticks, quiet_span, tick_grid
from catenary_monitor.replay.driver import ReplayError, replay_log

RSS_LIMIT_MB = 300
CPU_LIMIT_S = 10.0
SECOND = 10**9
DAY = 86_400 * SECOND


@pytest.fixture(scope='module')
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return span_logs.write_all(tmp_path_factory.mktemp('spans'))


def test_the_files_are_what_they_claim(files: dict[str, Path]) -> None:
    sizes = {k: p.stat().st_size for k, p in files.items()}
    assert sizes['stamp_1970'] < 12_000 and sizes['daily'] < 160_000, sizes
    t, _, _ = span_logs.stamp_1970()
    assert t[0] < 10 * SECOND and (t[1:] > span_logs.T2026).all() and len(t) == 200
    t, _, _ = span_logs.daily()
    assert (t[-1] - t[0]) // DAY == 2999


# --- the rules
# ------------------------------------------------------------------------------


def test_a_sample_far_from_every_other_is_a_bad_stamp() -> None:
    year = int(STAMP_FAR * 1e9)
    s = np.array([7, span_logs.T2026, span_logs.T2026 + 1, span_logs.T2026 + DAY])
    assert far_stamps(s).tolist() == [True, False, False, False]
    assert far_stamps(s[1:], before_ns=7).tolist() == [False, False, False]
    t2100 = np.array([span_logs.T2026 + 5 * year])
    assert far_stamps(t2100, before_ns=span_logs.T2026).tolist() == [True]
    assert far_stamps(t2100, span_logs.T2026, t2100[0] + DAY).tolist() == [False]
    assert far_stamps(np.array([5])).tolist() == [False]  # no neighbour at all: a log of one
    assert far_stamps(np.array([7, 7])).tolist() == [False, False]  # one stamp: neighbours
    days = span_logs.T2026 + np.arange(3000, dtype=np.int64) * DAY
    assert not far_stamps(days).any()  # gaps of days are no bad stamps
    # No int64 wrap between a log time read as negative and one of 2100.
    assert far_stamps(np.array([-(2**62), span_logs.T2100, span_logs.T2100 + 1])).tolist() == [
        True,
        False,
        False,
    ]


def test_a_header_stamp_from_1970_is_a_bad_stamp_for_the_node_and_replay_alike() -> None:
    """A stamped sensor's first samples stamped 1970 (its clock not set yet): refused by the
    core (the node's decision path) as bad stamps, not taken as readings 56 years old, and by
    its twin (replay) the same way: every transition, snapshot and the state left agree."""
    codes = readings.stamp_faults(
        np.array([T0_NS] * 4), np.array([7, T0_NS - 10**9, T0_NS + 5 * 10**9, 7]), -1, 1.0
    )
    assert codes.tolist() == [readings.FAULT_FAR, 0, readings.FAULT_AHEAD, readings.FAULT_FAR]
    assert readings.stamp_fault(T0_NS, 7, -1, 1.0) == readings.FAULT_FAR
    config, cols, depth = stamped_scene(bad=False, seconds=40.0)
    a, v, st = cols['line_01']
    st = st.copy()
    st[:3] = 7 + np.arange(3)
    cols['line_01'] = (a, v, st)
    dst = depth[2].copy()
    dst[0] = 9
    depth = (depth[0], depth[1], dst)
    ticks = ticks_for(*plain(cols, depth))
    core = MonitorCore(config, T0_NS)
    steps = [core.step(ev) for ev in events(config, cols, depth, ticks)]
    twin = MonitorCore(config, T0_NS)
    cut = T0_NS + 20 * SECOND
    results = [
        advance(twin, window(config, cols, depth, ticks, lo, hi), snapshots=True)
        for lo, hi in ((None, cut), (cut, None))
    ]
    want_sn = [s.snapshot for s in steps if s.snapshot is not None]
    got_sn = [sn for r in results for sn in r.snapshots]
    assert [s.stamp_ns for s in got_sn] == [s.stamp_ns for s in want_sn]
    for g, w in zip(got_sn, want_sn):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    key = lambda c: (c.transition.time, c.component)  # noqa: E731
    want_tr = sorted([c for s in steps for c in s.transitions], key=key)
    assert sorted([c for r in results for c in r.changes()], key=key) == want_tr
    assert_same_state(twin, core)
    first = next(s.snapshot for s in steps if s.kind == 'tick')
    line = dict(first.statuses[0].values)
    assert line['sensor_state'] == 'bad_stamp', line
    assert float(line['tension_age']) < 60.0  # the 1970 samples were no reading
    assert core.state.lines[0].sample_ns > T0_NS - SECOND


def test_the_grid_of_a_log_without_silences_is_the_whole_grid() -> None:
    rng = np.random.default_rng(1)
    stamps = np.sort(T0_NS + rng.integers(0, 3600 * SECOND, 5000))
    stamps[0] = T0_NS
    quiet = 700 * SECOND
    for rate in (1.0, 3.0, 0.7):
        got, k = grid_ticks(T0_NS, rate, 0, stamps, None, quiet, int(stamps[-1]))
        assert got.tolist() == tick_grid(T0_NS, int(stamps[-1]), rate).tolist()
        assert k == len(got)


def test_the_grid_cut_in_windows_and_parts_is_the_one_grid() -> None:
    """Any cut of the log (windows with the newest input before them, parts of ``cap``
    ticks) gives the one set of ticks: every grid point within ``quiet`` after an input."""
    rng = np.random.default_rng(2)
    steps = rng.choice([SECOND // 2, 40 * SECOND, 3 * DAY], 400, p=[0.8, 0.15, 0.05])
    t = T0_NS + np.cumsum(steps)
    t = np.concatenate([[T0_NS], t])
    quiet, rate, end = 100 * SECOND, 1.0, int(t[-1])
    whole, _ = grid_ticks(T0_NS, rate, 0, t, None, quiet, end)
    period = SECOND
    grid = np.arange((end - T0_NS) // period + 1) * period + T0_NS
    newest = t[np.searchsorted(t, grid, 'right') - 1]
    assert whole.tolist() == grid[grid - newest <= quiet].tolist()
    assert len(whole) < 400 * 101  # the days of silence cost nothing
    for cap in (1, 7, 1000, None):
        got, k, before = [], 0, None
        for lo, hi in zip(range(0, 401, 37), range(37, 438, 37)):
            part = t[lo:hi]
            end_part = int(t[hi]) - 1 if hi < len(t) else end
            while True:
                ticks, k = grid_ticks(T0_NS, rate, k, part, before, quiet, end_part, cap)
                got += ticks.tolist()
                if cap is None or len(ticks) < cap:
                    break
            before = int(part[-1]) if len(part) else before
        assert got == whole.tolist(), cap


def _silent_scene(silence_s: float, **alarm: float):
    """A storm with dropouts (90 s), ``silence_s`` without any input, another minute."""
    config = dock_config(3, **alarm)
    t1, d1 = generate(config, seconds=90.0, seed=4)
    t2, d2 = generate(config, seconds=60.0, seed=5)
    off = int(90e9) + int(silence_s * 1e9)
    tensions = {
        k: (np.concatenate([t1[k][0], t2[k][0] + off]), np.concatenate([t1[k][1], t2[k][1]]))
        for k in t1
    }
    depth = (np.concatenate([d1[0], d2[0] + off]), np.concatenate([d1[1], d2[1]]))
    stamps = np.unique(np.concatenate([c[0] for c in (*tensions.values(), depth)]))
    return config, tensions, depth, stamps


def _cut_grid(config, stamps, quiet_s=None):
    quiet = int((quiet_span(config) if quiet_s is None else quiet_s) * 1e9)
    rate = config.alarm.diagnostic_rate
    return grid_ticks(int(stamps[0]), rate, 0, stamps, None, quiet, int(stamps[-1]))[0]


def test_a_node_ticking_through_a_silence_decides_what_the_grid_does() -> None:
    """The core stepped with every tick of a three-hour silence (a node running through it)
    and with the grid's (ticks only ``quiet_span`` into it) makes the same transitions and the
    same alarm journal: the flood that the silence's STALE alarms raised ends in it, ten
    minutes later, in both. A shorter span would not: the test is not vacuous."""
    config, tensions, depth, stamps = _silent_scene(3 * 3600, flood_count=2.0)
    start = int(stamps[0])
    full = tick_grid(start, int(stamps[-1]), config.alarm.diagnostic_rate)
    cut = _cut_grid(config, stamps)
    assert len(cut) < len(full) // 10
    _, node = core_steps(config, tensions, depth, full, start)
    _, grid = core_steps(config, tensions, depth, cut, start)
    journal = [e for s in node for e in s.alarm_events]
    assert journal == [e for s in grid for e in s.alarm_events]
    changes = [c for s in node for c in s.transitions]
    assert changes == [c for s in grid for c in s.transitions]
    silence = (stamps[stamps < start + 100 * SECOND][-1] * 1e-9, start * 1e-9 + 3 * 3600)
    ends = [e.time for e in journal if e.kind == 'flood_end']
    assert any(silence[0] + 500 < t < silence[1] for t in ends), ends
    _, short = core_steps(config, tensions, depth, _cut_grid(config, stamps, 300.0), start)
    assert [e for s in short for e in s.alarm_events] != journal


def test_the_twin_equals_the_core_on_a_grid_with_silences() -> None:
    """test_batch's comparison (every output, transition, journal record, snapshot and the
    state left) on the grid of a log with two silences, in windows cut inside them."""
    config, tensions, depth, stamps = _silent_scene(2 * 3600, flood_count=2.0)
    ticks = _cut_grid(config, stamps)
    start = int(stamps[0])
    cuts = [start + 95 * SECOND, start + 2000 * SECOND, start + 7290 * SECOND]
    # compare() starts the core at T0_NS: the scene's first stamp is after it.
    assert start >= T0_NS
    compare(config, tensions, depth, ticks, cuts)


@pytest.mark.parametrize('name', sorted(span_logs.FILES))
def test_a_span_file_streamed_in_small_windows_is_the_one_window_replay(
    files: dict[str, Path], name: str
) -> None:
    config = span_logs.config()
    notes: list[str] = []
    small = replay_log([files[name]], config, window_messages=7, notes=notes)
    one = replay_log([files[name]], config, window_messages=None)
    a, b = small.result, one.result
    assert a.tick_ns.tolist() == b.tick_ns.tolist()
    assert a.changes() == b.changes() and a.alarm_events == b.alarm_events
    assert (a.start_ns, a.end_ns) == (b.start_ns, b.end_ns)
    for ra, rb in zip(a.lines, b.lines):
        assert ra.t_ns.tolist() == rb.t_ns.tolist()
    assert a.start_ns > span_logs.T2026 - 3001 * DAY  # never 1970
    assert a.end_ns < span_logs.T2026 + 366 * DAY  # never 2100
    assert len(a.tick_ns) <= 2 * len(small.depth[0]) * (quiet_span(config) + 1)
    if name.startswith('stamp_'):
        assert notes and notes[0].startswith('bad stamps: 1 input sample(s)'), notes
    else:
        assert notes and notes[0].startswith('silences: '), notes


def test_the_log_view_refuses_more_ticks_than_it_holds(files: dict[str, Path]) -> None:
    with pytest.raises(ReplayError, match='more than 1000 periodic steps'):
        replay_log([files['daily']], span_logs.config(), snapshots=True, max_ticks=1000)


# --- the commands, from outside
# ---------------------------------------------------------------------------------


COMMANDS = {
    'replay': ['replay', '{f}'],
    'alarms': ['alarms', '{f}'],
    'console --log': ['console', '--log', '{f}', '--port', '0'],
}


def _run(argv: list[str], serve: bool) -> dict:
    r = subprocess.run(
        [sys.executable, '-c', WRAP, json.dumps(argv), 'serve' if serve else 'run'],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=400,
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.parametrize('name', sorted(span_logs.FILES))
@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_a_span_file_costs_its_bytes_in_every_command(
    files: dict[str, Path], command: str, name: str
) -> None:
    argv = [sys.executable, '-m', 'catenary_monitor', *COMMANDS[command]]
    got = _run([a.format(f=files[name]) for a in argv], command.startswith('console'))
    out, err = got['out'], got['err']
    print(f'{command} {name}: {got["rss_mb"]:.0f} MB, {got["cpu"]:.2f} s CPU, {got["wall"]:.1f} s')
    assert 'Traceback' not in err and len(err.strip().splitlines()) <= 1, err
    if command == 'console --log' and name == 'daily':  # 2.1 million snapshots: refused
        assert got['rc'] == 2 and 'more than' in err and 'periodic steps' in err, err
    else:
        assert got['rc'] == 0, err
    if command == 'console --log':
        said = err
        assert got['rc'] or out.startswith('console: http://'), out
    else:
        said = out
    if name.startswith('stamp_'):
        assert 'bad stamps: 1 input sample(s) stamped more than 365 days' in said, said
    elif got['rc'] == 0:
        assert 'days not ticked through' in said, said
    if command == 'replay':
        assert ('1970' in out) == (name == 'stamp_1970') and '2100-' not in out.split('\n')[0]
    assert got['rss_mb'] < RSS_LIMIT_MB, got['rss_mb']
    assert got['cpu'] < CPU_LIMIT_S, got['cpu']


def test_the_fleet_takes_every_span_file_in_bounded_memory(
    files: dict[str, Path], tmp_path: Path
) -> None:
    """``fleet`` over the span files as six docks, one worker (the cluster's processes counted
    in): every dock replayed, its bad stamp named, memory bounded; CPU within the six docks'
    allowance beside the cluster's start (the 3,000-day dock writes 9,000 one-row Parquet
    files: a file per dock and UTC day in each dataset)."""
    pytest.importorskip('distributed')
    docks = []
    for name, src in files.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / src.name).write_bytes(src.read_bytes())
        docks.append(str(tmp_path / name))
    argv = [sys.executable, '-m', 'catenary_monitor', 'fleet', *docks, '--out',
            str(tmp_path / 'results'), '--workers', '1', '--quiet']  # fmt: skip
    got = _run(argv, False)
    print(f'fleet: {got["rss_mb"]:.0f} MB, {got["cpu"]:.2f} s CPU, {got["wall"]:.1f} s')
    assert got['rc'] == 0 and 'Traceback' not in got['err'], got['err']
    rows = {line.split()[0]: line for line in got['out'].splitlines() if line.split()}
    for name in files:
        assert name in rows, got['out']
    assert 'bad stamps: 1 input sample(s)' in got['out'], got['out']
    assert got['rss_mb'] < RSS_LIMIT_MB, got['rss_mb']
    assert got['cpu'] < CPU_LIMIT_S * len(files), got['cpu']
