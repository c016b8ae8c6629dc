"""``catenary-monitor bench-replay``: replay speed against the obvious per-message loop.

Generates (seeded) a log shaped like the node's: the paper dock's 12 lines at 10 Hz and the tide
at 1 Hz, a storm that lifts line 11's anchor, zstd chunks of 512 KiB; ``--messages`` in total
(default 1e6). Then, in the same run:

* replay: decode + solve + alarms + CSV (``read_float64_topics``, :func:`recompute`,
  :func:`write_csv` to a file), messages per second over the whole log, the median of
  ``--repeat`` rounds (the machines are shared: one run can be slowed by another job);
* MCAP output of the same results (inputs, per-line outputs, /diagnostics), reported beside;
* baselines, the obvious per-message loops, timed on the first ``--baseline-messages`` messages
  of the same log (their rate does not depend on the log length): *same work* -- ``mcap_ros2``
  decoding of each message in log-time order, the node's schedule with the scalar ``solve()``
  and ``LineAlarm.update`` per update, ``csv.writer`` per tension row; *minimal* -- decoding, a
  scalar ``solve()`` per tension message at the newest depth, ``csv.writer`` (no alarms).
  Each round times replay and both baselines one after the other, and each is reported as its
  median over the rounds, so a burst of load elsewhere slows them alike.

Replay is the command's streamed path (:mod:`catenary_monitor.replay.driver`, ticks on a
grid); ``read_s`` is a read-only pass of the same log and ``solve_alarm_s`` the rest of the
summary run. The peak RSS of the command itself (summary, ``--csv``, ``--out``) is measured in
child processes (``os.wait4``); ``--no-rss`` skips it.

Targets: replay >= 1e6 messages/s and >= 20 times the baseline (checked against the
minimal one, the conservative choice). The machines are shared: read the ratios first.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.monitor.events import Depth, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.physics.solve import solve
from catenary_monitor.io.cdr import float64_payloads
from catenary_monitor.io.mcap_column_writer import ColumnWriter
from catenary_monitor.io.ros_schemas import QOS_SENSOR_DATA, message_definition

__all__ = ['dock_config', 'generate_log', 'run', 'register']

T0_NS = 1_763_900_000_000_000_000


def dock_config(lines: int = 12) -> MonitorConfig:
    """The paper dock (config/floating_dock.yaml values): line 11 at 121.06 m."""
    return MonitorConfig(
        lines=tuple(
            LineConfig(
                name=f'line_{k:02d}',
                weight=1300.0,
                anchor_distance=121.06 if k == 11 else 120.0,
                mbl=4827000.0,
            )
            for k in range(1, lines + 1)
        )
    )


def generate_log(
    path: Path,
    messages: int,
    config: MonitorConfig,
    seed: int = 1,
    rate: float = 10.0,
    depth_rate: float = 1.0,
    chunk_bytes: int = 512 * 1024,
    start_ns: int = T0_NS,
    storm_at: Optional[float] = None,
    storm_width: Optional[float] = None,
) -> dict[str, Any]:
    """Write a seeded dock log of about ``messages`` Float64 messages; returns its facts.

    Written in stretches of about a million messages, so that a log of 1e7 or more takes
    bounded memory. The storm (line_11 lifted) peaks ``storm_at`` s after ``T0_NS`` (default:
    mid-log) with a width of ``storm_width`` s (default a tenth of the log).
    """
    rng = np.random.default_rng(seed)
    n_lines = len(config.lines)
    per_second = n_lines * rate + depth_rate
    seconds = messages / per_second
    mid = seconds / 2 if storm_at is None else storm_at
    width = seconds / 10 if storm_width is None else storm_width
    stretch = max(1.0, 1e6 / per_second)  # s of log per stretch
    n_line = int(seconds * rate)  # per line; the depth takes the rest of ``messages``
    n_depth = messages - n_line * n_lines
    total = 0
    with open(path, 'wb') as f:
        w = ColumnWriter(f, chunk_bytes=chunk_bytes, level=3)
        sid = w.register_schema(
            'std_msgs/msg/Float64', 'ros2msg', message_definition('std_msgs/msg/Float64').encode()
        )
        meta = {'offered_qos_profiles': QOS_SENSOR_DATA}
        ids = [w.register_channel(line.tension_topic, 'cdr', sid, meta) for line in config.lines]
        depth_id = w.register_channel(config.depth_topic, 'cdr', sid, meta)
        lo = 0.0
        while lo < seconds:
            hi = min(seconds, lo + stretch)
            t_all, v_all, c_all = [], [], []
            base = start_ns + int(lo * 1e9)
            span = max(1, int((hi - lo) * 1e9))
            for k, line in enumerate(config.lines):
                n_t = int(n_line * hi / seconds) - int(n_line * lo / seconds)
                # a sensor's regular samples with receive jitter (a quarter period)
                slot = span / max(n_t, 1)
                jitter = rng.uniform(0.25, 0.75, n_t)
                t = base + ((np.arange(n_t) + jitter) * slot).astype(np.int64)
                s = (t - start_ns) * 1e-9
                storm = (1.25e6 if line.name == 'line_11' else 0.05e6) * np.exp(
                    -(((s - mid) / width) ** 2)
                )
                v = 372e3 + storm + 40e3 * np.sin(2 * np.pi * s / 9.0 + k)
                t_all.append(t)
                v_all.append(v + rng.normal(0, 4e3, n_t))
                c_all.append(np.full(n_t, ids[k]))
            n_d = int(n_depth * hi / seconds) - int(n_depth * lo / seconds)
            slot = span / max(n_d, 1)
            td = base + ((np.arange(n_d) + rng.uniform(0.25, 0.75, n_d)) * slot).astype(np.int64)
            t_all.append(td)
            v_all.append(20.85 + 1.2 * np.sin(2 * np.pi * (td - T0_NS) * 1e-9 / 44700.0))
            c_all.append(np.full(n_d, depth_id))
            t = np.concatenate(t_all)
            order = np.argsort(t, kind='stable')
            w.write_columns(
                np.concatenate(c_all)[order],
                t[order],
                float64_payloads(np.concatenate(v_all)[order]),
            )
            total += len(t)
            lo = hi
        w.finish()
    return {'messages': total, 'seconds': seconds, 'bytes': path.stat().st_size}


def generate_month(
    folder: Path,
    config: MonitorConfig,
    days: float = 30.0,
    rate: float = 1.0,
    depth_rate: float = 0.2,
    file_hours: float = 24.0,
) -> dict[str, Any]:
    """A rotated set: ``days`` of dock log, one file per ``file_hours`` (``rate`` Hz per line,
    a storm in the middle of the month); returns its facts."""
    folder.mkdir(parents=True, exist_ok=True)
    per_second = len(config.lines) * rate + depth_rate
    seconds = days * 86400.0
    n_files = int(math.ceil(days * 24.0 / file_hours))
    facts = {'files': n_files, 'messages': 0, 'bytes': 0, 'seconds': seconds}
    for k in range(n_files):
        lo = k * file_hours * 3600.0
        hi = min(seconds, lo + file_hours * 3600.0)
        part = generate_log(
            folder / f'catenary_monitor_{k:04d}.mcap',
            int((hi - lo) * per_second),
            config,
            seed=k + 1,
            rate=rate,
            depth_rate=depth_rate,
            start_ns=T0_NS + int(lo * 1e9),
            storm_at=seconds / 2 - lo,
            storm_width=3 * 3600.0,
        )
        facts['messages'] += part['messages']
        facts['bytes'] += part['bytes']
    return facts


def baseline(
    path: Path, config: MonitorConfig, limit: int, out: io.TextIOBase, alarms_too: bool = True
) -> int:
    """The obvious loop over the first ``limit`` messages; returns the messages handled.

    ``alarms_too``: every message decoded and stepped through the monitor core
    (:class:`~catenary_monitor.core.monitor.monitor_core.MonitorCore`, the node's own decision
    path: depth re-solves, periodic ticks, alarms) and a CSV row per tension; False: only decode, a
    scalar solve per tension message at the newest depth and a CSV row (the minimal loop, the
    conservative baseline).
    """
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    index = {line.tension_topic: k for k, line in enumerate(config.lines)}
    writer = csv.writer(out)
    writer.writerow(
        [
            'time',
            'line',
            'top_tension',
            'depth',
            'min_anchor_distance',
            'anchor_margin',
            'uplift_force',
            'level',
        ]
    )
    period = int(1e9 / config.alarm.diagnostic_rate)
    core: Optional[MonitorCore] = None
    next_tick, depth, n = 0, math.nan, 0
    with open(path, 'rb') as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages(
            topics=[config.depth_topic, *index], log_time_order=True
        ):
            stamp = message.log_time
            n += 1
            if not alarms_too:
                if channel.topic == config.depth_topic:
                    depth = decoded.data
                else:
                    line = config.lines[index[channel.topic]]
                    r = solve(
                        line.weight,
                        depth + line.hook_height,
                        tension=decoded.data,
                        anchor_distance=line.anchor_distance,
                        mbl=line.mbl,
                    )
                    writer.writerow(
                        [
                            repr(stamp * 1e-9),
                            line.name,
                            repr(decoded.data),
                            repr(depth),
                            repr(r.min_anchor_distance),
                            repr(r.anchor_margin),
                            repr(r.uplift_force),
                        ]
                    )
            else:
                if core is None:
                    core, next_tick = MonitorCore(config, stamp), stamp
                while next_tick < stamp:
                    core.step(Tick(next_tick))
                    next_tick += period
                if channel.topic == config.depth_topic:
                    core.step(Depth(stamp, decoded.data))
                else:
                    k = index[channel.topic]
                    step = core.step(Tension(stamp, k, decoded.data))
                    v = step.outputs[0].values
                    writer.writerow(
                        [
                            repr(stamp * 1e-9),
                            config.lines[k].name,
                            repr(v[0]),
                            repr(v[1]),
                            repr(v[3]),
                            repr(v[4]),
                            repr(v[5]),
                            core.state.lines[k].state.level.name,
                        ]
                    )
            if n >= limit:
                break
    return n


def run(
    messages: int = 1_000_000,
    baseline_messages: int = 50_000,
    workdir: str | None = None,
    chunk_bytes: int = 512 * 1024,
    repeat: int = 3,
    measure_rss: bool = True,
    measure_mcap: bool = True,
    line_processes: Optional[int] = None,
) -> dict[str, Any]:
    """Generate the log, time replay and the two baselines (``repeat`` interleaved rounds, the
    median of each) and the MCAP output; returns the figures. ``line_processes``: the
    summary's child command's ``--line-processes`` (None: the command's default)."""

    config = dock_config()
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        log = Path(tmp) / 'dock.mcap'
        t0 = time.perf_counter()
        facts = generate_log(log, messages, config, chunk_bytes=chunk_bytes)
        gen_s = time.perf_counter() - t0
        log.read_bytes()  # warm the page cache: time the work, not the disk
        runs, base_runs, base_min_runs = [], [], []
        for _ in range(max(1, repeat)):  # rounds: a burst of load slows replay and baselines alike
            read_s = _time_read(log, config)
            t0 = time.perf_counter()
            tally, _ = _streamed(log, config)
            t1 = time.perf_counter()
            with open(Path(tmp) / 'out.csv', 'wb', buffering=1 << 20) as f:
                _, rows = _streamed(log, config, csv=f)
            t2 = time.perf_counter()
            runs.append((t2 - t1, read_s, (t1 - t0) - read_s, (t2 - t1) - (t1 - t0), t1 - t0))
            t4 = time.perf_counter()
            done = baseline(log, config, baseline_messages, io.StringIO())
            base_runs.append(time.perf_counter() - t4)
            t5 = time.perf_counter()
            done_min = baseline(log, config, baseline_messages, io.StringIO(), alarms_too=False)
            base_min_runs.append(time.perf_counter() - t5)
        runs.sort()
        base_s = sorted(base_runs)[len(base_runs) // 2]
        base_min_s = sorted(base_min_runs)[len(base_min_runs) // 2]
        replay_s, read_s, solve_s, csv_s, summary_s = runs[len(runs) // 2]  # the median run
        best_s = runs[0][0]
        csv_bytes = (Path(tmp) / 'out.csv').stat().st_size
        t2 = time.perf_counter()
        written, out_bytes = 0, 0
        if measure_mcap:
            with open(Path(tmp) / 'out.mcap', 'wb', buffering=1 << 20) as f:
                _, written = _streamed(log, config, mcap=f)
            out_bytes = (Path(tmp) / 'out.mcap').stat().st_size
        t3 = time.perf_counter()
        rss = {}
        if measure_rss:
            rss = peak_rss(log, config, Path(tmp), line_processes=line_processes)
        updates = sum(t.updates for t in tally.lines)
        transitions = sum(len(t.transitions) for t in tally.lines)
    n = facts['messages']
    rate = n / replay_s
    base_rate = done / base_s
    base_min_rate = done_min / base_min_s
    return {
        'messages': n,
        'log_bytes': facts['bytes'],
        'log_seconds': round(facts['seconds'], 1),
        'generate_s': round(gen_s, 3),
        'chunk_bytes': chunk_bytes,
        'repeat': len(runs),
        'replay_s': round(replay_s, 3),
        'replay_best_s': round(best_s, 3),
        'replay_best_msg_per_s': round(n / best_s),
        'read_s': round(read_s, 3),
        'solve_alarm_s': round(solve_s, 3),
        'csv_s': round(csv_s, 3),
        'csv_rows': rows,
        'csv_bytes': csv_bytes,
        'replay_msg_per_s': round(rate),
        # read, recompute, levels and summary (no output file), same median run
        'replay_summary_s': round(summary_s, 3),
        'replay_summary_msg_per_s': round(n / summary_s),
        'target_summary_rate_met': n / summary_s >= 2e6,
        'updates': updates,
        'transitions': transitions,
        'peak_rss_mb': rss,
        'mcap_out_s': round(t3 - t2, 3),
        'mcap_out_messages': written,
        'mcap_out_msg_per_s': round(written / max(t3 - t2, 1e-9)),
        'mcap_out_bytes': out_bytes,
        'baseline_messages': done,
        'baseline_s': round(base_s, 3),
        'baseline_msg_per_s': round(base_rate),
        'baseline_minimal_msg_per_s': round(base_min_rate),
        'speedup': round(rate / base_rate, 1),
        'speedup_vs_minimal': round(rate / base_min_rate, 1),
        'target_rate_met': rate >= 1e6,
        'target_speedup_met': rate / base_min_rate >= 20,
    }


def _streamed(log: Path, config: MonitorConfig, csv: Any = None, mcap: Any = None) -> Any:
    """The streamed replay of the command (ticks on a grid) into a summary tally and, if
    given, a CSV or a results MCAP; returns (tally, CSV rows or MCAP messages)."""
    from catenary_monitor.core.twin.window import COLUMNS
    from catenary_monitor.replay import outputs as out
    from catenary_monitor.replay.driver import input_topics, stream

    names = [line.name for line in config.lines]
    tally = out.Tally(names)
    topics, depth_topic = input_topics(config)
    sink = out.McapSink(mcap, config, names, topics, depth_topic) if mcap is not None else None
    rows = [0]

    def take(result: Any, window: Any) -> None:
        tally.add(result)
        if csv is not None:
            rows[0] += out.write_csv(csv, result, None, out.CSV_COLUMNS, header=not rows[0])
        if sink is not None:
            sink.write(result, dict(zip(names, window.tensions)), window.depth)

    stream([log], config, take, ticks='grid', snapshots=COLUMNS if sink is not None else False)
    return tally, (sink.finish() if sink is not None else rows[0])


def _time_read(log: Path, config: MonitorConfig) -> float:
    """Seconds to read the log's input columns window by window (no recompute)."""
    from catenary_monitor.io.mcap_read import iter_windows
    from catenary_monitor.replay.driver import input_topics

    topics, depth_topic = input_topics(config)
    t0 = time.perf_counter()
    for _ in iter_windows([log], [depth_topic, *topics.values()]):
        pass
    return time.perf_counter() - t0


def peak_rss(
    logs: Any,
    config: MonitorConfig,
    tmp: Path,
    extra: tuple[str, ...] = (),
    modes: tuple[str, ...] = ('summary', 'csv', 'out'),
    line_processes: Optional[int] = None,
) -> dict[str, Any]:
    """Peak RSS (MB) and wall time (s) of ``catenary-monitor replay`` in a child process, for
    the summary only, ``--csv`` and ``--out``: the child's ``VmHWM`` (Linux), which starts
    afresh at ``exec`` (``ru_maxrss`` of a forked child keeps the parent's high-water mark),
    and the RSS of the child and its line worker summed (polled). ``line_processes``: the
    summary's ``--line-processes`` (None: the command's default)."""
    import subprocess

    params = tmp / 'bench_params.yaml'
    _params_file(config, params)
    logs = [str(p) for p in (logs if isinstance(logs, (list, tuple)) else [logs])]
    out: dict[str, Any] = {}
    for mode, args in (
        ('summary', [] if line_processes is None else ['--line-processes', str(line_processes)]),
        ('csv', ['--csv', str(tmp / 'rss.csv')]),
        ('out', ['--out', str(tmp / 'rss.mcap')]),
    ):
        if mode not in modes:
            continue
        cmd = [sys.executable, '-c', _CHILD, 'replay', *logs]
        cmd += ['--params-file', str(params), '--quiet', '--json', *args, *extra]
        t0, cpu0 = time.perf_counter(), _children_cpu()
        tree_kb = 0
        with subprocess.Popen(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        ) as proc:
            while proc.poll() is None:  # the summed RSS of the child and its line worker
                tree_kb = max(tree_kb, _tree_rss_kb(proc.pid))
                time.sleep(0.005)
            stdout, stderr = proc.communicate()
        wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
        summary = json.loads(stdout) if proc.returncode == 0 else {}
        hwm = [ln for ln in stderr.splitlines() if ln.startswith('VmHWM:')]
        own = round(int(hwm[-1].split()[1]) / 1024, 1) if hwm else None
        out[mode] = {
            'rss_mb': own,
            'tree_rss_mb': max(own or 0.0, round(tree_kb / 1024, 1)),
            'wall_s': round(wall, 2),
            'cpu_s': round(cpu, 2),
            'replay_s': summary.get('timing', {}).get('total_s'),
            'exit': proc.returncode,
        }
        for f in (tmp / 'rss.csv', tmp / 'rss.mcap'):
            f.unlink(missing_ok=True)
    return out


def _tree_rss_kb(pid: int) -> int:
    """The summed VmRSS (kB) of process ``pid`` and its descendants now (Linux; 0 elsewhere):
    replay's line worker (``--line-processes``) counted beside the command."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            with open(f'/proc/{p}/status') as f:
                total += sum(int(ln.split()[1]) for ln in f if ln.startswith('VmRSS:'))
            for task in os.listdir(f'/proc/{p}/task'):
                with open(f'/proc/{p}/task/{task}/children') as f:
                    todo += [int(c) for c in f.read().split()]
        except (OSError, ValueError):
            continue
    return total


def _children_cpu() -> float:
    """User + system seconds of this process's finished children."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


#: End to end, the command as a user runs it (the summary of the log): at least this rate
#: (messages over the child's wall time) and at most this peak RSS (MiB, VmHWM).
TARGET_END_TO_END = 2.5e6
TARGET_RSS_MB = 210.0

#: The child of :func:`peak_rss`: the command, then its peak RSS on stderr.
_CHILD = (
    'import sys\n'
    'from catenary_monitor.cli.main import main\n'
    'code = main(sys.argv[1:])\n'
    'sys.stdout.flush()\n'
    'hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]\n'
    'sys.stderr.write(hwm[0] if hwm else "")\n'
    'sys.exit(code)\n'
)


def _params_file(config: MonitorConfig, path: Path) -> None:
    from catenary_monitor.core.config.parameters import config_to_params, params_file_text

    path.write_text(params_file_text(config_to_params(config)))


def cmd_bench_replay(args: argparse.Namespace) -> int:
    """Print the benchmark figures (table or JSON)."""
    if args.workdir and not Path(args.workdir).is_dir():
        print(f'bench-replay: --workdir {args.workdir}: no such directory', file=sys.stderr)
        return 2
    r = run(
        args.messages,
        args.baseline_messages,
        args.workdir,
        args.chunk_bytes,
        args.repeat,
        not args.no_rss,
        not args.no_mcap,
        args.line_processes,
    )
    if args.json:
        print(json.dumps(r))
        return 0
    print(
        f'log: {r["messages"]} messages ({r["log_bytes"] / 1e6:.1f} MB, '
        f'{r["log_seconds"]:.0f} s of dock time, {r["chunk_bytes"] // 1024} KiB chunks), '
        f'generated in {r["generate_s"]:.2f} s'
    )
    print(
        f'replay (decode + solve + alarms + CSV), median of {r["repeat"]} runs: '
        f'{r["replay_s"]:.3f} s = {r["replay_msg_per_s"] / 1e6:.2f} M msg/s (best '
        f'{r["replay_best_msg_per_s"] / 1e6:.2f})  [read {r["read_s"]:.3f} s, '
        f'solve+alarms {r["solve_alarm_s"]:.3f} s, CSV {r["csv_s"]:.3f} s for '
        f'{r["csv_rows"]} rows / {r["csv_bytes"] / 1e6:.0f} MB]'
    )
    print(
        f'replay without output files (read, recompute, levels, summary), the same median run: '
        f'{r["replay_summary_s"]:.3f} s = {r["replay_summary_msg_per_s"] / 1e6:.2f} M msg/s '
        f'(target >= 2 M msg/s: {"met" if r["target_summary_rate_met"] else "NOT met"})'
    )
    if r['mcap_out_messages']:
        print(
            f'MCAP output: {r["mcap_out_messages"]} messages in {r["mcap_out_s"]:.3f} s = '
            f'{r["mcap_out_msg_per_s"] / 1e6:.2f} M msg/s ({r["mcap_out_bytes"] / 1e6:.0f} MB)'
        )
    print(
        f'baseline, same work (mcap_ros2 decode, node schedule with scalar solve and alarm, '
        f'csv.writer; first {r["baseline_messages"]} messages): '
        f'{r["baseline_msg_per_s"] / 1e3:.1f} k msg/s -> speed-up {r["speedup"]:.1f}x'
    )
    print(
        f'baseline, minimal (mcap_ros2 decode, scalar solve per tension, csv.writer): '
        f'{r["baseline_minimal_msg_per_s"] / 1e3:.1f} k msg/s -> speed-up '
        f'{r["speedup_vs_minimal"]:.1f}x'
    )
    print(
        f'targets: >= 1e6 msg/s {"met" if r["target_rate_met"] else "NOT met"}; >= 20x the '
        f'minimal baseline {"met" if r["target_speedup_met"] else "NOT met"}'
    )
    for mode, m in r['peak_rss_mb'].items():
        print(
            f'peak RSS, catenary-monitor replay ({mode}, a child process): {m["rss_mb"]:.0f} MB '
            f'(with its line worker, summed: {m["tree_rss_mb"]:.0f} MB), '
            f'{m["wall_s"]:.2f} s wall, {m["cpu_s"]:.2f} s CPU ({m["replay_s"]} s in replay)'
        )
    m = r['peak_rss_mb'].get('summary')
    if m:
        wall_rate, cpu_rate = r['messages'] / m['wall_s'], r['messages'] / max(m['cpu_s'], 1e-9)
        rate_ok, rss_ok = wall_rate >= TARGET_END_TO_END, m['tree_rss_mb'] <= TARGET_RSS_MB
        print(
            f'end to end (catenary-monitor replay LOG, its summary, default bounds): '
            f'{wall_rate / 1e6:.2f} M msg/s ({cpu_rate / 1e6:.2f} M per CPU second), peak '
            f'{m["tree_rss_mb"]:.0f} MB (summed over its processes); targets >= '
            f'{TARGET_END_TO_END / 1e6:g} M msg/s {"met" if rate_ok else "NOT met"}, '
            f'<= {TARGET_RSS_MB:g} MB {"met" if rss_ok else "NOT met"}'
        )
    return 0


def register(sub: Any) -> None:
    """Add ``bench-replay`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-replay',
        help='replay speed vs the per-message loop (benchmark)',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument(
        '--messages',
        type=int,
        default=1_000_000,
        help='messages in the generated log (default 1e6)',
    )
    p.add_argument(
        '--baseline-messages',
        type=int,
        default=50_000,
        help='messages timed for the baseline loop (default 50 000)',
    )
    p.add_argument(
        '--repeat',
        type=int,
        default=3,
        help='rounds of replay and baselines; medians are reported (default 3)',
    )
    p.add_argument(
        '--chunk-bytes',
        type=int,
        default=512 * 1024,
        help='uncompressed chunk size of the generated log (default 512 KiB, the '
        "node logger's; 4096 is about the 0.75 s the node flushes at 10 Hz)",
    )
    p.add_argument(
        '--workdir', default=os.environ.get('TMPDIR'), help='directory for the temporary files'
    )
    p.add_argument(
        '--no-rss',
        action='store_true',
        help='skip the peak-RSS runs (the command in a child process: summary, --csv, --out)',
    )
    p.add_argument(
        '--no-mcap', action='store_true', help='skip the MCAP output (slow: every snapshot)'
    )
    p.add_argument(
        '--line-processes',
        type=int,
        default=None,
        metavar='N',
        help="the summary's peak-RSS run with replay --line-processes N (default: the "
        "command's own default)",
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_replay)


def main(argv: Optional[list[str]] = None) -> int:
    """``python -m catenary_monitor_study.bench_replay log PATH --messages N`` or ``month DIR
    [--days D] [--rate HZ] [--file-hours H]``: write the benchmark's logs (and a params file
    beside them, ``bench_params.yaml``) for measuring the command by hand."""
    parser = argparse.ArgumentParser(prog='python -m catenary_monitor_study.bench_replay')
    sub = parser.add_subparsers(dest='what', required=True)
    one = sub.add_parser('log', help='one log file')
    one.add_argument('path', type=Path)
    one.add_argument('--messages', type=int, default=1_000_000)
    month = sub.add_parser('month', help='a folder of daily files')
    month.add_argument('path', type=Path)
    month.add_argument('--days', type=float, default=30.0)
    month.add_argument('--rate', type=float, default=1.0, help='Hz per line (default 1)')
    month.add_argument('--file-hours', type=float, default=24.0)
    args = parser.parse_args(argv)
    config = dock_config()
    t0 = time.perf_counter()
    if args.what == 'log':
        facts = generate_log(args.path, args.messages, config)
        _params_file(config, args.path.parent / 'bench_params.yaml')
    else:
        facts = generate_month(args.path, config, args.days, args.rate, 0.2, args.file_hours)
        _params_file(config, args.path.parent / 'bench_params.yaml')
    facts['generate_s'] = round(time.perf_counter() - t0, 1)
    print(json.dumps(facts))
    return 0


if __name__ == '__main__':
    sys.exit(main())
