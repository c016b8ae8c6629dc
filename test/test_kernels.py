"""The C kernel (core/physics/_fused_kernel.c) against the numpy implementation it replaces, on
every instruction set this CPU runs; its residual counts per regime (counts, never timings)."""

import math

import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics import fused_kernel, inextensible
from catenary_monitor.core.physics import solve as solve_module
from catenary_monitor.core.physics.result import ALL_KEYS, Status

#: C against numpy: needs the accelerators (not in the no-compiler run).
pytestmark = pytest.mark.c_extension

W = 1300.0


def dock_scenes(n, seed=1, lifted_only=False):
    """The dock's regime: w 1300 N/m, h 2-60 m, T 0.2-4 MN, x 0.05-1.5 x_min (h/a 1e-4..1)."""
    rng = np.random.default_rng(seed)
    h = rng.uniform(2.0, 60.0, n)
    t = rng.uniform(0.2e6, 4e6, n)
    b = cat.two_prod_diff(t, W, h) / W
    hi = 1.0 if lifted_only else 1.5
    x = rng.uniform(0.05, hi, n) * cat.grounded(b, h).min_anchor_distance
    return np.full(n, W), h, t, x


def sweep_scenes(n, seed=2, beyond=0.3):
    """The methods sweep's span: h/a 1e-9..1e4, x/x_min 1e-3..2, w 10 N/m-10 kN/m, h 1-1000 m."""
    rng = np.random.default_rng(seed)
    w = 10.0 ** rng.uniform(1, 4, n)
    h = 10.0 ** rng.uniform(0, 3, n)
    t = w * (h / 10.0 ** rng.uniform(-9, 4, n) + h)
    b = cat.two_prod_diff(t, w, h) / w
    x = cat.grounded(b, h).min_anchor_distance * 10.0 ** rng.uniform(-3, beyond, n)
    return w, h, t, x


#: Agreement kernel vs numpy: relative, or of these scales for the differences (margins) and
#: for the quantities that vanish at lift-off (as test_methods_scalar allows between paths).
def _scales(w, h, t, x):
    return {
        'anchor_margin': x,
        'tide_margin': h,
        'load_margin': t,
        'uplift_force': t,
        'anchor_angle_deg': np.full_like(t, 90.0),
    }


def test_kernel_is_built():
    """CI builds it (pip install . and test/conftest.py); a missing build is a failure here."""
    assert (
        fused_kernel.AVAILABLE
    ), 'core/physics/_fused_kernel.c is not built: python setup.py build_ext --inplace'
    assert (
        fused_kernel.isa() in fused_kernel.supported() and 'baseline' in fused_kernel.supported()
    )


@pytest.mark.parametrize('scenes', [dock_scenes, sweep_scenes])
def test_arrays_equal_numpy_implementation(isa, scenes):
    w, h, t, x = scenes(40_000)
    mbl = 5.0 * t
    got = solve(w, h, tension=t, anchor_distance=x, mbl=mbl)
    ref = inextensible._solve_arrays(
        'tension',
        {'weight': w, 'depth': h, 'tension': t, 'anchor_distance': x, 'mbl': mbl},
        False,
    )
    np.testing.assert_array_equal(got.status, ref.status)
    assert (got.status == 0).all() and got.keys == ref.keys
    scale = _scales(w, h, t, x)
    for k in ALL_KEYS:
        a, b = getattr(got, k), getattr(ref, k)
        if k == 'grounded_length':
            assert np.isnan(a).all() and np.isnan(b).all()
            continue
        s = np.maximum(np.abs(b), scale.get(k, 0.0))
        assert np.max(np.abs(a - b) / s) <= 2e-14, k


def test_scalar_equals_numpy_scalar_path():
    w, h, t, x = sweep_scenes(3000, seed=7)
    for i in range(w.size):
        wi, hi, ti, xi = float(w[i]), float(h[i]), float(t[i]), float(x[i])
        got = solve(wi, hi, tension=ti, anchor_distance=xi, mbl=2.0 * ti)
        ref = inextensible._solve_scalar('tension', wi, hi, ti, xi, 2.0 * ti)
        assert got.status == ref.status == 0 and got.keys == ref.keys
        sc = {
            k: float(v[0]) for k, v in _scales(*(np.array([v]) for v in (wi, hi, ti, xi))).items()
        }
        for k in ref.keys:
            a, b = getattr(got, k), getattr(ref, k)
            assert abs(a - b) <= 2e-14 * max(abs(b), sc.get(k, 0.0)), k


def test_without_the_kernel_solve_gives_the_numpy_answers(monkeypatch):
    """The fallback where the extension is not built: solve() runs catenary.py's numpy code."""
    w, h, t, x = dock_scenes(500)
    fast = solve(w, h, tension=t, anchor_distance=x)
    one = solve(W, float(h[0]), tension=float(t[0]), anchor_distance=float(x[0]))
    monkeypatch.setattr(fused_kernel, 'AVAILABLE', False)
    monkeypatch.setattr(solve_module, '_ONE', None)
    monkeypatch.setattr(inextensible, '_ONE', None)
    monkeypatch.setattr(fused_kernel, '_k', None)  # any call into the kernel now fails
    # the Python solve() itself: the C entry that wraps it would still take a plain-float
    # element to the kernel, and the comparison would be the kernel against itself
    python_solve = solve_module.solve.__wrapped__
    slow = python_solve(w, h, tension=t, anchor_distance=x)
    one_slow = python_solve(W, float(h[0]), tension=float(t[0]), anchor_distance=float(x[0]))
    for k in fast.keys:
        np.testing.assert_allclose(getattr(fast, k), getattr(slow, k), rtol=1e-13, atol=1e-6)
        assert getattr(one, k) == pytest.approx(getattr(one_slow, k), rel=1e-13, abs=1e-6)


def _counts(w, h, t, x):
    it = np.empty(w.size, dtype=np.int64)
    rows, status = fused_kernel.solve_arrays(w, h, t, x, None, w.size, it)
    assert (status == 0).all()
    lifted = rows[ALL_KEYS.index('uplift_force')] > 0
    return it, lifted


def test_residual_counts_dock_regime():
    """Dock scenes: every lifted element converges after 2 or 3 uplift residuals (the model
    start is within 0.03 in log d there), grounded ones need none."""
    w, h, t, x = dock_scenes(100_000)
    it, lifted = _counts(w, h, t, x)
    assert (it[~lifted] == 0).all()
    counts = np.bincount(it[lifted], minlength=7)
    assert it[lifted].min() >= 2 and it[lifted].max() == 3, counts
    assert counts[3] / lifted.sum() >= 0.95, counts


def test_residual_counts_sweep():
    """The sweep (h/a 1e-9..1e4, x/x_min 1e-3..1): median 2, 90 % within 3, none beyond the
    whole-block Newton phase (FAST_STEPS) into the bracketed per-element loop."""
    w, h, t, x = sweep_scenes(100_000, beyond=0.0)
    it, lifted = _counts(w, h, t, x)
    n = it[lifted]
    assert np.median(n) == 2 and np.mean(n <= 3) >= 0.9, np.bincount(n)
    assert n.max() <= fused_kernel._k.FAST_STEPS, np.bincount(n)


def test_load_margin_table_matches_the_newton_solution():
    """Inside its range the kernel's load margin comes from its table alone: within 1e-14 of the
    Newton-converged critical parameter, h/x from 1e-6 to 7e9 (and beyond: the scalar Newton)."""
    c = np.geomspace(1e-8, 1e11, 20001)
    x = np.full(c.size, 40.0)
    h = c * x
    a_ref, ok = cat.critical_parameter(h, x)
    assert ok.all()
    t = W * (a_ref + h) * 1.5  # a load above critical: load_margin = w (a + h) - T
    r = solve(W, h, tension=t, anchor_distance=x)
    a_got = (r.load_margin + t) / W - h
    assert np.max(np.abs(a_got - a_ref) / (a_ref + h)) <= 1e-14


def test_statuses_and_nan_rules_match():
    cases = [
        (math.nan, 20.0, 1e6, 100.0, None),
        (0.0, 20.0, 1e6, 100.0, None),
        (1300.0, -1.0, 1e6, 100.0, None),
        (1300.0, 20.0, 100.0, 100.0, None),
        (1300.0, 20.0, 1e6, -3.0, None),
        (1300.0, 20.0, 1e6, 100.0, -1.0),
        (1300.0, 20.0, math.inf, 100.0, 5e6),
        (1300.0, 20.0, 1e6, None, None),
    ]
    for w, h, t, x, mbl in cases:
        got = solve(w, h, tension=t, anchor_distance=x, mbl=mbl)
        ref = inextensible._solve_scalar('tension', w, h, t, x, mbl)
        arr = solve([w], [h], tension=[t], anchor_distance=None if x is None else [x], mbl=mbl)
        assert got.status == ref.status == arr.status[0]
        assert got.keys == ref.keys == arr.keys
        for k in ALL_KEYS:
            a, b = getattr(got, k), getattr(ref, k)
            assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-14), k


def test_extreme_grounded_span_keeps_infinite_tide_margin():
    """x/a beyond exp's range: the depth the chain reaches overflows to inf, not NaN."""
    got = solve(1300.0, 20.0, tension=1e6, anchor_distance=1e6)
    ref = inextensible._solve_scalar('tension', 1300.0, 20.0, 1e6, 1e6)
    assert got.status == ref.status == Status.OK
    assert math.isinf(ref.tide_margin) and got.tide_margin == ref.tide_margin
    arr = solve([1300.0], 20.0, tension=1e6, anchor_distance=1e6)
    assert arr.tide_margin[0] == math.inf


def test_no_convergence_is_reported(monkeypatch):
    monkeypatch.setattr(cat, 'MAXITER', 0)
    one = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06)
    arr = solve(1300.0, 20.85, tension=[1623.5e3], anchor_distance=[121.06])
    assert one.status == arr.status[0] == Status.NO_CONVERGENCE
    assert math.isnan(one.uplift_force) and math.isnan(arr.horizontal_tension[0])


@pytest.fixture
def threads():
    before = fused_kernel.threads()
    yield fused_kernel.set_threads
    fused_kernel.set_threads(before)


@pytest.mark.parametrize('n', [4095, 4096, 3 * fused_kernel.MIN_SHARE + 77, 50_001])
def test_results_do_not_depend_on_the_thread_count(threads, n):
    """Shares of whole blocks on several threads give the very bits of one thread (statuses,
    residual counts, a partial last block, invalid elements and a constant weight included)."""
    w, h, t, x = sweep_scenes(n, seed=5)
    t[::97] = np.nan
    x[::89] = -1.0
    runs = []
    for count in (1, 2, 3, 7):
        threads(count)
        iters = np.empty(n, dtype=np.int64)
        out, status = fused_kernel.solve_arrays(W, h, t, x, 4e6, n, iters)
        one = solve(W, h, tension=t, anchor_distance=x, mbl=4e6)
        runs.append((out, status, iters, one.uplift_force))
    first = runs[0]
    assert np.sum(first[1] != 0) > 0 and np.sum(first[2] > 0) > 0
    for other in runs[1:]:
        for a, b in zip(first, other):
            np.testing.assert_array_equal(a, b)


def test_thread_count_from_the_environment(monkeypatch):
    monkeypatch.setenv(fused_kernel.THREADS_ENV, '3')
    assert fused_kernel.default_threads() == 3
    monkeypatch.setenv(fused_kernel.THREADS_ENV, 'many')
    with pytest.warns(UserWarning, match='CATENARY_MONITOR_THREADS'):
        fallback = fused_kernel.default_threads()
    assert 1 <= fallback <= fused_kernel._k.MAX_THREADS
    with pytest.raises(ValueError, match='threads'):
        fused_kernel.set_threads(0)


def test_bench_reports_one_thread_beside_the_default(threads):
    """``catenary-monitor bench``'s vectorized row: problem 4 with the kernel's threads and with
    one, each against the floor of the same rounds."""
    from catenary_monitor_study import bench_core

    threads(2)
    v = bench_core.vector_figures('dock', 5000)
    assert v['p4_ratio_best'] > 0 and v['p4_1t_ratio_best'] > 0
    assert fused_kernel.threads() == 2  # restored after the one-thread case
    row = bench_core._vector_row('dock_5000', v)
    assert row[8] == f"{v['p4_1t_best_ns']:.1f}" and row[-1].endswith('%')


def test_cores_left_to_other_work(threads):
    threads(3)
    with fused_kernel.cores_left_to(1) as now:
        assert now == fused_kernel.threads() == 2
        with fused_kernel.cores_left_to(5):
            assert fused_kernel.threads() == 1
        assert fused_kernel.threads() == 2
    assert fused_kernel.threads() == 3


def test_replay_leaves_the_read_ahead_its_core(threads, monkeypatch):
    """stream() solves on one thread fewer while the read-ahead decodes (two kernel threads
    beside it were slower on two cores), and gives the count back after."""
    from catenary_monitor.replay import driver

    seen = []

    def fake(*args):
        seen.append(fused_kernel.threads())
        return 'state'

    monkeypatch.setattr(driver, '_stream', fake)
    monkeypatch.setattr(driver.mcap_read, 'READ_AHEAD', 1)  # a fleet worker in this process sets 0
    threads(2)
    assert driver.stream([], None, None) == 'state'
    assert driver.stream([], None, None, jobs=4) == 'state'
    assert seen == [1, 1] and fused_kernel.threads() == 2
