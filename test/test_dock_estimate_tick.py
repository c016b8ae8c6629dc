"""The dock estimate one tick at a time in plain floats (core/body/estimate_tick.py) against its
array formulation (estimate_dock_arrays): the same offsets, loads, residuals and drops to
rounding, on the plain dock and with clump weights (tables and the exact solve), with readings
missing, a line far off and lines excluded; and the chain's plain-float closed forms and
Newton against the array functions."""

import dataclasses
import math

import numpy as np
import pytest
from dock_data import ACCURACY, dock_config

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import solve_equilibrium
from catenary_monitor.core.body.estimate import estimate_dock, estimate_dock_arrays
from catenary_monitor.core.config.parameters import config_from_params
from catenary_monitor.core.physics import fixed_length as fl
from catenary_monitor_study import bench_point_loads

DEPTH = 20.85


def _clumped_model(tables=True):
    from dock_data import DOCK_YAML

    model = DockModel.from_config(
        config_from_params(bench_point_loads.clumped_params(str(DOCK_YAML)))
    )
    return model if tables else dataclasses.replace(model, tables=())


def _readings(model, n, seed):
    eq = solve_equilibrium(model, DEPTH, np.array([2e5, -8e5, 1e6]))
    truth = eq.lines.statics.top_tension
    rng = np.random.default_rng(seed)
    tensions = truth[None, :] + rng.normal(0.0, ACCURACY, (n, truth.size))
    tensions[::5, 3] += 300e3  # a line far off now and then: dropped
    usable = rng.random(tensions.shape) > 0.1  # readings missing
    usable[::9, :10] = False  # too few readings: no estimate
    depth = DEPTH + rng.uniform(-0.8, 0.8, n)
    return depth, tensions, usable


def _same(got, want):
    for field in got._fields:
        a, b = getattr(got, field), getattr(want, field)
        assert a.shape == b.shape and a.dtype.kind == b.dtype.kind, field
        if a.dtype.kind in 'bi':
            assert np.array_equal(a, b), field
            continue
        assert np.array_equal(np.isnan(a), np.isnan(b)), field
        atol = {'offset': 1e-9, 'load': 1e-2, 'normalized': 1e-8}.get(field, 1e-4)  # m, N, N m
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=atol, err_msg=field)


def _model(dock):
    if dock == 'plain':
        return DockModel.from_config(dock_config())
    if dock == 'elastic':
        config = dock_config()
        flat = {f'{line.name}.ea': 6.63e8 for line in config.lines}
        return DockModel.from_config(dock_config(**flat))
    return _clumped_model(tables=dock == 'tables')


@pytest.mark.parametrize('dock', ['plain', 'elastic', 'tables', 'exact'])
def test_one_tick_in_plain_floats_is_the_array_estimate(dock):
    model = _model(dock)
    if dock == 'elastic':
        assert np.isfinite(model.ea).all()
    n = 4 if dock == 'exact' else 60
    depth, tensions, usable = _readings(model, n, seed=3)
    exclude = np.zeros(tensions.shape[1], bool)
    exclude[7] = True
    for ex in (None, exclude):
        got = estimate_dock(model, depth, tensions, usable, ex)
        _same(got, estimate_dock_arrays(model, depth, tensions, usable, ex))
        if dock != 'exact':  # not vacuous: estimates, drops, and ticks without an estimate
            assert got.valid.any() and not got.valid.all() and got.dropped.any()


def test_each_tick_the_same_bits_alone_or_in_a_window():
    model = _clumped_model()
    depth, tensions, usable = _readings(model, 20, seed=4)
    est = estimate_dock(model, depth, tensions, usable)
    for i in range(20):
        one = estimate_dock(model, depth[i : i + 1], tensions[i : i + 1], usable[i : i + 1])
        for field in est._fields:
            assert np.array_equal(getattr(one, field)[0], getattr(est, field)[i], equal_nan=True)


@pytest.mark.parametrize('ea', [math.inf, 6.63e8])
def test_the_chains_plain_float_forms_are_the_array_ones(ea):
    rng = np.random.default_rng(5)
    w, length = 1300.0, 122.6247
    for _ in range(300):
        h = rng.uniform(15.0, 30.0)
        t = rng.uniform(1.05, 40.0) * w * h
        s, d = fl.span_and_sensitivity_scalar(w, h, length, t, ea)
        s_a, d_a = fl.span_and_sensitivity(w, h, length, t, ea)
        assert s == pytest.approx(float(s_a), rel=1e-13, abs=1e-12)
        assert d == pytest.approx(float(d_a), rel=1e-9)
        if not s == s:
            continue
        start = t * rng.uniform(0.7, 1.3)
        top, hor = fl.tension_at_span_scalar(w, h, length, s, ea, start)
        st = fl.statics_at_span(w, h, length, s, ea, start)
        assert top == pytest.approx(float(st.top_tension), rel=1e-10)
        assert hor == pytest.approx(float(st.horizontal_tension), rel=1e-10)
        assert top == pytest.approx(t, rel=1e-8)
    # slack and (inextensible) beyond reach, as the array path answers
    assert fl.tension_at_span_scalar(w, 20.0, length, 50.0, ea, 1e5) == (
        pytest.approx(float(fl.statics_at_span(w, 20.0, length, 50.0, ea).top_tension)),
        0.0,
    )
    if math.isinf(ea):
        assert fl.tension_at_span_scalar(w, 20.0, length, 125.0, ea, 1e5) == (math.inf,) * 2
