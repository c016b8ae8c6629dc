"""``catenary-monitor bench-dynamics``: the quasi-static monitor against MoorDyn on a grid of
wave-frequency hook motions (period, amplitude), tides (depth relative to the chain's lift
depth) and chain lengths.

Each scene drives one chain's hook in MoorDyn (:mod:`catenary_monitor_study.moordyn_scene`):
the hook surges ``a sin(2 pi t / T)`` about the installed span (the waves building over 20 s),
its depth held at the lift depth of the chain plus an offset. The hook tension and the depth
MoorDyn gives go through the monitor's replay twin (the node's decisions on the same samples),
and its answers are compared, after a settling time, with MoorDyn's anchor force:

* ``qs_excess``: how far the anchor's force exceeds the quasi-static uplift of the same reading
  (kN, the largest over the scene): the error of solving one reading as a chain at rest;
* ``held``: the share of samples with the anchor force above 1 kN where ``uplift_force_upper``
  holds it, and the same share for the instantaneous quasi-static uplift (the baseline: what
  the monitor had before the wave window);
* ``peak_ratio``: the bound's peak over the anchor force's peak.

Prints a table (``--json``: one object), ``--plot`` charts the quasi-static excess against the
period for each amplitude, one panel per depth offset (docs/dynamics.md shows it).

``--dock`` runs the paper's whole dock instead, one body with its twelve chains, through a tide
rise and a storm with waves (:mod:`catenary_monitor_study.dock_dynamics`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, Optional

import numpy as np

__all__ = ['register', 'run_scene', 'run_grid']

SETTLE = 40.0  # s: the waves built up and the wave window filled


def run_scene(
    length: float,
    offset: float,
    amplitude: float,
    period: float,
    duration: float,
    allowance: float = 0.3,
    tension_accuracy: Optional[float] = None,
) -> dict[str, Any]:
    """One scene's figures (module docstring); SI in, kN in the figures; the monitor with
    ``wave_allowance`` ``allowance`` and ``tension_accuracy`` (N, None: its default)."""
    from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
    from catenary_monitor.core.twin.engine import recompute
    from catenary_monitor.core.physics.fixed_length import lift_depth
    from catenary_monitor_study.moordyn_scene import Chain, run_line

    chain = Chain(length=length)
    span = 121.06
    depth = float(lift_depth(chain.weight, length, span, chain.ea)) + offset
    w = 2.0 * math.pi / period

    def surge(t: float) -> tuple[float, float]:
        a, da = amplitude * min(t / 20.0, 1.0), (amplitude / 20.0 if t < 20.0 else 0.0)
        return span + a * math.sin(w * t), a * w * math.cos(w * t) + da * math.sin(w * t)

    rec = run_line(chain, surge, lambda t: (depth, 0.0), duration)
    line = LineConfig(
        name='line',
        weight=chain.weight,
        anchor_distance=span,
        mbl=4.827e6,
        ea=chain.ea,
        tension_accuracy=tension_accuracy,
    )
    config = MonitorConfig(lines=(line,), alarm=AlarmConfig(wave_allowance=allowance))
    t0 = 1_763_900_000_000_000_000
    t_ns = t0 + np.rint(rec.t * 1e9).astype(np.int64)
    result = recompute(
        config, {'line': (t_ns, rec.tension)}, (t_ns[::10] - 50_000_000, rec.depth[::10])
    )
    line_result = result.lines[0]
    rows = line_result.tension_rows  # one per tension reading, as MoorDyn's samples
    keep = rec.t > SETTLE
    dyn, qs = rec.uplift[keep], line_result.values['uplift_force'][rows][keep]
    upper = line_result.values['uplift_force_upper'][rows][keep]
    lifted = dyn > 1e3
    share = (lambda b: float(np.mean(b[lifted] >= dyn[lifted])) if lifted.any() else math.nan)
    return {
        'length': length,
        'depth': depth,
        'offset': offset,
        'amplitude': amplitude,
        'period': period,
        'dynamic_peak_kN': float(dyn.max()) / 1e3,
        'qs_peak_kN': float(np.nanmax(qs)) / 1e3,
        'qs_excess_kN': float(np.nanmax(dyn - qs)) / 1e3,
        'held_bound': share(upper),
        'held_qs': share(qs),
        'peak_ratio': float(np.nanmax(upper) / dyn.max()) if dyn.max() > 1e3 else math.nan,
    }


def run_grid(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Every scene of the grid, with a progress line on stderr."""
    grid = [
        (length, offset, amplitude, period)
        for length in args.lengths
        for offset in args.offsets
        for amplitude in args.amplitudes
        for period in args.periods
    ]
    rows = []
    for k, scene in enumerate(grid):
        print(f'\rbench-dynamics: scene {k + 1}/{len(grid)}', end='', file=sys.stderr, flush=True)
        rows.append(run_scene(*scene, args.duration, args.allowance, args.tension_accuracy))
    print(file=sys.stderr)
    return rows


def _table(rows: list[dict[str, Any]]) -> str:
    head = (
        f'{"L m":>7} {"h m":>6} {"a m":>4} {"T s":>4} {"dyn kN":>7} {"qs kN":>7} '
        f'{"excess":>7} {"held qs":>7} {"held bd":>7} {"bd/dyn":>6}'
    )
    out = [head]
    for r in rows:
        out.append(
            f'{r["length"]:7.2f} {r["depth"]:6.2f} {r["amplitude"]:4.1f} {r["period"]:4.0f} '
            f'{r["dynamic_peak_kN"]:7.1f} {r["qs_peak_kN"]:7.1f} {r["qs_excess_kN"]:7.1f} '
            f'{r["held_qs"]:7.2f} {r["held_bound"]:7.2f} {r["peak_ratio"]:6.2f}'
        )
    return '\n'.join(out)


def _plot(rows: list[dict[str, Any]], path: str) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    offsets = sorted({r['offset'] for r in rows})
    fig, axes = plt.subplots(1, len(offsets), figsize=(4.2 * len(offsets), 3.6), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, offset in zip(axes, offsets):
        for length in sorted({r['length'] for r in rows}):
            for amp in sorted({r['amplitude'] for r in rows}):
                sel = [
                    r
                    for r in rows
                    if r['offset'] == offset and r['amplitude'] == amp and r['length'] == length
                ]
                sel.sort(key=lambda r: r['period'])
                ax.plot(
                    [r['period'] for r in sel],
                    [r['qs_excess_kN'] for r in sel],
                    marker='o',
                    label=f'{amp:g} m, L {length:g} m',
                )
        ax.set_title(f'tide {offset:+.1f} m from the lift depth')
        ax.set_xlabel('wave period [s]')
        ax.grid(alpha=0.3)
    axes[0].set_ylabel('anchor force above the quasi-static [kN]')
    axes[-1].legend(fontsize=7)
    fig.suptitle('MoorDyn anchor force minus the monitor\'s quasi-static uplift (hook surge)')
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def cmd_bench_dynamics(args: argparse.Namespace) -> int:
    """Run the grid; print a table or JSON; chart it."""
    from catenary_monitor_study.moordyn_scene import available

    if not available():
        print(
            'bench-dynamics: needs MoorDyn (pip install "catenary_monitor[dynamics]")',
            file=sys.stderr,
        )
        return 2
    if args.dock:
        return _dock(args)
    if args.duration is None:
        args.duration = 100.0
    rows = run_grid(args)
    if args.plot:
        _plot(rows, args.plot)
    if args.json:
        clean = [{k: (None if v != v else v) for k, v in r.items()} for r in rows]
        print(json.dumps({'scenes': clean}, allow_nan=False))
    else:
        print(_table(rows))
    return 0


def _dock(args: argparse.Namespace) -> int:
    """``--dock``: the paper's dock in MoorDyn (catenary_monitor_study.dock_dynamics)."""
    from catenary_monitor_study import dock_dynamics as dd

    if args.params_file is None:
        from catenary_monitor.sim.scenario import default_config_path

        args.params_file = default_config_path()
    scene = dd.DockScene(duration=args.duration or 300.0, segments=args.segments)
    print('bench-dynamics: the dock in MoorDyn (about a minute)...', file=sys.stderr, flush=True)
    out = dd.run_dock_scene(args.params_file, scene)
    if args.plot:
        dd.plot_dock(out, args.plot)
    if args.json:
        body = {k: v for k, v in out.items() if k != 'series'}
        print(json.dumps(dd.finite(body), allow_nan=False))
    else:
        print(dd.dock_table(out))
    return 0


def _floats(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(',') if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a comma-separated list of numbers: {text!r}')


def _duration(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number of seconds: {text!r}')
    if not 10.0 <= value <= 86400.0:
        raise argparse.ArgumentTypeError(f'{value:g} s: from 10 to 86400 s')
    return value


def register(sub: Any) -> None:
    """Add ``bench-dynamics`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-dynamics',
        help='the quasi-static monitor against MoorDyn: waves, tide, chain length',
        description=__doc__.splitlines()[0],
    )
    p.add_argument('--periods', type=_floats, default=[7.0, 9.0, 12.0], help='s (7,9,12)')
    p.add_argument('--amplitudes', type=_floats, default=[0.3, 0.5, 0.8], help='m (0.3,0.5,0.8)')
    p.add_argument(
        '--offsets', type=_floats, default=[-0.5, 0.0, 0.5], help='m from the lift depth'
    )
    p.add_argument('--lengths', type=_floats, default=[123.6847], help='chain lengths [m]')
    p.add_argument(
        '--duration', type=_duration, default=None, help='s per scene (100; --dock: 300)'
    )
    p.add_argument(
        '--allowance', type=float, default=0.3, help="the monitor's wave_allowance (0.3)"
    )
    p.add_argument(
        '--tension-accuracy',
        type=float,
        default=None,
        metavar='N',
        help="the load pin's accuracy (default: the monitor's, 0.5 %% of the MBL; 1: exact)",
    )
    p.add_argument(
        '--dock',
        action='store_true',
        help="the paper's dock, 12 chains on one body, through a tide rise and a storm",
    )
    p.add_argument('--params-file', metavar='F', help='--dock: default config/floating_dock.yaml')
    p.add_argument('--segments', type=int, default=20, help='--dock: segments per chain (20)')
    p.add_argument('--plot', metavar='PNG', help='chart the quasi-static excess (--dock: a line)')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench_dynamics)
