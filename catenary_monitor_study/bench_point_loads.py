"""``catenary-monitor bench-point-loads``: the live dock estimate with clump weights on four
lines, by the lines' tables against the exact point-load solve, and against MoorPy.

The paper's dock (config/floating_dock.yaml, 12 lines) with a 30 kN clump weight 60 m up
line_01, line_06, line_07 and line_12 and tables over tide depths of 19-23 m
(``dock_table_depth_min`` / ``_max``). Figures, all in the same run: the tables' build time and
their error as measured when built; the estimate's offset from MoorPy's hook tensions against
MoorPy's own offset (its ``System`` with free points of the clumps' masses, a body free in surge,
sway and yaw, pushed by 1 MN from six directions, solved to 1e-5 m); the estimate's cost per
tick one tick at a time (as the node runs ``decide_dock``) with the tables, with the exact solve
(the baseline: a chain-length root per line and query) and for the plain dock (no clumps); the
tables' own queries per tick; and per tick over a whole log (replay). Times are the
process's CPU time (shared, noisy machines): compare the ratios.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
import warnings
from typing import Any, Callable

import numpy as np

os.environ.setdefault('PYTHONBREAKPOINT', '0')

__all__ = ['run', 'register', 'clumped_params', 'CLUMPED']

#: The lines given a clump weight, where and how heavy [m from the anchor, N].
CLUMPED = ('line_01', 'line_06', 'line_07', 'line_12')
CLUMP_AT, CLUMP_WEIGHT = 60.0, 30e3
DEPTHS = (19.0, 23.0)
DEPTH = 20.85


def clumped_params(params_file: str) -> dict[str, Any]:
    """The flat parameters of ``params_file`` with the four clumps and the tables' depths."""
    from catenary_monitor.core.config.parameters import load_params_file

    flat = load_params_file(params_file)
    for name in CLUMPED:
        flat[f'{name}.point_load_positions'] = [CLUMP_AT]
        flat[f'{name}.point_load_weights'] = [CLUMP_WEIGHT]
    flat['dock_table_depth_min'], flat['dock_table_depth_max'] = DEPTHS
    return flat


def _time(fn: Callable[[], object]) -> float:
    """CPU seconds of ``fn`` in this process (the machines are shared: wall time counts the
    other jobs' turns too)."""
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def _ticks(model: Any, config: Any, tensions: np.ndarray) -> Callable[[], None]:
    """One tick at a time through decide_dock, as the node steps (returns the loop)."""
    from catenary_monitor.core.rules import dock_watch

    n, m = tensions.shape
    now = np.arange(n, dtype=float)
    stamps = np.tile(now[:, None], (1, m))
    depth, ok = np.full(n, DEPTH), np.ones(n, bool)

    def loop() -> None:
        s = dock_watch.Smoothing.initial(m)
        for i in range(n):
            sl = slice(i, i + 1)
            _, s = dock_watch.decide_dock(
                model, config, now[sl], depth[sl], ok[sl], tensions[sl], stamps[sl], s
            )

    return loop


def _batch(model: Any, config: Any, tensions: np.ndarray) -> Callable[[], object]:
    from catenary_monitor.core.rules import dock_watch

    n, m = tensions.shape
    now = np.arange(n, dtype=float)
    stamps = np.tile(now[:, None], (1, m))
    state = dock_watch.Smoothing.initial(m)
    return lambda: dock_watch.decide_dock(
        model, config, now, np.full(n, DEPTH), np.ones(n, bool), tensions, stamps, state
    )


def _moorpy(model: Any) -> dict[str, Any]:
    """The estimate's offset (tables and exact) from MoorPy's tensions vs MoorPy's offset."""
    from catenary_monitor.core.body.estimate import estimate_dock
    from catenary_monitor.core.body.loads import push_direction
    from catenary_monitor_study.body_peer import moorpy_equilibrium

    exact = dataclasses.replace(model, tables=())
    worst = {'tables': 0.0, 'exact': 0.0}
    use = np.ones((1, len(model.names)), bool)
    directions = (0.0, 45.0, 100.0, 150.0, 270.0, 315.0)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        for phi in directions:
            push = push_direction(phi)
            load = np.array([push[0] * 1e6, push[1] * 1e6, 0.0])
            offset, tensions, _ = moorpy_equilibrium(model, DEPTH, load, tol=1e-5)
            for key, m in (('tables', model), ('exact', exact)):
                est = estimate_dock(m, np.array([DEPTH]), tensions[None, :], use)
                err = float(np.max(np.abs(est.offset[0, :2] - offset[:2])))
                worst[key] = max(worst[key], err if err == err else np.inf)
    return {'directions': len(directions), 'offset_error_m': worst}


def run(params_file: str, ticks: int = 200, exact_ticks: int = 10) -> dict[str, Any]:
    """Every figure (see the module docstring)."""
    from catenary_monitor.core.body.dock_model import DockModel
    from catenary_monitor.core.body.equilibrium import solve_equilibrium
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.core.physics import point_load_table

    point_load_table.build_table.cache_clear()
    flat = clumped_params(params_file)
    build = _time(lambda: config_from_params(flat))
    config = config_from_params(flat)
    model = DockModel.from_config(config)
    exact = dataclasses.replace(model, tables=())
    plain_config = config_from_params(load_params_file(params_file))
    plain = DockModel.from_config(plain_config)
    tables = [t for t in model.tables if t is not None]
    out: dict[str, Any] = {
        'lines': len(model.names),
        'clumped': len(tables),
        'table_build_s': build,
        'table_nodes': list(tables[0].span.shape),
        'table_span_error_m': model.table_span_error,
        'table_tension_error': max(t.tension_error for t in tables),
    }
    rng = np.random.default_rng(1)
    per_tick = {}
    cases = (('plain', plain, plain_config), ('tables', model, config), ('exact', exact, config))
    for key, m, c in cases:
        eq = solve_equilibrium(m, DEPTH, np.array([0.0, -1.0e6, 0.0]))
        assert eq.lines is not None
        truth = eq.lines.statics.top_tension
        n = exact_ticks if key == 'exact' else ticks
        tensions = truth[None, :] + rng.normal(0.0, 20e3, (n, truth.size))
        loop = _ticks(m, c, tensions)
        loop()  # warm
        per_tick[key] = min(_time(loop) for _ in range(3)) / n * 1e3
        if key == 'tables':
            batch = min(_time(_batch(m, c, tensions)) for _ in range(3))
            out['replay_ms_per_tick'] = batch / n * 1e3
            out['queries_ms_per_tick'] = _queries(model, tensions[0]) * 1e3
    out['ms_per_tick'] = per_tick
    out['exact_over_tables'] = per_tick['exact'] / per_tick['tables']
    out['moorpy'] = _moorpy(model)
    return out


def _queries(model: Any, tensions: np.ndarray) -> float:
    """Seconds per tick of the tables' own queries: each clumped line's span from its tension
    and its tension at a span, one element each (the live core's)."""
    tables = [(i, t) for i, t in enumerate(model.tables) if t is not None]
    h = np.array([DEPTH])
    rounds = 200

    def go() -> None:
        for _ in range(rounds):
            for i, t in tables:
                s, _ = t.span_at_tension(h, tensions[i : i + 1])
                t.state_at_span(h, s)

    go()
    return min(_time(go) for _ in range(3)) / rounds


def _text(r: dict[str, Any]) -> str:
    from catenary_monitor.cli.table import format_table

    t = r['ms_per_tick']
    rows = [
        ('plain dock (no clumps)', f"{t['plain']:.3f}", '-'),
        ('clumps, tables', f"{t['tables']:.3f}", '1.0x'),
        ('clumps, exact solve', f"{t['exact']:.1f}", f"{r['exact_over_tables']:.0f}x"),
    ]
    mp = r['moorpy']
    return (
        f"{r['lines']}-line dock, clump weights on {r['clumped']} lines: tables built in "
        f"{r['table_build_s']:.2f} s ({r['table_nodes'][0]} depths x {r['table_nodes'][1]} "
        f"H), error as built {r['table_span_error_m'] * 1e3:.3f} mm in span, "
        f"{r['table_tension_error']:.1e} in tension\n\n"
        + format_table(rows, ('live dock estimate', 'ms per tick', 'exact / tables'))
        + f"\n\nthe tables' queries: {r['queries_ms_per_tick']:.3f} ms per tick (4 lines); "
        f"replay {r['replay_ms_per_tick']:.3f} ms per tick\n"
        f"offset against MoorPy's System ({mp['directions']} pushes of 1 MN): tables "
        f"{mp['offset_error_m']['tables'] * 1e3:.3f} mm, exact "
        f"{mp['offset_error_m']['exact'] * 1e3:.3f} mm at most"
    )


def cmd_bench_point_loads(args: argparse.Namespace) -> int:
    """Run and print the benchmark."""
    params = args.params_file
    if params is None:
        from catenary_monitor.sim.scenario import default_config_path

        params = str(default_config_path())
    result = run(params, ticks=args.ticks, exact_ticks=args.exact_ticks)
    print(json.dumps(result) if args.json else _text(result))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``bench-point-loads``."""
    p = sub.add_parser(
        'bench-point-loads',
        help='the live dock estimate with clump weights: tables vs the exact solve vs MoorPy',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument('--params-file', metavar='F', help='default: config/floating_dock.yaml')
    p.add_argument('--ticks', type=int, default=200, help='ticks timed (default 200)')
    p.add_argument('--exact-ticks', type=int, default=10, help='ticks of the exact baseline')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_point_loads)
