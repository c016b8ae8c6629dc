"""``catenary-monitor bench``: speed of the core's problems 3 and 4, against same-run baselines.

Scalar: median microseconds per ``solve()`` call with plain floats, against the obvious way a
newcomer would write it (problem 3: ``a * math.acosh(1 + h/a)``; problem 4: scipy ``brentq`` on
the paper's equation in ``a``).  Vectorized: nanoseconds per element of one ``solve()`` call on
arrays, against one naive numpy closed-form evaluation of problem 3 on the same arrays (the floor:
the work a single catenary evaluation needs).  The machines are shared and noisy: compare the
ratios, not the absolute numbers.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Callable

import numpy as np

from catenary_monitor.core.solve import solve

W, H = 1300.0, 20.85  # the paper's dock chain and mean depth


def _scenes(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Dock-like scenes: hook tension 0.3-3 MN, depth 15-26 m, anchor 20-100 % of x_min."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0.3e6, 3.0e6, n)
    h = rng.uniform(15.0, 26.0, n)
    x = rng.uniform(0.2, 1.0, n) * solve(W, h, tension=t).min_anchor_distance
    return t, h, x


def _median_us(fn: Callable[[int], object], n: int, repeats: int = 5) -> float:
    """Median over ``repeats`` runs of the mean time per call of ``fn(i)`` for i < n, in us."""
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for i in range(n):
            fn(i)
        runs.append((time.perf_counter() - t0) / n * 1e6)
    return float(np.median(runs))


def _median_ns_per_elem(fn: Callable[[], object], n: int, repeats: int = 7) -> float:
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        runs.append((time.perf_counter() - t0) / n * 1e9)
    return float(np.median(runs))


def run(n_scalar: int = 2000, n_vector: int = 200_000) -> dict[str, float]:
    """Measure everything; returns a flat dict of figures (us, ns/element and ratios)."""
    from scipy.optimize import brentq

    t, h, x = _scenes(max(n_scalar, 1))
    tl, hl, xl = t.tolist(), h.tolist(), x.tolist()

    def naive3(i: int) -> float:
        a = tl[i] / W - hl[i]
        return a * math.acosh(1.0 + hl[i] / a)

    def naive4(i: int) -> float:
        big_a, b = tl[i] / W, tl[i] / W - hl[i]

        def g(a: float) -> float:
            return a * (math.acosh(big_a / a) - math.acosh(b / a)) - xl[i]

        return brentq(g, 1e-12 * b, b, xtol=1e-300, rtol=8.9e-16)

    out: dict[str, float] = {}
    steps = [
        ('p3_scalar_us', lambda: _median_us(lambda i: solve(W, hl[i], tension=tl[i]), n_scalar)),
        ('p3_scalar_baseline_us', lambda: _median_us(naive3, n_scalar)),
        (
            'p4_scalar_us',
            lambda: _median_us(
                lambda i: solve(W, hl[i], tension=tl[i], anchor_distance=xl[i]), n_scalar
            ),
        ),
        ('p4_scalar_baseline_us', lambda: _median_us(naive4, n_scalar // 4)),
    ]
    tv, hv, xv = _scenes(n_vector, seed=2)

    def floor() -> np.ndarray:
        a = tv / W - hv
        return a * np.arccosh(1.0 + hv / a)

    steps += [
        ('p3_vector_ns', lambda: _median_ns_per_elem(lambda: solve(W, hv, tension=tv), n_vector)),
        (
            'p4_vector_ns',
            lambda: _median_ns_per_elem(
                lambda: solve(W, hv, tension=tv, anchor_distance=xv), n_vector
            ),
        ),
        ('vector_floor_ns', lambda: _median_ns_per_elem(floor, n_vector)),
    ]
    for k, (name, step) in enumerate(steps, 1):
        print(f'\r[{k}/{len(steps)}] {name:<24}', end='', file=sys.stderr, flush=True)
        out[name] = step()
    print('\r' + ' ' * 40 + '\r', end='', file=sys.stderr, flush=True)
    out['p3_scalar_ratio'] = out['p3_scalar_us'] / out['p3_scalar_baseline_us']
    out['p4_scalar_speedup_vs_brentq'] = out['p4_scalar_baseline_us'] / out['p4_scalar_us']
    out['p3_vector_ratio_to_floor'] = out['p3_vector_ns'] / out['vector_floor_ns']
    out['p4_vector_ratio_to_floor'] = out['p4_vector_ns'] / out['vector_floor_ns']
    return out


def report(r: dict[str, float]) -> str:
    rows = [
        (
            'problem 3 (x_min from T)',
            'scalar solve()',
            f"{r['p3_scalar_us']:.2f} us",
            f"naive math.acosh {r['p3_scalar_baseline_us']:.2f} us",
            f"x{r['p3_scalar_ratio']:.1f} slower",
        ),
        (
            'problem 4 (uplift from T, x)',
            'scalar solve()',
            f"{r['p4_scalar_us']:.2f} us",
            f"scipy brentq {r['p4_scalar_baseline_us']:.2f} us",
            f"x{r['p4_scalar_speedup_vs_brentq']:.1f} faster",
        ),
        (
            'problem 3',
            'vectorized solve()',
            f"{r['p3_vector_ns']:.1f} ns/elem",
            f"numpy closed form {r['vector_floor_ns']:.1f} ns/elem",
            f"x{r['p3_vector_ratio_to_floor']:.1f} the floor",
        ),
        (
            'problem 4',
            'vectorized solve()',
            f"{r['p4_vector_ns']:.1f} ns/elem",
            f"numpy closed form {r['vector_floor_ns']:.1f} ns/elem",
            f"x{r['p4_vector_ratio_to_floor']:.1f} the floor",
        ),
    ]
    from catenary_monitor.cli.main import format_table

    return format_table(rows, ('problem', 'path', 'time', 'baseline (same run)', 'ratio'))


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the core benchmark and print a table (or JSON)."""
    r = run(n_scalar=args.n_scalar, n_vector=args.n_vector)
    print(json.dumps(r) if args.json else report(r))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        'bench',
        help='benchmark the core (problems 3 and 4, scalar and vectorized)',
        description=__doc__.split('\n\n')[0],
    )
    p.add_argument(
        '--n-scalar', type=int, default=2000, help='scalar calls per timing (default 2000)'
    )
    p.add_argument('--n-vector', type=int, default=200_000, help='elements per vectorized call')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=cmd_bench)
