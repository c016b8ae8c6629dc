"""``catenary-monitor bench-methods``: every method on one chart, and where each one fails.

One run on this machine measures, for every method of :mod:`catenary_monitor_study.methods` over a
fixed scene sweep (the paper dock, w = 1300 N/m, h = 20.85 m, with the anchor-end parameter
``h/a`` from 1e-9 to 1e4 and the anchor distance ``x/x_min`` from 1e-3 to 1 - 1e-6, plus the
seed tables):

* median time per scalar solve (per scene the best of a few calls) and, where the method has
  one, the time per element of its vectorized form;
* median and worst error against the 50-digit mpmath solution of the paper's equations,
  computed in this run (``methods.reference``): the relative error of each output divided by
  ``max(1, condition number)``, so that an answer as good as the problem allows scores ~1e-16;
* failures: an exception, no convergence, NaN, or an error above 1e-6.

Every speed figure is reported as a ratio to a baseline timed in the same run: the textbook
closed form of problem 3, ``a acosh(1 + h/a)`` (one catenary evaluation: the floor), and one
MoorPy catenary call, over the whole sweep and over its scenes in the dock's regime.
Writes ``methods.csv``, ``methods.md``, ``speed_accuracy.png`` and ``stability_map.png``.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import platform
import re
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

import numpy as np

from catenary_monitor.cli.status_line import StatusLine

W_DOCK, H_DOCK = 1300.0, 20.85  # the paper's floating dock: U3 chain 81 mm, g = 10
GOOD = 1e-12  # the project's accuracy target
FAIL = 1e-6  # above this the answer counts as a failure
TINY = 1e-17  # errors are shown no smaller than this
#: The dock's regime within the sweep: h/a from 1e-4 to 1, x/x_min from 0.02 to 1.
DOCK_HA, DOCK_XR = (1e-4, 1.0), (0.02, 1.0)


# ------------------------------------------------------------------------------ scenes
@dataclass
class Scenes:
    """Scene set of one problem: inputs, reference answers and map coordinates."""

    problem: int
    w: np.ndarray
    h: np.ndarray
    t: np.ndarray
    x: np.ndarray  # NaN for problem 3
    ha: np.ndarray  # h / a (a = anchor-end parameter T/w - h)
    xr: np.ndarray  # x / x_min (1 for problem 3)
    seed: np.ndarray  # True for the seed-table scenes
    # Filled by compute_reference (empty until then):
    ref: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))  # (n, 2) reference values
    cond: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))  # (n, 2) condition numbers
    length: np.ndarray = field(default_factory=lambda: np.empty(0))  # suspended length (problem 4)
    # (n, 2) reference and condition numbers of the length-given problem
    ref_l: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))
    cond_l: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))

    @property
    def n(self) -> int:
        return self.w.size

    @property
    def dock(self) -> np.ndarray:
        """The sweep's scenes in the dock's regime (DOCK_HA, DOCK_XR): what the monitor sees."""
        return (
            ~self.seed
            & (self.ha >= DOCK_HA[0] * (1 - 1e-9))
            & (self.ha <= DOCK_HA[1] * (1 + 1e-9))
            & (self.xr >= DOCK_XR[0])
            & (self.xr <= DOCK_XR[1])
        )


def grid(quick: bool) -> tuple[np.ndarray, np.ndarray]:
    """The sweep: h/a (half decades 1e-9..1e4) and x/x_min (1e-3..0.9, then 0.99..1-1e-6)."""
    n_ha, n_x = (14, 6) if quick else (27, 10)
    ha = np.logspace(-9, 4, n_ha)
    xr = np.concatenate([np.logspace(-3, math.log10(0.9), n_x), [0.99, 0.9999, 0.999999]])
    return ha, xr


def build_scenes(problem: int, quick: bool) -> Scenes:
    from catenary_monitor.core.physics.catenary import grounded, two_prod_diff

    ha, xr = grid(quick)
    rows: list[tuple[float, float, float, float, float, float, bool]] = []
    for q in ha:
        t = W_DOCK * (H_DOCK / q + H_DOCK)
        if problem == 2:  # the load is R; x_min of a no-uplift chain with that R
            r = W_DOCK * H_DOCK / q
            x_min = float(grounded(r / W_DOCK, H_DOCK).min_anchor_distance)
            for xr_ in xr:
                rows.append((W_DOCK, H_DOCK, r, xr_ * x_min, q, xr_, False))
            continue
        if problem == 3:
            rows.append((W_DOCK, H_DOCK, t, math.nan, q, 1.0, False))
            continue
        b = float(two_prod_diff(t, W_DOCK, H_DOCK)) / W_DOCK
        x_min = float(grounded(b, H_DOCK).min_anchor_distance)
        for r in xr:
            rows.append((W_DOCK, H_DOCK, t, r * x_min, q, r, False))
    # seed tables: ship (table 1, R = 89.63 kN as the paper computed it), dock (tables 2-4)
    seeds3 = [
        (517.0, 80.0, 89.63e3 + 517.0 * 80.0),
        (1300.0, 20.85, 372e3 + 1300.0 * 20.85),
        (1300.0, 20.85, 1623.5e3),
    ]
    seeds4 = [
        (1300.0, 20.85, 1623.5e3, 121.06),
        (1300.0, 20.85, 1623.5e3, 200.0),
        (1300.0, 20.85, 399.1048e3, 100.0),
    ]
    seeds2 = [(1300.0, 20.85, 1584.6e3, 121.06)]  # table 3
    seeds: dict[int, Sequence[tuple[float, ...]]] = {2: seeds2, 3: seeds3, 4: seeds4}
    for s in seeds[problem]:
        w, h, t = s[:3]
        ha_s = h / (t / w) if problem == 2 else h / (t / w - h)
        rows.append((w, h, t, s[3] if problem != 3 else math.nan, ha_s, math.nan, True))
    cols = list(zip(*rows))
    w_, h_, t_, x_, ha_, xr_ = (np.array(c, dtype=float) for c in cols[:6])
    return Scenes(problem, w_, h_, t_, x_, ha_, xr_, np.array(cols[6], bool))


def compute_reference(sc: Scenes, with_length: bool, progress: Callable[[str], None]) -> None:
    from catenary_monitor_study.methods import reference as ref

    sc.ref = np.empty((sc.n, 2))
    sc.cond = np.ones((sc.n, 2))
    sc.length = np.full(sc.n, np.nan)
    sc.ref_l = np.full((sc.n, 2), np.nan)
    sc.cond_l = np.ones((sc.n, 2))
    for i in range(sc.n):
        progress(f'reference (mpmath, 50 digits), problem {sc.problem}: {i + 1}/{sc.n}')
        if sc.problem == 3:
            r = ref.problem3(sc.w[i], sc.h[i], sc.t[i])
        elif sc.problem == 2:
            r = ref.problem2(sc.w[i], sc.h[i], sc.t[i], sc.x[i])
        else:
            r = ref.problem4(sc.w[i], sc.h[i], sc.t[i], sc.x[i])
            sc.length[i] = r.length
            if with_length:
                rl = ref.given_length(sc.w[i], sc.h[i], sc.x[i], r.length, r.v1 / sc.w[i])
                sc.ref_l[i] = rl.v1, rl.v2
                sc.cond_l[i] = rl.c1, rl.c2
        sc.ref[i] = r.v1, r.v2
        sc.cond[i] = r.c1, r.c2


def scene_error(val: tuple[float, float], ref: np.ndarray, cond: np.ndarray) -> float:
    """max over outputs of relative error / max(1, condition number); inf for NaN."""
    v = np.asarray(val, dtype=float)
    if not np.all(np.isfinite(v)):
        return math.inf
    with np.errstate(divide='ignore', invalid='ignore'):
        rel = np.where(ref != 0, np.abs(v - ref) / np.abs(ref), np.abs(v))
    return float(np.max(rel / np.maximum(1.0, cond)))


# ------------------------------------------------------------------------------ running
@dataclass
class Outcome:
    method: Any
    idx: np.ndarray  # scene indices run
    err: np.ndarray  # error per scene run (inf: failed to produce a number)
    t_us: np.ndarray  # scalar time per scene run
    why_failed: dict = field(default_factory=dict)  # exception text -> count
    vec_ns: float = math.nan
    vec_err: Optional[np.ndarray] = None
    dock: Optional[np.ndarray] = None  # per scene run: in the dock's regime
    vec_ns_dock: float = math.nan

    @property
    def failures(self) -> int:
        return int(np.sum(~(self.err <= FAIL)))

    def row(self) -> dict[str, Any]:
        ok = np.isfinite(self.err)
        e = np.maximum(self.err[ok], TINY) if ok.any() else np.array([math.inf])
        vec_fail = '' if self.vec_err is None else int(np.sum(~(self.vec_err <= FAIL)))
        return {
            'problem': self.method.problem,
            'method': self.method.name,
            'family': self.method.family,
            'scenes': int(self.idx.size),
            'scalar_us_median': float(np.median(self.t_us)),
            'vector_ns_per_element': self.vec_ns,
            'error_median': float(np.median(np.maximum(self.err, TINY))),
            'error_worst': float(np.max(np.maximum(self.err, TINY))),
            'error_worst_finite': float(np.max(e)),
            'failures': self.failures,
            'vector_failures': vec_fail,
            'dock_scenes': int(np.sum(self.dock)) if self.dock is not None else 0,
            'dock_scalar_us_median': self._dock(self.t_us, np.median),
            'dock_vector_ns_per_element': self.vec_ns_dock,
            'dock_error_worst': self._dock(np.maximum(self.err, TINY), np.max),
            'dock_failures': (
                int(np.sum(~(self.err[self.dock] <= FAIL))) if self.dock is not None else 0
            ),
            'why': self.method.why,
        }

    def _dock(self, values: np.ndarray, reduce: Callable[[np.ndarray], Any]) -> float:
        if self.dock is None or not self.dock.any():
            return math.nan
        return float(reduce(values[self.dock]))


def _args(sc: Scenes, i: int, given: str) -> tuple[float, ...]:
    if sc.problem == 3:
        return sc.w[i], sc.h[i], sc.t[i]
    if given == 'length':
        return sc.w[i], sc.h[i], sc.x[i], sc.length[i]
    return sc.w[i], sc.h[i], sc.t[i], sc.x[i]


def _call(m: Any, args: tuple) -> tuple[Any, float]:
    t0 = time.perf_counter()
    try:
        out = m.scalar_fn(*args)
    except Exception as exc:  # a failure of the method, recorded
        out = exc
    return out, time.perf_counter() - t0


#: A timed sample lasts at least this long [s]: faster calls are repeated within one sample
#: (as ``timeit`` does), so the timer's own cost (~0.1 us per reading) is not charged to them.
SAMPLE_S = 20e-6


def _call_loop(m: Any, args: tuple, n: int) -> float:
    """Time per call [s] of ``n`` back-to-back calls (a method that raised is timed by _call)."""
    fn = m.scalar_fn
    t0 = time.perf_counter()
    for _ in range(n):
        fn(*args)
    return (time.perf_counter() - t0) / n


def _record(m: Any, val: Any, ref: np.ndarray, cond: np.ndarray, why: dict[str, int]) -> float:
    if isinstance(val, Exception):
        key = re.sub(r'[-+]?\d[\d.e+-]*', '#', f'{type(val).__name__}: {str(val)}')[:90]
        why[key] = why.get(key, 0) + 1
        return math.inf
    err = scene_error(val, ref, cond)
    if not math.isfinite(err):
        why['NaN or inf returned'] = why.get('NaN or inf returned', 0) + 1
    return err


def run_scalar(
    methods: list, sc: Scenes, idx: np.ndarray, progress: Callable[[str], None], repeats: int = 5
) -> list[Outcome]:
    """Run methods on the scenes ``idx``; per scene the best of ``repeats`` timed calls.

    The timing runs in rounds; in each round every method sweeps all the scenes (warm caches
    within a sweep), and a scene's time is its best over the rounds.  A burst of load from
    elsewhere on the machine therefore slows every method alike and the same-run ratios stay
    fair.  Calls slower than 2 ms are timed once; calls faster than ``SAMPLE_S`` are timed in
    loops of back-to-back calls from the second round on.  Inputs are passed as Python floats.
    """
    import warnings

    k_m = len(methods)
    err = np.empty((k_m, idx.size))
    t_us = np.full((k_m, idx.size), math.inf)
    raised = np.zeros((k_m, idx.size), dtype=bool)
    why: list[dict[str, int]] = [{} for _ in methods]
    args = [[tuple(float(v) for v in _args(sc, i, m.given)) for i in idx] for m in methods]
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        for rep in range(repeats):
            for j, m in enumerate(methods):
                ref, cond = (sc.ref_l, sc.cond_l) if m.given == 'length' else (sc.ref, sc.cond)
                for k, i in enumerate(idx):
                    if k % 8 == 0:
                        progress(
                            f'problem {sc.problem}, round {rep + 1}/{repeats}: '
                            f'{m.name}: {k}/{idx.size}'
                        )
                    if rep and t_us[j, k] > 2000.0:
                        continue
                    if rep and not raised[j, k] and t_us[j, k] < SAMPLE_S * 1e6:
                        dt = _call_loop(m, args[j][k], math.ceil(SAMPLE_S * 1e6 / t_us[j, k]))
                    else:
                        val, dt = _call(m, args[j][k])
                    t_us[j, k] = min(t_us[j, k], dt * 1e6)
                    if rep == 0:
                        raised[j, k] = isinstance(val, Exception)
                        err[j, k] = _record(m, val, ref[i], cond[i], why[j])
    return [
        Outcome(m, idx, err[j], t_us[j], why[j], dock=sc.dock[idx]) for j, m in enumerate(methods)
    ]


def time_vectors(
    outcomes: list[Outcome],
    scenes: dict[int, Scenes],
    n_elem: int,
    repeats: int = 5,
    progress: Callable[[str], None] = lambda s: None,
) -> None:
    """Vectorized forms: errors on the sweep; time per element on the sweep tiled to n_elem,
    best of ``repeats`` rounds in which every method runs once (interleaved, as the scalars)."""
    import warnings

    todo = [o for o in outcomes if o.method.vector_fn is not None]
    data = {}
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        for o in todo:
            sc = scenes[o.method.problem]
            cols = [sc.w, sc.h, sc.t] + ([sc.x] if sc.problem != 3 else [])
            r1, r2 = o.method.vector_fn(*(c.copy() for c in cols))
            o.vec_err = np.array(
                [scene_error((r1[i], r2[i]), sc.ref[i], sc.cond[i]) for i in range(sc.n)]
            )
            reps = -(-n_elem // sc.n)
            data[id(o)] = [np.tile(c, reps) for c in cols]
            dock = sc.dock
            if dock.any():  # the same method on the dock's scenes, tiled to the same size
                reps = -(-n_elem // int(dock.sum()))
                data[-id(o)] = [np.tile(c[dock], reps) for c in cols]
        best = {k: math.inf for k in data}
        for rep in range(repeats):
            progress(f'vectorized forms, round {rep + 1}/{repeats}')
            for o in todo:
                for key in (id(o), -id(o)):
                    if key not in data:
                        continue
                    args = [c.copy() for c in data[key]]
                    t0 = time.perf_counter()
                    o.method.vector_fn(*args)
                    best[key] = min(best[key], time.perf_counter() - t0)
    for o in todo:
        o.vec_ns = best[id(o)] / data[id(o)][0].size * 1e9
        if -id(o) in data:
            o.vec_ns_dock = best[-id(o)] / data[-id(o)][0].size * 1e9


# ------------------------------------------------------------------------------ reporting
def pareto(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both time and error (lower is better)."""
    front = []
    for i, (t, e) in enumerate(points):
        if not any((t2 <= t and e2 <= e) and (t2 < t or e2 < e) for t2, e2 in points):
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def plot_speed_accuracy(rows: list[dict], path: str) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(19, 9.0))
    for ax, problem, title in (
        (axes[0], 4, 'problem 4: tension + anchor distance -> uplift'),
        (axes[1], 3, 'problem 3: hook tension -> minimum anchor distance'),
        (axes[2], 2, 'problem 2: horizontal tension + distance -> uplift'),
    ):
        rs = [r for r in rows if r['problem'] == problem]
        labels = []
        for k, r in enumerate(rs, 1):
            t, e_med, e_fin = r['scalar_us_median'], r['error_median'], r['error_worst_finite']
            failed = r['failures'] > 0
            e_show = min(e_fin if math.isfinite(e_fin) else 1.0, 1.0)
            colour = (
                'tab:red'
                if failed
                else ('tab:green' if r['error_worst'] <= GOOD else 'tab:orange')
            )
            ax.plot([t, t], [min(e_med, 1.0), e_show], color=colour, lw=1.5, alpha=0.6)
            ax.scatter(
                [t],
                [min(e_med, 1.0)],
                s=120,
                marker='X' if failed else 'o',
                color=colour,
                edgecolor='k',
                zorder=3,
            )
            ax.annotate(
                str(k),
                (t, min(e_med, 1.0)),
                textcoords='offset points',
                xytext=(7, -3),
                fontsize=8,
                weight='bold',
            )
            if not math.isnan(r['vector_ns_per_element']):
                tv = r['vector_ns_per_element'] / 1e3
                ax.scatter(
                    [tv],
                    [min(e_med, 1.0)],
                    s=40,
                    marker='s',
                    facecolor='none',
                    edgecolor=colour,
                    zorder=2,
                )
                ax.plot([tv, t], [min(e_med, 1.0)] * 2, color=colour, lw=0.6, ls=':')
            labels.append(
                f"{k}  {r['method']}"
                + (f"  [{r['failures']}/{r['scenes']} fail]" if failed else '')
            )
        ok = [r for r in rs if r['failures'] == 0]
        pts = [(r['scalar_us_median'], r['error_worst']) for r in ok]
        front = pareto(pts)
        ax.step(
            [pts[i][0] for i in front],
            [pts[i][1] for i in front],
            where='post',
            color='k',
            lw=1,
            ls='--',
            label='Pareto front of the methods that never fail (worst error)',
        )
        ax.axhline(GOOD, color='tab:green', lw=0.6)
        ax.axhline(FAIL, color='tab:red', lw=0.6)
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_ylim(TINY / 3, 3.0)
        ax.set_xlabel('median time per solve [µs]  (● scalar, □ vectorized, per element)')
        ax.set_ylabel('error / max(1, condition number): marker median, bar to worst finite')
        ax.set_title(title, fontsize=10)
        ax.legend(loc='center left', fontsize=7)
        ax.text(
            0.0,
            -0.13,
            '\n'.join(labels),
            transform=ax.transAxes,
            fontsize=7.5,
            va='top',
            family='monospace',
        )
        ax.grid(True, which='major', alpha=0.3)
    fig.suptitle(
        'Speed against accuracy: green line 1e-12 (target), red line 1e-6 (failure); '
        'X red = fails on some scenes, amber = loses accuracy, green = within 1e-12 everywhere',
        fontsize=10,
    )
    fig.subplots_adjust(left=0.05, right=0.99, top=0.92, bottom=0.36, wspace=0.25)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_stability(outcomes: list[Outcome], scenes: dict[int, Scenes], path: str) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap(['#2ca02c', '#ffbf00', '#d62728', '#d9d9d9'])
    o4 = [o for o in outcomes if o.method.problem == 4] + [
        o for o in outcomes if o.method.problem == 2
    ]
    o3 = [o for o in outcomes if o.method.problem == 3]
    ncol = 4
    nrow4 = -(-len(o4) // ncol)
    fig = plt.figure(figsize=(3.4 * ncol, 2.5 * nrow4 + 0.45 * len(o3) + 1.6))
    gs = fig.add_gridspec(nrow4 + 1, ncol, height_ratios=[1] * nrow4 + [0.18 * len(o3) + 0.3])
    for k, o in enumerate(o4):
        sc4 = scenes[o.method.problem]
        grid_idx = np.flatnonzero(~sc4.seed)
        ha_u = np.unique(sc4.ha[grid_idx])
        xr_u = np.unique(sc4.xr[grid_idx])
        ax = fig.add_subplot(gs[k // ncol, k % ncol])
        z = np.full((xr_u.size, ha_u.size), 3.0)
        for j, i in enumerate(o.idx):
            if sc4.seed[i]:
                continue
            e = o.err[j]
            z[np.searchsorted(xr_u, sc4.xr[i]), np.searchsorted(ha_u, sc4.ha[i])] = (
                0 if e <= GOOD else 1 if e <= FAIL else 2
            )
        ax.pcolormesh(
            np.arange(ha_u.size + 1), np.arange(xr_u.size + 1), z, cmap=cmap, vmin=0, vmax=3
        )
        ax.set_title(
            f'{o.method.name}' + ('  [problem 2: R given]' if o.method.problem == 2 else ''),
            fontsize=8,
        )
        xt = [
            i
            for i, v in enumerate(ha_u)
            if abs(math.log10(v) - round(math.log10(v))) < 1e-9 and round(math.log10(v)) % 3 == 2
        ]
        ax.set_xticks([i + 0.5 for i in xt])
        ax.set_xticklabels([f'1e{round(math.log10(ha_u[i]))}' for i in xt], fontsize=6)
        yt = [0, xr_u.size // 2, xr_u.size - 4, xr_u.size - 1]
        ax.set_yticks([i + 0.5 for i in yt])
        ax.set_yticklabels([f'{xr_u[i]:.6g}' for i in yt], fontsize=6)
        if k % ncol == 0:
            ax.set_ylabel('x / x_min', fontsize=7)
        ax.set_xlabel('h / a' + (' (a = R/w)' if o.method.problem == 2 else ''), fontsize=7)
    ax = fig.add_subplot(gs[nrow4, :])
    sc3 = scenes[3]
    g3 = np.flatnonzero(~sc3.seed)
    ha3 = np.unique(sc3.ha[g3])
    z = np.full((len(o3), ha3.size), 3.0)
    for r, o in enumerate(o3):
        for j, i in enumerate(o.idx):
            if not sc3.seed[i]:
                e = o.err[j]
                z[r, np.searchsorted(ha3, sc3.ha[i])] = 0 if e <= GOOD else 1 if e <= FAIL else 2
    ax.pcolormesh(np.arange(ha3.size + 1), np.arange(len(o3) + 1), z, cmap=cmap, vmin=0, vmax=3)
    ax.set_yticks([r + 0.5 for r in range(len(o3))])
    ax.set_yticklabels([o.method.name for o in o3], fontsize=7)
    xt = [i for i, v in enumerate(ha3) if abs(math.log10(v) - round(math.log10(v))) < 1e-9]
    ax.set_xticks([i + 0.5 for i in xt])
    ax.set_xticklabels([f'1e{round(math.log10(ha3[i]))}' for i in xt], fontsize=6)
    ax.set_xlabel('h / a', fontsize=7)
    ax.set_title('problem 3 (minimum anchor distance from T): h / a only', fontsize=8)
    fig.suptitle(
        'Where each method holds: green error <= 1e-12, amber <= 1e-6 (loses accuracy), '
        'red fails (> 1e-6, NaN, exception), grey not run.\nProblem 4 (and 2) panels: '
        'x from 1e-3 x_min (bottom) to 1 - 1e-6 (top); dock chain w = 1.3 kN/m, h = 20.85 m',
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def fmt(v: float, unit: str = '') -> str:
    if isinstance(v, str):
        return v
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return '–'
    if unit == 'err':
        return f'{v:.1e}' if v < 1.0 else '≥ 1'
    return f'{v:.3g}'


def write_tables(rows: list[dict], summary: list[str], out_dir: str) -> None:
    keys = list(rows[0])
    with open(os.path.join(out_dir, 'methods.csv'), 'w', newline='') as fh:
        wr = csv.DictWriter(fh, fieldnames=keys)
        wr.writeheader()
        for r in rows:
            wr.writerow(r)
    lines = ['# Methods benchmark (generated by `catenary-monitor bench-methods`)', '']
    lines += summary + ['']
    titles = {
        4: 'Problem 4: hook tension T and anchor distance x -> uplift (the live problem)',
        3: 'Problem 3: hook tension T -> minimum anchor distance',
        2: 'Problem 2 (table 3): horizontal tension R and x -> anchor angle and uplift',
    }
    for problem in (4, 3, 2):
        lines += [
            f'## {titles[problem]}',
            '',
            '| method | scenes | scalar µs (median) | vectorized ns/element | error median | '
            'error worst | failures | dock: µs | dock: ns/element | dock: error worst | '
            'dock: failures | why it fails where it fails |',
            '|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|',
        ]
        for r in rows:
            if r['problem'] != problem:
                continue
            vf = f" ({r['vector_failures']} vec)" if r['vector_failures'] not in ('', 0) else ''
            lines.append(
                f"| {r['method']} | {r['scenes']} | {fmt(r['scalar_us_median'])} | "
                f"{fmt(r['vector_ns_per_element'])} | {fmt(r['error_median'], 'err')} | "
                f"{fmt(r['error_worst'], 'err')} | {r['failures']}{vf} | "
                f"{fmt(r['dock_scalar_us_median'])} | {fmt(r['dock_vector_ns_per_element'])} | "
                f"{fmt(r['dock_error_worst'], 'err')} | {r['dock_failures']} | {r['why']} |"
            )
        lines.append('')
    with open(os.path.join(out_dir, 'methods.md'), 'w') as fh:
        fh.write('\n'.join(lines))


# ------------------------------------------------------------------------------ main
def run(
    quick: bool = False,
    out_dir: Optional[str] = 'docs',
    only: Optional[str] = None,
    stream: Any = sys.stderr,
) -> dict[str, Any]:
    """Run the benchmark; returns rows, outcomes and the same-run ratios."""
    os.environ.setdefault('PYTHONBREAKPOINT', '0')
    from catenary_monitor_study.methods import all_methods
    from catenary_monitor_study.methods.peers import peer_versions

    status = StatusLine('[bench-methods] ', stream) if stream is not None else None

    def progress(msg: str) -> None:
        if status is not None:
            status(f'{status.elapsed():5.0f} s: {msg[:90]}')

    versions = peer_versions()
    methods = [m for m in all_methods(peers=True) if m.problem in (2, 3, 4)]
    if only:
        methods = [
            m
            for m in methods
            if only.lower() in m.name.lower()
            or m.default
            or m.name.startswith('closed form')
            or m.name == 'default kernel'
        ]
    has_len = any(m.given == 'length' for m in methods)
    scenes = {p: build_scenes(p, quick) for p in (2, 3, 4)}
    for p in (2, 3, 4):
        compute_reference(scenes[p], has_len and p == 4, progress)
    thin = 4 if quick else 1
    by_name: dict[tuple[int, str], Outcome] = {}
    for p in (2, 3, 4):
        sc = scenes[p]
        fast = [m for m in methods if m.problem == p and not m.slow]
        for o in run_scalar(fast, sc, np.arange(sc.n), progress, repeats=3 if quick else 7):
            by_name[(p, o.method.name)] = o
        idx = np.arange(sc.n)
        idx = np.concatenate([idx[~sc.seed][::thin], np.flatnonzero(sc.seed)])
        for m in methods:
            if m.problem == p and m.slow:
                by_name[(p, m.name)] = run_scalar([m], sc, idx, progress, repeats=1)[0]
    outcomes = [by_name[(m.problem, m.name)] for m in methods]
    # 20 rounds: the best is then a quiet one on a shared VM (5 left the dock 7.0-8.4x apart)
    n_vec, rounds = (20_000, 5) if quick else (100_000, 20)
    time_vectors(outcomes, scenes, n_vec, rounds, progress)
    rows = [o.row() for o in outcomes]

    def pick(problem: int, name: str) -> Optional[dict]:
        return next((r for r in rows if r['problem'] == problem and r['method'] == name), None)

    def need(problem: int, name: str) -> dict:
        row = pick(problem, name)
        if row is None:  # the baselines are always run (see the method filter above)
            raise LookupError(f'bench-methods: problem {problem} method {name!r} was not run')
        return row

    floor = need(3, 'closed form (textbook)')  # one catenary evaluation: a acosh(1 + h/a)
    default4, kernel4 = need(4, 'default'), need(4, 'default kernel')
    moorpy = pick(4, 'MoorPy catenary (L given)')
    ratios: dict[str, float] = {}
    for pre in ('', 'dock_'):  # the sweep, then its scenes in the dock's regime (same run)

        def g(r: dict, key: str) -> float:
            return float(r[pre + key])

        ratios.update(
            {
                f'{pre}default_p4_scalar_us': g(default4, 'scalar_us_median'),
                f'{pre}kernel_p4_scalar_us': g(kernel4, 'scalar_us_median'),
                f'{pre}floor_p3_scalar_us': g(floor, 'scalar_us_median'),
                f'{pre}floor_p3_vector_ns': g(floor, 'vector_ns_per_element'),
                f'{pre}default_p4_vector_ns': g(default4, 'vector_ns_per_element'),
                f'{pre}kernel_p4_vector_ns': g(kernel4, 'vector_ns_per_element'),
                f'{pre}vector_p4_over_floor': g(default4, 'vector_ns_per_element')
                / g(floor, 'vector_ns_per_element'),
                f'{pre}vector_kernel_p4_over_floor': g(kernel4, 'vector_ns_per_element')
                / g(floor, 'vector_ns_per_element'),
                f'{pre}scalar_p4_over_floor': g(default4, 'scalar_us_median')
                / g(floor, 'scalar_us_median'),
            }
        )
        if moorpy:
            ratios[f'{pre}moorpy_us'] = g(moorpy, 'scalar_us_median')
            ratios[f'{pre}moorpy_over_default'] = g(moorpy, 'scalar_us_median') / g(
                default4, 'scalar_us_median'
            )
            ratios[f'{pre}moorpy_over_kernel'] = g(moorpy, 'scalar_us_median') / g(
                kernel4, 'scalar_us_median'
            )
    for r in rows:
        r['vs_default_scalar'] = (
            r['scalar_us_median']
            / (default4 if r['problem'] == 4 else need(3, 'default'))['scalar_us_median']
        )
    summary = [
        f'Run: {time.strftime("%Y-%m-%d %H:%M")}, {platform.python_implementation()} '
        f'{platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} cores shared, '
        f'{"quick" if quick else "full"} sweep: {scenes[4].n} problem-4, '
        f'{scenes[3].n} problem-3 and '
        f'{scenes[2].n} problem-2 scenes '
        + (
            f'(slow methods on every {thin}th scene). Peers: '
            if thin > 1
            else '(every method on every scene). Peers: '
        )
        + ', '.join(f'{k} {v}' if v else f'{k} absent' for k, v in versions.items())
        + '.',
        '',
        'Error = relative error of each output (R and x_min, or R and F) divided by '
        'max(1, condition '
        'number), worst over outputs, against the 50-digit mpmath solution of the '
        'paper\'s equations '
        'computed in this run. Failure = exception, no convergence, NaN, or error > 1e-6.',
        '',
        'Same-run ratios (the speed targets), over the whole sweep and over its scenes in the '
        f'dock\'s regime (h/a {DOCK_HA[0]:g} to {DOCK_HA[1]:g}, x/x_min {DOCK_XR[0]:g} to '
        f'{DOCK_XR[1]:g}: {default4["dock_scenes"]} problem-4 scenes); `catenary-monitor bench` '
        'measures the same targets on random dock scenes at 1e3-1e6 elements:',
        '',
    ]
    for pre, label in (('', 'sweep'), ('dock_', 'dock')):
        summary += [
            f'* {label}: problem-4 scalar `solve()` {ratios[pre + "default_p4_scalar_us"]:.2f} µs '
            'median'
            + (
                f'; one MoorPy catenary call {ratios[pre + "moorpy_us"]:.0f} µs: **MoorPy / '
                f'default = {ratios[pre + "moorpy_over_default"]:.0f}×** (target ≥ 30×)'
                if moorpy
                else '; MoorPy absent'
            )
            + f'; scalar `solve()` / one scalar closed-form evaluation of problem 3 '
            f'**{ratios[pre + "scalar_p4_over_floor"]:.1f}×** (target ≤ 4×); vectorized problem '
            f'4 / the vectorized floor ({ratios[pre + "floor_p3_vector_ns"]:.1f} ns/element): '
            f'`solve()` **{ratios[pre + "vector_p4_over_floor"]:.1f}×** (target ≤ 8×), numpy '
            f'fallback kernel alone {ratios[pre + "vector_kernel_p4_over_floor"]:.1f}×',
        ]
    summary += []
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        progress('writing tables and pictures')
        write_tables(rows, summary, out_dir)
        plot_speed_accuracy(rows, os.path.join(out_dir, 'speed_accuracy.png'))
        plot_stability(outcomes, scenes, os.path.join(out_dir, 'stability_map.png'))
    if status is not None:
        status.done(f'done in {status.elapsed():.0f} s')
    return {
        'rows': rows,
        'outcomes': outcomes,
        'ratios': ratios,
        'summary': summary,
        'scenes': scenes,
    }


def cmd_bench_methods(args: argparse.Namespace) -> int:
    """Run the methods benchmark and print its table."""
    out = args.out if args.out is not None else (None if args.quick else 'docs')
    res = run(quick=args.quick, out_dir=out or None, only=args.only)
    print('\n'.join(res['summary']))
    print()
    hdr = (
        'problem',
        'method',
        'scenes',
        'scalar µs',
        'vec ns/el',
        'err median',
        'err worst',
        'failures',
        'dock µs',
        'dock ns/el',
        'dock err worst',
        'dock fail',
    )
    from catenary_monitor.cli.main import format_table

    print(
        format_table(
            [
                (
                    r['problem'],
                    r['method'],
                    r['scenes'],
                    fmt(r['scalar_us_median']),
                    fmt(r['vector_ns_per_element']),
                    fmt(r['error_median'], 'err'),
                    fmt(r['error_worst'], 'err'),
                    r['failures'],
                    fmt(r['dock_scalar_us_median']),
                    fmt(r['dock_vector_ns_per_element']),
                    fmt(r['dock_error_worst'], 'err'),
                    r['dock_failures'],
                )
                for r in res['rows']
            ],
            hdr,
        )
    )
    if out:
        print(f'\nwrote {out}/methods.md, methods.csv, speed_accuracy.png, stability_map.png')
    return 0


def register(sub: Any) -> None:
    """Add ``bench-methods`` to the ``catenary-monitor`` sub-commands."""
    p = sub.add_parser(
        'bench-methods',
        help='every solver method: speed, accuracy, stability map',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument(
        '--quick', action='store_true', help='coarser sweep, finishes in under a minute'
    )
    p.add_argument(
        '--out',
        default=None,
        metavar='DIR',
        help="where to write the tables and pictures (default: docs for a full run, "
        "nothing for --quick; '' writes nothing)",
    )
    p.add_argument(
        '--only',
        default=None,
        metavar='TEXT',
        help='run only the methods whose name contains TEXT (plus the baselines)',
    )
    p.set_defaults(func=cmd_bench_methods)
