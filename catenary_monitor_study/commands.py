"""The study's sub-commands for ``catenary-monitor`` (entry point ``catenary_monitor.commands``).

``bench``, ``bench-methods``, ``bench-replay`` and ``bench-latency`` measure the monitor against
baselines in the same run; ``bench-alarms`` counts its annunciations on generated normal days and
injected faults; ``fuzz`` fuzzes what reads untrusted bytes. They live outside the monitor's
runtime import graph: the command line finds this module through its entry point, and nothing in
``catenary_monitor`` imports it.
"""

from __future__ import annotations

import argparse
import functools
from typing import Any

from catenary_monitor.cli.allocator import keep_freed_memory

__all__ = ['register']


def cmd_bench_latency(args: argparse.Namespace) -> int:
    """Tension-to-result latency across processes against a bare rclpy echo node."""
    from catenary_monitor_study.bench_latency import run_bench

    return run_bench(
        lines=args.lines,
        rate=args.rate,
        duration=args.duration,
        json_out=args.json,
        ea=args.ea,
        params_file=args.params_file,
    )


def _batch(func: Any) -> Any:
    """A batch command on large arrays: keep freed memory for reuse (see cli.allocator)."""

    @functools.wraps(func)
    def run(args: argparse.Namespace) -> int:
        keep_freed_memory()
        return int(func(args) or 0)

    return run


def register(sub: Any) -> None:
    """Add the benchmark sub-commands to the ``catenary-monitor`` parser."""
    from catenary_monitor_study import (
        bench_alarms,
        bench_body,
        bench_bounds,
        bench_dynamics,
        bench_console,
        bench_core,
        bench_fleet,
        bench_flood,
        bench_harbour,
        bench_step,
        bench_methods,
        bench_point_loads,
        bench_replay,
        bench_soak,
        fuzz,
    )

    bench_console.register(sub)
    bench_alarms.register(sub)
    bench_body.register(sub)
    bench_point_loads.register(sub)
    bench_dynamics.register(sub)
    bench_soak.register(sub)
    bench_flood.register(sub)
    bench_step.register(sub)
    bench_bounds.register(sub)
    bench_fleet.register(sub)
    bench_harbour.register(sub)
    fuzz.register(sub)
    for module in (bench_core, bench_methods, bench_replay):
        module.register(sub)
    # bench runs as a library user's process (glibc defaults; --keep-freed-memory to compare)
    for name in ('bench-methods', 'bench-replay'):
        parser = sub.choices[name]
        parser.set_defaults(func=_batch(parser.get_default('func')))
    p = sub.add_parser(
        'bench-latency',
        help='latency and CPU of the node vs a bare echo node',
        description='Measure tension message -> published result latency '
        'across processes (median, p99) for the monitor (the paper\'s dock) and for a '
        'bare rclpy echo node in the same run, the CPU use, and that every sample was '
        'logged and stepped.',
    )
    p.add_argument(
        '--lines', type=int, default=12, help='the dock\'s first N lines (default: 12)'
    )
    p.add_argument('--rate', type=float, default=20.0, help='rate per line [Hz] (default: 20)')
    p.add_argument(
        '--duration', type=float, default=20.0, help='measuring time per node [s] (default: 20)'
    )
    p.add_argument(
        '--ea',
        type=float,
        default=None,
        metavar='N',
        help='axial stiffness EA [N] on every line: measures the elastic model '
        '(e.g. 6.63e8 for the U3 81 mm chain; default: inextensible)',
    )
    p.add_argument(
        '--params-file', metavar='F', help="the monitor's lines (default: the paper's dock)"
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_latency)
