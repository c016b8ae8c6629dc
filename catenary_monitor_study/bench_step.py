"""``catenary-monitor bench-step``: the monitor core's cost per tension sample.

``MonitorCore.step(Tension)`` on the paper's dock (config/floating_dock.yaml: 12 lines with
their chain lengths, so a sample runs the solve, the bounds within the sensors' accuracy, the
holding values with the fixed-length chain, the alarms), in CPU time (``time.process_time``:
what the node pays, whatever else the machine runs), against baselines in the same run, in
interleaved rounds (medians over the rounds):

* the same step in a storm: every tension 128 kN above the pretension (500 kN, the readings
  ``bench-latency`` sends), every anchor lifted, its ERROR and three warnings up, each update's
  message formatted;
* the same step with the bounds of the sampled box (five depths and the parabola's vertex, numpy
  on one element: the core's bounds before they came from the analysis);
* one scalar ``solve()`` per sample: the catenary alone, the floor of any step.

The samples: every line in turn, the pretension (372 kN) with 2 kN of noise, at the paper's mean
depth (20.85 m), 1 ms apart. Target: the step at most :data:`TARGET_US` µs.

:func:`step_over_solve` is the suite's check (test/test_step_cost.py): the step's cost over
the scalar solve's, both the least CPU time of a few rounds in one process, against
:data:`RECORDED_STEP_OVER_SOLVE`; the suite fails when it doubles, so a feature that puts its
cost on the live path says so in the commit that records the new ratio.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
from typing import Any, Callable, Iterator, Optional

import numpy as np

__all__ = ['run', 'register', 'step_over_solve', 'RECORDED_STEP_OVER_SOLVE', 'TARGET_US']

#: The step at most this (µs of CPU per tension sample): 12 lines x 100 Hz in a tenth of a core.
TARGET_US = 100.0
#: :func:`step_over_solve` as recorded on the 2-vCPU x86-64 VM (2026-12-07: 159-165 at loads
#: 7-8, the C kernel built); the suite fails at twice this.
RECORDED_STEP_OVER_SOLVE = 165.0
#: The storm's tensions above the pretension [N] (bench-latency's readings, 500 kN).
STORM = 128e3


def _events(config: Any, n: int, seed: int = 1, add: float = 0.0) -> list[Any]:
    from catenary_monitor.core.monitor.events import Tension

    rng = np.random.default_rng(seed)
    lines = len(config.lines)
    values = 372e3 + add + rng.normal(0.0, 2e3, n)
    return [Tension(10**18 + (i + 1) * 10**6, i % lines, float(values[i])) for i in range(n)]


@contextlib.contextmanager
def _sampled_bounds() -> Iterator[None]:
    """The core's bounds by the sampled box on one-element arrays (what the core took before
    the analysis): :func:`~catenary_monitor.core.rules.uncertainty.sampled_bounds`."""
    from catenary_monitor.core.rules import uncertainty

    def sampled(*given: float) -> tuple[float, float, float]:
        b = uncertainty.sampled_bounds(*(np.array([v]) for v in given))
        upper, anchor, tide = (float(b[key][0]) for key in uncertainty.FIELDS)
        return upper, anchor, tide

    analytic = uncertainty.bounds_one
    uncertainty.bounds_one = sampled  # type: ignore[assignment]
    try:
        yield
    finally:
        uncertainty.bounds_one = analytic


def _stepper(config: Any, events: list[Any], sampled: bool = False) -> Callable[[], None]:
    from catenary_monitor.core.monitor.events import Depth
    from catenary_monitor.core.monitor.monitor_core import MonitorCore

    core = MonitorCore(config, 10**18)
    core.step(Depth(10**18 + 1, 20.85))
    shift = [0]

    def run() -> None:
        offset = shift[0]
        shift[0] += 10**10
        with _sampled_bounds() if sampled else contextlib.nullcontext():
            for ev in events:
                core.step(ev._replace(stamp_ns=ev.stamp_ns + offset))

    return run


def _solver(config: Any, events: list[Any], repeat: int = 1) -> Callable[[], None]:
    from catenary_monitor.core.physics.solve import solve

    lines = config.lines
    given = [(lines[ev.line], ev.value) for ev in events] * repeat

    def run() -> None:
        for lc, t in given:
            solve(lc.weight, 20.85, tension=t, anchor_distance=lc.anchor_distance, mbl=lc.mbl)

    return run


def _config(params_file: Optional[str] = None) -> Any:
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import default_config_path

    return config_from_params(load_params_file(params_file or default_config_path()))


def run(
    params_file: Optional[str] = None, samples: int = 2400, rounds: int = 7
) -> dict[str, Any]:
    """The figures: CPU µs per sample of each variant (medians over ``rounds``)."""
    config = _config(params_file)
    events = _events(config, samples)
    variants = {
        'step': _stepper(config, events),
        'step_storm': _stepper(config, _events(config, samples, add=STORM)),
        'step_sampled_bounds': _stepper(config, events, sampled=True),
        'solve_only': _solver(config, events),
    }
    for run_one in variants.values():  # warm-up (imports, caches)
        run_one()
    times: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(rounds):
        for name, run_one in variants.items():
            t0 = time.process_time()
            run_one()
            times[name].append((time.process_time() - t0) / samples * 1e6)
    us = {k: float(np.median(v)) for k, v in times.items()}
    return {
        'lines': len(config.lines),
        'samples': samples,
        'rounds': rounds,
        'us_per_sample': us,
        'speedup_vs_sampled_bounds': us['step_sampled_bounds'] / us['step'],
        'step_over_solve': us['step'] / us['solve_only'],
        'recorded_step_over_solve': RECORDED_STEP_OVER_SOLVE,
        'target_us': TARGET_US,
        'target_met': us['step'] <= TARGET_US,
    }


def step_over_solve(samples: int = 1200, rounds: int = 5, repeat: int = 20) -> float:
    """The step's CPU time per sample over one scalar ``solve()``'s on the paper's dock, each
    the least of ``rounds`` interleaved rounds (the solve's loop ``repeat`` times longer, so
    that both last milliseconds): a ratio of one process's times, which a loaded machine moves
    little (its CPU time, its quietest round)."""
    config = _config()
    events = _events(config, samples)
    step, solve_loop = _stepper(config, events), _solver(config, events, repeat)
    step()
    solve_loop()
    best = [float('inf'), float('inf')]
    for _ in range(rounds):
        for k, (fn, n) in enumerate(((step, samples), (solve_loop, samples * repeat))):
            t0 = time.process_time()
            fn()
            best[k] = min(best[k], (time.process_time() - t0) / n)
    return best[0] / best[1]


def report(r: dict[str, Any]) -> str:
    us = r['us_per_sample']
    verdict = 'met' if r['target_met'] else 'NOT met'
    return '\n'.join(
        [
            f'MonitorCore.step per tension sample, the paper\'s dock ({r["lines"]} lines), '
            f'CPU time, median of {r["rounds"]} rounds of {r["samples"]} samples',
            f'{"step (the pretension, 372 kN)":44s} {us["step"]:8.1f} us',
            f'{"step in a storm (500 kN: anchors lifted)":44s} {us["step_storm"]:8.1f} us',
            f'{"step, bounds of the sampled box (numpy)":44s} {us["step_sampled_bounds"]:8.1f} us'
            f'   ({r["speedup_vs_sampled_bounds"]:.1f}x the step\'s time)',
            f'{"one scalar solve() (the floor)":44s} {us["solve_only"]:8.1f} us'
            f'   (the step is {r["step_over_solve"]:.1f}x it; recorded '
            f'{r["recorded_step_over_solve"]:g}x, the suite fails at twice that)',
            f'target: step <= {r["target_us"]:g} us {verdict}',
        ]
    )


def register(sub: Any) -> None:
    """Add ``bench-step`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-step',
        help="the monitor core's CPU time per tension sample, against baselines",
        description='MonitorCore.step per tension sample on the paper\'s dock (CPU time), '
        'at the pretension and in a storm, against the same step with the bounds of the '
        'sampled box and against one scalar solve(), in the same run.',
    )
    p.add_argument('--params-file', metavar='F', help='default: config/floating_dock.yaml')
    p.add_argument('--samples', type=int, default=2400, help='per round (default: 2400)')
    p.add_argument('--rounds', type=int, default=7, help='interleaved rounds (default: 7)')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(func=_command)


def _command(args: argparse.Namespace) -> int:
    r = run(args.params_file, max(12, args.samples), max(1, args.rounds))
    print(json.dumps(r) if args.json else report(r))
    return 0
