"""What replay's ``--out`` costs beside the recompute: the diagnostic snapshots and the heap.

``python -m catenary_monitor_study.bench_out snapshots LOG PARAMS`` streams the log as the
command does (``--out``'s windows and parts, ticks on a grid) three ways in one process, twice:
without snapshots, with the snapshots in columns (``snapshots=COLUMNS``, what ``--out`` builds)
and as Snapshot objects (``snapshots=True``), encoding every snapshot's DiagnosticArray (nothing
written): the difference to the first is what the snapshots cost, per snapshot.

``python -m catenary_monitor_study.bench_out heap LOG PARAMS [--windows N]`` runs ``--out``
into a temporary file and prints every 10 windows the process's peak and current RSS and glibc's
heap (``mallinfo2``: the heap's size, in use, free, free blocks): memory in use that grows with
the log shows in ``inuse``, a scattered heap in ``free`` and ``nfree``.
"""

from __future__ import annotations

import argparse
import ctypes
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

from catenary_monitor.cli.allocator import keep_freed_memory
from catenary_monitor.replay.outputs import McapSink, snapshot_payloads
from catenary_monitor.core.twin.window import COLUMNS
from catenary_monitor.replay.driver import WINDOW_MESSAGES, input_topics, load_config, stream


class _MallInfo2(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            'arena',
            'ordblks',
            'smblks',
            'hblks',
            'hblkhd',
            'usmblks',
            'fsmblks',
            'uordblks',
            'fordblks',
            'keepcost',
        )
    ]


def _heap() -> str:
    libc = ctypes.CDLL('libc.so.6')
    libc.mallinfo2.restype = _MallInfo2
    m = libc.mallinfo2()
    return (
        f'heap {m.arena / 1e6:.1f} MB, in use {m.uordblks / 1e6:.1f} MB, '
        f'free {m.fordblks / 1e6:.1f} MB in {m.ordblks} blocks'
    )


def _rss() -> str:
    found = {}
    with open('/proc/self/status') as f:
        for line in f:
            key = line.split(':')[0]
            if key in ('VmHWM', 'VmRSS'):
                found[key] = int(line.split()[1]) / 1e3
    return f'peak RSS {found["VmHWM"]:.1f} MB, RSS {found["VmRSS"]:.1f} MB'


def snapshots(log: Path, params: Path) -> None:
    config = load_config(str(params))
    for _ in range(2):
        for mode in (False, COLUMNS, True):
            count, encode = [0], [0.0]

            def take(result: Any, window: Any) -> None:
                if mode:
                    t = time.perf_counter()
                    _, payloads = snapshot_payloads(result)
                    encode[0] += time.perf_counter() - t
                    count[0] += len(payloads)

            t0 = time.perf_counter()
            stream([log], config, take, snapshots=mode, window_messages=WINDOW_MESSAGES // 2)
            print(
                f'snapshots={mode!s:7}: {time.perf_counter() - t0:6.2f} s, {count[0]} '
                f'DiagnosticArrays (of which encoding {encode[0]:.2f} s)',
                flush=True,
            )


def heap(log: Path, params: Path, windows: Optional[int]) -> None:
    config = load_config(str(params))
    names = [line.name for line in config.lines]
    topics, depth_topic = input_topics(config)
    with tempfile.TemporaryFile() as f:
        sink = McapSink(f, config, names, topics, depth_topic)

        def take(result: Any, window: Any) -> None:
            sink.write(result, dict(zip(names, window.tensions)), window.depth)

        def progress(state: Any) -> None:
            if state.windows % 10 == 0:
                print(f'window {state.windows}: {_rss()}; {_heap()}', flush=True)
                if windows and state.windows >= windows:
                    raise KeyboardInterrupt

        try:
            stream(
                [log],
                config,
                take,
                ticks='grid',
                snapshots=COLUMNS,
                window_messages=WINDOW_MESSAGES // 2,
                progress=progress,
            )
        except KeyboardInterrupt:
            return
        sink.finish()
        print(f'finished: {_rss()}; {_heap()}')


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m catenary_monitor_study.bench_out')
    sub = parser.add_subparsers(dest='what', required=True)
    for name in ('snapshots', 'heap'):
        p = sub.add_parser(name)
        p.add_argument('log', type=Path)
        p.add_argument('params', type=Path)
        if name == 'heap':
            p.add_argument('--windows', type=int, default=None)
    args = parser.parse_args(argv)
    keep_freed_memory()  # as the command does
    if args.what == 'snapshots':
        snapshots(args.log, args.params)
    else:
        heap(args.log, args.params, args.windows)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
