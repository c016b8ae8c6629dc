"""``catenary-monitor bench``: the public ``solve()`` on the dock's scenes and on the sweep.

Everything through ``catenary_monitor.solve`` as a library user calls it, each figure against its
baseline measured in the same run, in interleaved rounds (medians over the rounds):

* vectorized, 1e3, 1e5 and 1e6 elements: problem 4 with its margins (and problem 3) against one
  numpy closed-form evaluation of problem 3 on the same arrays, ``a*np.log1p(e + np.sqrt(e*(2 +
  e)))`` with ``e = h/a`` (the floor: one catenary evaluation);
* scalar, each call a new scene (as the node sees them): ``solve()`` against one ``math``-based
  closed-form evaluation of problem 3 (``a = T/w - h``, then the same formula) and one MoorPy
  catenary call on the same scenes (with the chain length of our solution: its cost of one
  catenary);
* the crossover: the smallest array size at which one vectorized call beats a loop of scalar
  calls per element.

Dock scenes: w = 1300 N/m, h 2-60 m, T 0.2-4 MN, x 0.05-1.5 of the minimum distance (h/a 1e-4
to 1, lifted and grounded mixed).  The sweep: the methods study's span, h/a 1e-9 to 1e4
log-uniform, x/x_min 1e-3 to 1, w 10 N/m-10 kN/m, h 1-1000 m.  The process runs with glibc's
allocator defaults, as a library user's does (``--keep-freed-memory`` applies the batch
commands' setting, cli/allocator.py, for comparison).  The machines are shared and noisy: read
the ratios.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from typing import Any, Callable, Optional

import numpy as np

from catenary_monitor.cli.status_line import StatusLine
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics import fused_kernel
from catenary_monitor.core.physics.solve import solve

W = 1300.0  # the paper's dock chain
SIZES = (1_000, 100_000, 1_000_000)
REGIMES = ('dock', 'sweep')
#: The speed targets, printed beside the figures (never asserted: benchmarks, not tests).
TARGET_VECTOR, TARGET_SCALAR, TARGET_MOORPY = 8.0, 4.0, 30.0


def scenes(regime: str, n: int, seed: int = 1) -> tuple[np.ndarray, ...]:
    """``(w, h, t, x)`` arrays of n scenes of the regime ('dock' or 'sweep')."""
    rng = np.random.default_rng(seed)
    if regime == 'dock':
        w = np.full(n, W)
        h = rng.uniform(2.0, 60.0, n)
        t = rng.uniform(0.2e6, 4e6, n)
        xr = rng.uniform(0.05, 1.5, n)
    else:
        w = 10.0 ** rng.uniform(1, 4, n)
        h = 10.0 ** rng.uniform(0, 3, n)
        t = w * (h / 10.0 ** rng.uniform(-9, 4, n) + h)
        xr = 10.0 ** rng.uniform(-3, 0, n)
    b = cat.two_prod_diff(t, w, h) / w
    x = xr * cat.grounded(b, h).min_anchor_distance
    return w, h, t, x


def _rounds(
    cases: dict[str, Callable[[], object]], rounds: int, base: Optional[str] = None
) -> dict[str, float]:
    """Median seconds per call of each case, the cases interleaved round by round, and the best
    (``NAME_best``); with ``base``, also ``NAME/base``: the median over rounds of the ratio
    within each round (a burst of load from elsewhere slows both sides of a round alike), and
    ``NAME/base_best``: best against best, what a quiet machine gives."""
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(rounds):
        for name, fn in cases.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    out = {k: float(np.median(v)) for k, v in times.items()}
    out.update({f'{k}_best': float(min(v)) for k, v in times.items()})
    if base is not None:
        for k, v in times.items():
            out[f'{k}/{base}'] = float(np.median(np.array(v) / np.array(times[base])))
            out[f'{k}/{base}_best'] = min(v) / min(times[base])
    return out


def _settle_floor(n: int) -> None:
    """Put glibc's allocator where the floor is fastest, whatever solve() allocated before.

    glibc maps a block above its mmap threshold afresh (and page-faults it in), and the threshold
    follows the largest block freed so far (up to 32 MB); its trim threshold is twice that.  So
    whether the floor's n-element temporaries come back from the heap or are mapped and faulted
    in each call depended on the sizes solve() had freed before (a 9.6 MB result block at 1e5
    left the 1e6 floor at ~5 ns per element, an 8 MB one at ~8).  One freed block of 2n doubles
    (at most 16 MB) raises the threshold above the temporaries, on every branch alike: the floor
    at its fastest, the strictest baseline.  No allocator setting is changed."""
    np.ones(2 * n).sum()


def vector_figures(regime: str, n: int) -> dict[str, float]:
    """ns per element of vectorized problem 4 (with margins), problem 3 and the floor."""
    w, h, t, x = scenes(regime, n, seed=2)
    a = t / w - h  # the floor's catenary parameter, outside its timing
    wv: Any = W if regime == 'dock' else w  # the dock's chain: one weight, as a user passes it

    def floor() -> object:
        e = h / a
        return a * np.log1p(e + np.sqrt(e * (2 + e)))

    def p4_one_thread() -> object:
        threads = fused_kernel.threads()
        fused_kernel.set_threads(1)
        try:
            return solve(wv, h, tension=t, anchor_distance=x)
        finally:
            fused_kernel.set_threads(threads)

    cases: dict[str, Callable[[], object]] = {
        'floor': floor,
        'p4': lambda: solve(wv, h, tension=t, anchor_distance=x),
        'p3': lambda: solve(wv, h, tension=t),
    }
    if fused_kernel.AVAILABLE and fused_kernel.threads() > 1:
        cases['p4_1t'] = p4_one_thread
    # 1e7 elements per case (100 rounds at 1e5, 10 at 1e6): the best round then is a quiet one
    # for the slow cases too, not only for the floor's sub-millisecond calls
    rounds = max(7, min(200, int(1e7 / n)))
    _settle_floor(n)
    med = _rounds(cases, rounds, base='floor')
    lifted = float(np.mean(solve(wv, h, tension=t, anchor_distance=x).uplift_force > 0))
    out = {f'{k}_ns': med[k] / n * 1e9 for k in cases}
    out.update({f'{k}_best_ns': med[f'{k}_best'] / n * 1e9 for k in cases})
    for k in cases:
        if k != 'floor':
            out[f'{k}_ratio'] = med[f'{k}/floor']
            out[f'{k}_ratio_best'] = med[f'{k}/floor_best']
    out['lifted_fraction'] = lifted
    return out


def _moorpy() -> Optional[Callable[..., Any]]:
    os.environ.setdefault('PYTHONBREAKPOINT', '0')  # MoorPy calls breakpoint() on some errors
    try:
        from moorpy.Catenary import catenary
    except ImportError:
        return None
    return catenary


def scalar_figures(regime: str, n: int = 2000, n_moorpy: int = 200) -> dict[str, float]:
    """us per call of scalar solve() (each call a new scene), the math floor and MoorPy."""
    w, h, t, x = scenes(regime, n, seed=3)
    wl, hl, tl, xl = (v.tolist() for v in (w, h, t, x))
    calls = list(zip(wl, hl, tl, xl))

    def floor3(w_: float, h_: float, t_: float) -> float:
        a = t_ / w_ - h_
        e = h_ / a
        return a * math.log1p(e + math.sqrt(e * (2.0 + e)))

    def run_solve() -> None:
        for w_, h_, t_, x_ in calls:
            solve(w_, h_, tension=t_, anchor_distance=x_)

    def run_floor() -> None:
        for w_, h_, t_, _ in calls:
            floor3(w_, h_, t_)

    cases: dict[str, Callable[[], object]] = {'solve': run_solve, 'floor': run_floor}
    catenary = _moorpy()
    if catenary is not None:
        # MoorPy solves a line of given length: the suspended length of our solution (the
        # scenes where MoorPy returns a profile: lifted anchors, where L is the whole chain)
        res = solve(w, h, tension=t, anchor_distance=x)
        lift = np.flatnonzero(res.uplift_force > 0)[:n_moorpy]
        mp = [
            (float(x[i]), float(h[i]), float(res.suspended_length[i]), float(w[i])) for i in lift
        ]
        ours = [(wl[i], hl[i], tl[i], xl[i]) for i in lift]

        def run_moorpy() -> None:
            for x_, h_, l_, w_ in mp:
                catenary(x_, h_, l_, 1e12 * w_ * (x_ + h_ + l_), w_)

        def run_solve_lifted() -> None:
            for w_, h_, t_, x_ in ours:
                solve(w_, h_, tension=t_, anchor_distance=x_)

    med = _rounds(cases, 9, base='floor')
    out = {
        'solve_us': med['solve'] / n * 1e6,
        'floor_us': med['floor'] / n * 1e6,
        'scalar_ratio': med['solve/floor'],
        'solve_best_us': med['solve_best'] / n * 1e6,
        'floor_best_us': med['floor_best'] / n * 1e6,
        'scalar_ratio_best': med['solve/floor_best'],
    }
    if catenary is not None:
        m = len(mp)
        mr = _rounds({'solve_lifted': run_solve_lifted, 'moorpy': run_moorpy}, 7, 'solve_lifted')
        out['moorpy_us'] = mr['moorpy'] / m * 1e6
        out['solve_lifted_us'] = mr['solve_lifted'] / m * 1e6
        out['moorpy_speedup'] = mr['moorpy/solve_lifted']
        out['moorpy_speedup_best'] = mr['moorpy/solve_lifted_best']
    return out


def crossover(regime: str) -> dict[str, float]:
    """Smallest array size at which one vectorized solve() beats a scalar loop per element."""
    w, h, t, x = scenes(regime, 256, seed=4)
    found = math.nan
    sizes = [1, 2, 4, 8, 16, 32, 64, 128, 256]
    per: dict[str, float] = {}
    for n in sizes:
        args = [v[:n] for v in (w, h, t, x)]
        lists = list(zip(*(a.tolist() for a in args)))
        reps = max(20, 4000 // n)

        def vec() -> None:
            for _ in range(reps):
                solve(args[0], args[1], tension=args[2], anchor_distance=args[3])

        def loop() -> None:
            for _ in range(reps):
                for w_, h_, t_, x_ in lists:
                    solve(w_, h_, tension=t_, anchor_distance=x_)

        med = _rounds({'vector': vec, 'loop': loop}, 5)
        per[f'vector_us_per_element_n{n}'] = med['vector'] / reps / n * 1e6
        per[f'loop_us_per_element_n{n}'] = med['loop'] / reps / n * 1e6
        if math.isnan(found) and med['vector'] < med['loop']:
            found = n
    per['crossover_n'] = found
    return per


def run(
    sizes: tuple[int, ...] = SIZES,
    regimes: tuple[str, ...] = REGIMES,
    progress: Callable[[str], None] = lambda s: None,
) -> dict[str, Any]:
    """Measure everything; returns a JSON-ready dict."""
    out: dict[str, Any] = {
        'kernel': fused_kernel.isa(),
        'threads': fused_kernel.threads(),
        'numpy': np.__version__,
        'vector': {},
        'scalar': {},
        'crossover': {},
    }
    for regime in regimes:
        for n in sizes:
            progress(f'{regime}: vectorized, {n} elements')
            out['vector'][f'{regime}_{n}'] = vector_figures(regime, n)
        progress(f'{regime}: scalar')
        out['scalar'][regime] = scalar_figures(regime)
        progress(f'{regime}: crossover')
        out['crossover'][regime] = crossover(regime)
    return out


def _vector_row(key: str, v: dict[str, float]) -> tuple[str, ...]:
    """One row of the vectorized table (``key``: regime_n)."""
    regime, n = key.split('_')
    one = (
        (f"{v['p4_1t_best_ns']:.1f}", f"{v['p4_1t_ratio_best']:.1f}x")
        if 'p4_1t_best_ns' in v
        else ('same', 'same')
    )
    return (
        regime,
        f'{int(n):.0e}'.replace('e+0', 'e'),
        f"{v['p4_best_ns']:.1f}",
        f"{v['p3_best_ns']:.1f}",
        f"{v['floor_best_ns']:.1f}",
        f"{v['p4_ratio_best']:.1f}x",
        f"{v['p4_ratio']:.1f}x",
        f"{v['p3_ratio_best']:.1f}x",
        *one,
        f"{100 * v['lifted_fraction']:.0f} %",
    )


def report(r: dict[str, Any]) -> str:
    from catenary_monitor.cli.main import format_table

    threads = r.get('threads', 1)
    text = [
        f"vectorized solve(), ns per element, best of the rounds (kernel {r['kernel']}, up to "
        f'{threads} thread{"s" if threads > 1 else ""} per call from '
        f'{2 * fused_kernel.MIN_SHARE} elements; floor = one numpy closed-form evaluation of '
        'problem 3 on the same arrays, one thread; target problem 4 <= '
        f'{TARGET_VECTOR:g}x; "median" = the median over rounds of the ratio within a round; '
        '"1 thread" = problem 4 with set_threads(1))',
        format_table(
            [_vector_row(key, v) for key, v in r['vector'].items()],
            (
                'scenes',
                'n',
                'problem 4',
                'problem 3',
                'floor',
                'p4/floor',
                'p4/floor median',
                'p3/floor',
                'p4 1 thread',
                'p4/floor 1 thread',
                'lifted',
            ),
        ),
        '',
    ]
    rows = []
    for regime, v in r['scalar'].items():
        moorpy = (
            (f"{v['moorpy_us']:.1f}", f"{v['solve_lifted_us']:.2f}", f"{v['moorpy_speedup']:.0f}x")
            if 'moorpy_us' in v
            else ('absent', '', '')
        )
        rows.append(
            (
                regime,
                f"{v['solve_best_us']:.2f}",
                f"{v['floor_best_us']:.3f}",
                f"{v['scalar_ratio_best']:.1f}x",
                f"{v['scalar_ratio']:.1f}x",
                *moorpy,
                f"{r['crossover'][regime]['crossover_n']:.0f}",
            )
        )
    text += [
        'scalar solve(), us per call, each call a new scene, best of the rounds (floor = one math '
        f'closed-form evaluation of problem 3, target <= {TARGET_SCALAR:g}x; MoorPy catenary on '
        f'the lifted scenes, medians, target >= {TARGET_MOORPY:g}x); crossover = smallest n '
        'where one vectorized call beats n scalar calls',
        format_table(
            rows,
            (
                'scenes',
                'solve() us',
                'floor us',
                'ratio',
                'ratio median',
                'MoorPy us',
                'solve() lifted us',
                'MoorPy/solve()',
                'crossover n',
            ),
        ),
    ]
    return '\n'.join(text)


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the core benchmark and print a table (or JSON)."""
    allocator = 'glibc defaults (as a library user)'
    if args.keep_freed_memory:
        from catenary_monitor.cli.allocator import keep_freed_memory

        allocator = 'keep freed memory (cli/allocator.py)' if keep_freed_memory() else allocator
    sizes = tuple(int(float(s)) for s in args.sizes.split(','))
    if args.threads is not None and fused_kernel.AVAILABLE:
        fused_kernel.set_threads(args.threads)

    status = StatusLine('[bench] ')
    r = run(sizes=sizes, regimes=tuple(args.regimes.split(',')), progress=status)
    status.done()
    r['allocator'] = allocator
    print(json.dumps(r) if args.json else f'allocator: {allocator}\n' + report(r))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        'bench',
        help='benchmark solve() on dock scenes and the sweep (scalar, vectorized, crossover)',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument('--sizes', default='1e3,1e5,1e6', help='vectorized sizes (default 1e3,1e5,1e6)')
    p.add_argument('--regimes', default='dock,sweep', help='dock, sweep or both (default)')
    p.add_argument(
        '--keep-freed-memory',
        action='store_true',
        help="apply the batch commands' allocator setting first (default: glibc defaults)",
    )
    p.add_argument(
        '--threads',
        type=_threads,
        default=None,
        help='most threads per vectorized call (default: the kernel\'s, the usable CPUs or '
        'CATENARY_MONITOR_THREADS)',
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench)


def _threads(text: str) -> int:
    """argparse type of ``--threads``: 1 to the kernel's MAX_THREADS."""
    most = 64
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= most:
        raise argparse.ArgumentTypeError(f'a thread count from 1 to {most}, not {text!r}')
    return value
