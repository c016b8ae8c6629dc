"""``catenary-monitor bench-body``: the dock model's speed against MoorPy in the same run.

The paper's dock (config/floating_dock.yaml, 12 lines), inextensible and with EA = 6.63e8 N on
every line: one static equilibrium (surge, sway, yaw) under each of a set of loads (six
directions, a yaw moment, wind and waves), by :func:`catenary_monitor.core.body.equilibrium.
solve_equilibrium` from rest and by MoorPy's ``System.solveEquilibrium`` on the same system (one
free body, DOFs 0, 1, 5; its tolerance 1e-4 m), interleaved, medians of ``--repeats`` rounds;
and the live dock estimate of one tick (``core.rules.dock_watch.decide_dock`` with one tick,
as the node runs it) and per tick when replay does a whole log at once. The machines are shared and
noisy: compare the ratios.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from typing import Any, Callable

import numpy as np

os.environ.setdefault('PYTHONBREAKPOINT', '0')

__all__ = ['run', 'register']


def _model(params_file: str) -> tuple[Any, Any]:
    from catenary_monitor.core.body.dock_model import DockModel
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file

    config = config_from_params(load_params_file(params_file))
    return config, DockModel.from_config(config)


def _loads(config: Any) -> list[np.ndarray]:
    from catenary_monitor.core.body.loads import environmental_load, push_direction

    out = []
    for phi in (0.0, 45.0, 100.0, 200.0, 270.0, 315.0):
        push = push_direction(phi)
        out.append(np.array([push[0] * 1.5e6, push[1] * 1.5e6, 0.0]))
    out.append(np.array([2e5, -5e5, 4e7]))
    out.append(environmental_load(config.dock, wind=25.0, wind_from=290.0, hs=1.5).total)
    return out


def _time(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def run(params_file: str, repeats: int = 5, ticks: int = 600) -> dict[str, Any]:
    """Every figure (ms per solve, ratios, ms per tick of the dock estimate)."""
    from catenary_monitor.core.body.equilibrium import solve_equilibrium
    from catenary_monitor_study.body_peer import moorpy_equilibrium, moorpy_system

    config, rigid = _model(params_file)
    loads = _loads(config)
    out: dict[str, Any] = {'lines': len(rigid.names), 'loads': len(loads), 'repeats': repeats}
    depth = 20.85
    for kind, model in (
        ('inextensible', rigid),
        ('elastic', dataclasses.replace(rigid, ea=np.full(len(rigid.names), 6.63e8))),
    ):
        system = moorpy_system(model, depth)
        ours, peer, iters = [], [], []
        for _ in range(repeats):
            for load in loads:
                ours.append(_time(lambda: solve_equilibrium(model, depth, load)))
                peer.append(
                    _time(lambda: moorpy_equilibrium(model, depth, load, tol=1e-4, system=system))
                )
        iters = [solve_equilibrium(model, depth, load).iterations for load in loads]
        a, b = float(np.median(ours)) * 1e3, float(np.median(peer)) * 1e3
        out[kind] = {
            'catenary_monitor_ms': a,
            'moorpy_ms': b,
            'moorpy_over_ours': b / a,
            'newton_iterations_median': float(np.median(iters)),
        }
    out['estimate'] = _estimate_figures(config, rigid, ticks)
    return out


def _estimate_figures(config: Any, model: Any, ticks: int) -> dict[str, float]:
    """The live dock estimate: ms per tick one at a time, and per tick over a whole log."""
    from catenary_monitor.core.body.equilibrium import solve_equilibrium
    from catenary_monitor.core.rules import dock_watch

    rng = np.random.default_rng(1)
    eq = solve_equilibrium(model, 20.85, np.array([0.0, -1.5e6, 0.0]))
    assert eq.lines is not None
    truth = eq.lines.statics.top_tension
    tensions = truth[None, :] + rng.normal(0.0, 20e3, (ticks, len(truth)))
    now = np.arange(ticks, dtype=float)
    stamps = np.tile(now[:, None], (1, len(truth)))
    depth, ok = np.full(ticks, 20.85), np.ones(ticks, bool)
    state = dock_watch.Smoothing.initial(len(truth))

    def one_at_a_time() -> None:
        s = state
        for i in range(ticks):
            sl = slice(i, i + 1)
            _, s = dock_watch.decide_dock(
                model, config, now[sl], depth[sl], ok[sl], tensions[sl], stamps[sl], s
            )

    def all_at_once() -> None:
        dock_watch.decide_dock(model, config, now, depth, ok, tensions, stamps, state)

    one_at_a_time()  # warm: the model's constants as lists, first calls
    single = min(_time(one_at_a_time) for _ in range(3)) / ticks * 1e3
    batch = min(_time(all_at_once) for _ in range(3)) / ticks * 1e3
    return {'ticks': ticks, 'live_ms_per_tick': single, 'replay_ms_per_tick': batch}


def _table(r: dict[str, Any]) -> str:
    from catenary_monitor.cli.table import format_table

    rows = [
        (
            kind,
            f"{r[kind]['catenary_monitor_ms']:.2f}",
            f"{r[kind]['moorpy_ms']:.1f}",
            f"{r[kind]['moorpy_over_ours']:.1f}x",
            f"{r[kind]['newton_iterations_median']:.0f}",
        )
        for kind in ('inextensible', 'elastic')
    ]
    head = (
        f"one equilibrium of the {r['lines']}-line dock (median of {r['loads']} loads x "
        f"{r['repeats']} rounds)\n\n"
    )
    table = format_table(
        rows, ('lines', 'catenary_monitor ms', 'MoorPy ms', 'MoorPy / ours', 'Newton steps')
    )
    e = r['estimate']
    tail = (
        f"\n\nlive dock estimate: {e['live_ms_per_tick']:.2f} ms per tick (one at a time, as the "
        f"node), {e['replay_ms_per_tick']:.3f} ms per tick over a {e['ticks']}-tick log (replay)"
    )
    return head + table + tail


def cmd_bench_body(args: argparse.Namespace) -> int:
    """Run and print the benchmark."""
    if args.params_file is None:
        from catenary_monitor.sim.scenario import default_config_path

        args.params_file = default_config_path()
    result = run(args.params_file, repeats=args.repeats, ticks=args.ticks)
    print(json.dumps(result) if args.json else _table(result))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``bench-body``."""
    p = sub.add_parser(
        'bench-body',
        help='the dock model (12-line equilibrium, live estimate) against MoorPy',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument('--params-file', metavar='F', help='default: config/floating_dock.yaml')
    p.add_argument('--repeats', type=int, default=5, help='rounds over the loads (default 5)')
    p.add_argument('--ticks', type=int, default=600, help='ticks of the estimate timing')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_body)
