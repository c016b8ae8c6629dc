"""``catenary-monitor bench-bounds``: the margins' bounds within the sensors' accuracy, three
ways, speed against accuracy (docs/study.md, "The bounds").

Every method answers the same question over the box of true readings ``[T - dT, T + dT] x
[h - dh, h + dh]`` (:mod:`catenary_monitor.core.rules.uncertainty`): the largest uplift force
and the smallest anchor and tide margins. The methods:

* **analytic** (the monitor's, :func:`~catenary_monitor.core.rules.uncertainty.bounds_one` and
  ``bounds`` on arrays): the worst case from the analysis, at ``T + dT``, the critical depths
  in closed form or tabulated, one solve where the anchor lifts somewhere in the box;
* **sampled box** (``sampled_bounds``: the monitor's before): the solve at ``T + dT`` and five
  depths (``h - dh``, ``h``, ``h + dh``, the two grounded critical depths clipped), the
  uplift's parabola vertex where it is concave over the three;
* **linearized** (first-order propagation, the textbook's): the nominal value plus ``|df/dT|
  dT + |df/dh| dh``, the slopes by forward differences (two more solves).

The reference is the box sampled densely: the solve at ``T + dT`` (every bound falls or grows
with the tension: tested) at 4001 depths over ``[h - dh, h + dh]``. The error of a bound is its
distance from the reference (the uplift's relative to the reference's value, the anchor
margin's to the span, the tide margin's to the depth), ``unsafe`` where the bound is on the
wrong side of it (an uplift below the worst, a margin above it) beyond rounding.

The readings: random lines and readings around and beyond the uplift (weight 200-3000 N/m, depth
3-80 m, span 0.3-4 depths, hook tension 0.7-2 times the uplift tension, tension accuracy 0-5 %),
at four depth accuracies (0.02 m, the default, to 1 m), every box of possible readings. Times:
the scalar call per reading (the monitor's per-sample path; the least of a few rounds) and the
vectorized call per element (the replay twin's).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any, Callable, Optional

import numpy as np

__all__ = ['run', 'register', 'METHODS']

#: The methods, in the chart's order.
METHODS = ('analytic', 'sampled box', 'linearized')
#: The depth accuracies of the sweep [m] (0.02: the default ``depth_accuracy``).
DEPTH_ACCURACIES = (0.02, 0.05, 0.2, 1.0)
UNSAFE = 1e-9  # a bound on the wrong side of the reference by more than this: unsafe
GRID = 4001


def readings(n: int, seed: int = 1) -> dict[str, np.ndarray]:
    """Random lines and readings: ``w, h, x, t, dt, dh`` (every box of possible readings)."""
    from catenary_monitor.core.physics.solve import solve

    rng = np.random.default_rng(seed)
    m = 3 * n
    w = rng.uniform(200.0, 3000.0, m)
    h = rng.uniform(3.0, 80.0, m)
    x = rng.uniform(0.3, 4.0, m) * h
    t_crit = np.asarray(solve(w, h, tension=w * h * 10, anchor_distance=x).load_margin)
    t = np.maximum((t_crit + w * h * 10) * rng.uniform(0.7, 2.0, m), w * h * 1.2)
    dt = t * rng.uniform(0.0, 0.05, m)
    dh = np.asarray(DEPTH_ACCURACIES)[rng.integers(0, len(DEPTH_ACCURACIES), m)]
    keep = np.flatnonzero((t + dt > w * (h + dh) * 1.0001) & (h - dh > 0.0))[:n]
    return {k: v[keep] for k, v in zip('w h x t dt dh'.split(), (w, h, x, t, dt, dh))}


def reference(r: dict[str, np.ndarray]) -> np.ndarray:
    """``(n, 3)``: the box sampled densely (:data:`GRID` depths at ``T + dT``)."""
    from catenary_monitor.core.physics.solve import solve

    out = np.empty((len(r['t']), 3))
    for i in range(len(r['t'])):
        hs = np.linspace(r['h'][i] - r['dh'][i], r['h'][i] + r['dh'][i], GRID)
        s = solve(r['w'][i], hs, tension=r['t'][i] + r['dt'][i], anchor_distance=r['x'][i])
        out[i] = (np.max(s.uplift_force), np.min(s.anchor_margin), np.min(s.tide_margin))
    return out


def _linearized(
    w: Any, x: Any, t: Any, h: Any, dt: Any, dh: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-order propagation from the nominal solve, the slopes by forward differences."""
    from catenary_monitor.core.physics.solve import solve

    keys = ('uplift_force', 'anchor_margin', 'tide_margin')
    step_t, step_h = 1e-6 * np.asarray(t), 1e-6 * np.asarray(h)
    r0, rt, rh = (
        solve(w, h + a, tension=t + b, anchor_distance=x)
        for a, b in ((0.0, 0.0), (0.0, step_t), (step_h, 0.0))
    )
    out = []
    for key, sign in zip(keys, (1.0, -1.0, -1.0)):
        f0 = np.asarray(getattr(r0, key), dtype=float)
        d_t = (np.asarray(getattr(rt, key)) - f0) / step_t
        d_h = (np.asarray(getattr(rh, key)) - f0) / step_h
        out.append(f0 + sign * (np.abs(d_t) * dt + np.abs(d_h) * dh))
    return out[0], out[1], out[2]


def _arrays(name: str) -> Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The method ``name`` on arrays: ``(upper, anchor lower, tide lower)``."""
    from catenary_monitor.core.rules import uncertainty as u

    def through(fn: Callable[..., dict[str, np.ndarray]]) -> Callable[..., Any]:
        def run(w: Any, x: Any, t: Any, h: Any, dt: Any, dh: Any) -> Any:
            b = fn(w, x, 1e12, math.inf, t, h, dt, dh, np.zeros_like(t))
            return tuple(np.asarray(b[k]) for k in u.FIELDS)

        return run

    if name == 'linearized':
        return _linearized
    return through(u.bounds if name == 'analytic' else u.sampled_bounds)


def _scalar(name: str) -> Callable[..., tuple[float, float, float]]:
    """The method ``name`` on one reading in plain floats (the monitor's per-sample call)."""
    from catenary_monitor.core.rules import uncertainty as u

    if name == 'analytic':
        return lambda w, x, t, h, dt, dh: u.bounds_one(w, x, 1e12, math.inf, t, h, dt, dh, 0.0)
    fn = _arrays(name)

    def one(w: float, x: float, t: float, h: float, dt: float, dh: float) -> Any:
        b = fn(*(np.array([v]) for v in (w, x, t, h, dt, dh)))
        return tuple(float(v[0]) for v in b)

    return one


def _dock(n: int) -> list[np.ndarray]:
    """The paper's dock on a calm day (``w, x, t, h, dt, dh``): 372 kN with 30 kN of waves
    at 20.85 m +- 0.5 m of tide, 120 m span, the default accuracies (0.5 % of the MBL, 0.02 m):
    no anchor lifts anywhere in the box (the usual sample's cost)."""
    rng = np.random.default_rng(2)
    t = 372e3 + rng.normal(0.0, 30e3, n)
    h = 20.85 + rng.uniform(-0.5, 0.5, n)
    full = np.full(n, 1.0)
    return [1300.0 * full, 120.0 * full, t, h, 0.005 * 4.827e6 * full, 0.02 * full]


def _times(
    vec: Callable[..., Any], one: Callable[..., Any], cols: list[np.ndarray], rounds: int
) -> tuple[float, float]:
    """(s per scalar call, s per element of the vectorized call): the least of ``rounds``."""
    few = [tuple(float(c[i]) for c in cols) for i in range(min(len(cols[0]), 500))]
    best_s = best_v = math.inf
    for _ in range(rounds):
        t0 = time.process_time()
        vec(*cols)
        best_v = min(best_v, (time.process_time() - t0) / len(cols[0]))
        t0 = time.process_time()
        for args in few:
            one(*args)
        best_s = min(best_s, (time.process_time() - t0) / len(few))
    return best_s, best_v


def errors(got: np.ndarray, ref: np.ndarray, r: dict[str, np.ndarray]) -> np.ndarray:
    """Signed errors ``(n, 3)``: positive on the safe side (an uplift above the worst, a margin
    below it), relative to the uplift, the span and the depth."""
    scale = np.c_[np.maximum(ref[:, 0], 1e-9), r['x'], r['h']]
    sign = np.array([1.0, -1.0, -1.0])
    return sign * (got - ref) / scale


def run(n: int = 3000, rounds: int = 5, seed: int = 1) -> dict[str, Any]:
    """The figures of each method: per depth accuracy and over all, the error (median and
    worst magnitude, how many unsafe), the scalar call's µs per reading and the vectorized
    call's ns per element."""
    r = readings(n, seed)
    ref = reference(r)
    cols = [r[k] for k in ('w', 'x', 't', 'h', 'dt', 'dh')]
    dock = _dock(len(r['t']))
    out: dict[str, Any] = {'readings': len(r['t']), 'grid': GRID, 'methods': {}}
    for name in METHODS:
        vec, one = _arrays(name), _scalar(name)
        got = np.column_stack(vec(*cols))
        err = errors(got, ref, r)
        best_s, best_v = _times(vec, one, cols, rounds)
        dock_s, dock_v = _times(vec, one, dock, rounds)
        per: dict[str, Any] = {}
        for dh in (*DEPTH_ACCURACIES, None):
            pick = slice(None) if dh is None else r['dh'] == dh
            e = err[pick]
            mag = np.abs(e)
            per['all' if dh is None else f'{dh:g}'] = {
                'readings': int(len(e)),
                'error_median': float(np.median(mag)),
                'error_worst': float(np.max(mag)),
                'unsafe': int(np.sum(e < -UNSAFE)),
                'unsafe_worst': float(max(0.0, -np.min(e))),
            }
        out['methods'][name] = {
            'scalar_us': best_s * 1e6,
            'vector_ns_per_element': best_v * 1e9,
            'dock_scalar_us': dock_s * 1e6,
            'dock_vector_ns_per_element': dock_v * 1e9,
            'by_depth_accuracy': per,
        }
    return out


def report(res: dict[str, Any]) -> str:
    """The table the command prints."""
    lines = [
        f'bounds over the box of true readings, {res["readings"]} random readings, reference: '
        f'{res["grid"]} depths at T + dT; error relative to the worst uplift, the span, the '
        'depth; unsafe: on the wrong side by more than 1e-9',
        'times: the least CPU time of the rounds, per reading (scalar call) and per element '
        '(vectorized), on these readings (most lift an anchor somewhere in the box) and on the '
        "paper's dock on a calm day (none does)",
        f'{"method":12s} {"scalar us":>10s} {"vector ns":>10s} {"dock us":>8s} {"dock ns":>8s}   '
        + '   '.join(f'{"dh " + k + " m":>26s}' for k in (*map(str, DEPTH_ACCURACIES),)),
        f'{"":12s} {"":>10s} {"":>10s} {"":>8s} {"":>8s}   '
        + '   '.join(f'{"median / worst / unsafe":>26s}' for _ in DEPTH_ACCURACIES),
    ]
    for name, m in res['methods'].items():
        cells = []
        for dh in DEPTH_ACCURACIES:
            p = m['by_depth_accuracy'][f'{dh:g}']
            cells.append(
                f'{p["error_median"]:8.1e} / {p["error_worst"]:7.1e} / {p["unsafe"]:4d}'
            )
        lines.append(
            f'{name:12s} {m["scalar_us"]:10.1f} {m["vector_ns_per_element"]:10.0f} '
            f'{m["dock_scalar_us"]:8.1f} {m["dock_vector_ns_per_element"]:8.0f}   '
            + '   '.join(f'{c:>26s}' for c in cells)
        )
    return '\n'.join(lines)


def plot(res: dict[str, Any], path: str) -> None:
    """Speed against accuracy: a marker per method at its worst error over the readings, at its
    scalar call's time (circle) and its vectorized time per element (square), filled on the
    sweep's readings, hollow on the calm dock's; X: unsafe on some readings."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    floor = 1e-17
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.8))
    colours = {'analytic': 'tab:green', 'sampled box': 'tab:orange', 'linearized': 'tab:red'}
    for ax, key, title in (
        (axes[0], '0.02', 'depth accuracy 0.02 m (the default)'),
        (axes[1], 'all', 'every depth accuracy, 0.02 to 1 m'),
    ):
        for name, m in res['methods'].items():
            p = m['by_depth_accuracy'][key]
            worst = max(p['error_worst'], floor)
            unsafe = p['unsafe'] > 0
            c = colours[name]
            times = (
                m['scalar_us'],
                m['vector_ns_per_element'] / 1e3,
                m['dock_scalar_us'],
                m['dock_vector_ns_per_element'] / 1e3,
            )
            ax.plot([min(times), max(times)], [worst, worst], color=c, lw=0.8, ls=':')
            for t, marker, size, fill in zip(
                times,
                ('X' if unsafe else 'o', 's', 'o', 's'),
                (140, 70, 70, 50),
                (c, c, 'none', 'none'),
            ):
                ax.scatter(
                    [t], [worst], marker=marker, s=size, facecolor=fill, edgecolor=c, zorder=3
                )
            label = name + (f' ({p["unsafe"]} of {p["readings"]} unsafe)' if unsafe else '')
            ax.annotate(
                label, (min(times), worst), textcoords='offset points', xytext=(0, 9), fontsize=8
            )
        ax.axhline(1e-6, color='k', lw=0.6, ls='--')
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_xlim(0.05, 1000.0)
        ax.set_ylim(floor / 3, 100.0)
        ax.set_xlabel(
            'time per reading [µs]: ● one call, ■ vectorized (per element)\n'
            'filled: these readings (most lift an anchor in the box); hollow: the calm dock'
        )
        ax.set_ylabel('worst |bound - box sampled densely| (1e-17: exact)')
        ax.set_title(title, fontsize=10)
        ax.grid(True, which='major', alpha=0.3)
    fig.suptitle(
        "The bounds within the sensors' accuracy, three ways: speed against accuracy "
        f'({res["readings"]} random readings; dashed: 1e-6; X: unsafe on some)',
        fontsize=10,
    )
    fig.subplots_adjust(left=0.07, right=0.98, top=0.9, bottom=0.17, wspace=0.22)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def register(sub: Any) -> None:
    """Add ``bench-bounds`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-bounds',
        help='the bounds within the sensors\' accuracy three ways: speed against accuracy',
        description='The analytic bounds, the sampled box and first-order propagation against '
        'the box sampled densely, on random readings; --plot writes the chart.',
    )
    p.add_argument('--readings', type=int, default=3000, help='random readings (default 3000)')
    p.add_argument('--rounds', type=int, default=5, help='timing rounds (default 5)')
    p.add_argument('--plot', metavar='PNG', help='write the chart (e.g. docs/bounds_methods.png)')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=_command)


def _command(args: argparse.Namespace) -> int:
    res = run(max(10, args.readings), max(1, args.rounds))
    print(json.dumps(res) if args.json else report(res))
    if args.plot:
        plot(res, args.plot)
    return 0


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m catenary_monitor_study.bench_bounds')
    sub = parser.add_subparsers(dest='cmd', required=True)
    register(sub)
    args = parser.parse_args(['bench-bounds', *(argv or [])])
    return int(args.func(args))
