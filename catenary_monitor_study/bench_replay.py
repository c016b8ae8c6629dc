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

Targets (issue 4): replay >= 1e6 messages/s and >= 20 times the baseline (checked against the
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

from catenary_monitor.core.config import LineConfig, MonitorConfig
from catenary_monitor.core.monitor import Depth, MonitorCore, Tension, Tick
from catenary_monitor.core.solve import solve
from catenary_monitor.io.cdr import float64_payloads
from catenary_monitor.io.mcap_fast import ColumnWriter
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
) -> dict[str, Any]:
    """Write a seeded dock log of about ``messages`` Float64 messages; returns its facts."""
    rng = np.random.default_rng(seed)
    n_lines = len(config.lines)
    per_second = n_lines * rate + depth_rate
    seconds = messages / per_second
    n_t = int(seconds * rate)
    n_d = messages - n_t * n_lines
    t_all, v_all, c_all = [], [], []
    with open(path, 'wb') as f:
        w = ColumnWriter(f, chunk_bytes=chunk_bytes, level=3)
        sid = w.register_schema(
            'std_msgs/msg/Float64', 'ros2msg', message_definition('std_msgs/msg/Float64').encode()
        )
        meta = {'offered_qos_profiles': QOS_SENSOR_DATA}
        for k, line in enumerate(config.lines):
            cid = w.register_channel(line.tension_topic, 'cdr', sid, meta)
            t = T0_NS + np.sort(rng.integers(0, int(seconds * 1e9), n_t))
            s = (t - T0_NS) * 1e-9
            storm = (1.25e6 if line.name == 'line_11' else 0.05e6) * np.exp(
                -(((s - seconds / 2) / (seconds / 10)) ** 2)
            )
            v = 372e3 + storm + 40e3 * np.sin(2 * np.pi * s / 9.0 + k) + rng.normal(0, 4e3, n_t)
            t_all.append(t)
            v_all.append(v)
            c_all.append(np.full(n_t, cid))
        cid = w.register_channel(config.depth_topic, 'cdr', sid, meta)
        td = T0_NS + np.sort(rng.integers(0, int(seconds * 1e9), n_d))
        t_all.append(td)
        v_all.append(20.85 + 1.2 * np.sin(2 * np.pi * (td - T0_NS) * 1e-9 / 44700.0))
        c_all.append(np.full(n_d, cid))
        t = np.concatenate(t_all)
        order = np.argsort(t, kind='stable')
        w.write_columns(
            np.concatenate(c_all)[order], t[order], float64_payloads(np.concatenate(v_all)[order])
        )
        w.finish()
    return {'messages': int(len(t)), 'seconds': seconds, 'bytes': path.stat().st_size}


def baseline(
    path: Path, config: MonitorConfig, limit: int, out: io.TextIOBase, alarms_too: bool = True
) -> int:
    """The obvious loop over the first ``limit`` messages; returns the messages handled.

    ``alarms_too``: every message decoded and stepped through the monitor core
    (:class:`~catenary_monitor.core.monitor.MonitorCore`, the node's own decision path: depth
    re-solves, periodic ticks, alarms) and a CSV row per tension; False: only decode, a scalar
    solve per tension message at the newest depth and a CSV row (the minimal loop, the
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
                            core.lines[k].state.level.name,
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
) -> dict[str, Any]:
    """Generate the log, time replay and the two baselines (``repeat`` interleaved rounds, the
    median of each) and the MCAP output; returns the figures."""
    from catenary_monitor.cli.replay import input_topics, run_replay
    from catenary_monitor.cli.replay_output import write_csv, write_mcap

    config = dock_config()
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        log = Path(tmp) / 'dock.mcap'
        t0 = time.perf_counter()
        facts = generate_log(log, messages, config, chunk_bytes=chunk_bytes)
        gen_s = time.perf_counter() - t0
        log.read_bytes()  # warm the page cache: time the work, not the disk
        runs, base_runs, base_min_runs = [], [], []
        for _ in range(max(1, repeat)):  # rounds: a burst of load slows replay and baselines alike
            t0 = time.perf_counter()
            result, tensions, depth, report, timing = run_replay([log], config, ticks='grid')
            t1 = time.perf_counter()
            with open(Path(tmp) / 'out.csv', 'wb', buffering=1 << 20) as f:
                rows = write_csv(f, result)
            t2 = time.perf_counter()
            runs.append((t2 - t0, timing['read_s'], timing['solve_s'], t2 - t1, t1 - t0))
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
        topics, depth_topic = input_topics(config)
        t2 = time.perf_counter()
        with open(Path(tmp) / 'out.mcap', 'wb', buffering=1 << 20) as f:
            written = write_mcap(f, result, config, tensions, depth, topics, depth_topic)
        t3 = time.perf_counter()
        out_bytes = (Path(tmp) / 'out.mcap').stat().st_size
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
        # issue 13: read, recompute, levels and summary (no output file), same median run
        'replay_summary_s': round(summary_s, 3),
        'replay_summary_msg_per_s': round(n / summary_s),
        'target_summary_rate_met': n / summary_s >= 2e6,
        'updates': result.updates,
        'transitions': sum(len(r.transitions) for r in result.lines),
        'mcap_out_s': round(t3 - t2, 3),
        'mcap_out_messages': written,
        'mcap_out_msg_per_s': round(written / (t3 - t2)),
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


def cmd_bench_replay(args: argparse.Namespace) -> int:
    """Print the benchmark figures (table or JSON)."""
    r = run(args.messages, args.baseline_messages, args.workdir, args.chunk_bytes, args.repeat)
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
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_replay)


if __name__ == '__main__':  # pragma: no cover
    sys.exit(
        cmd_bench_replay(
            argparse.Namespace(
                messages=1_000_000,
                baseline_messages=50_000,
                workdir=None,
                json=False,
                repeat=3,
                chunk_bytes=512 * 1024,
            )
        )
    )
