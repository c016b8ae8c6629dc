"""``catenary-monitor bench-step``: the monitor core's cost per tension sample.

``MonitorCore.step(Tension)`` on the paper's dock (config/floating_dock.yaml: 12 lines with
their chain lengths, so a sample runs the solve, the holding values with the fixed-length chain,
the alarms), in CPU time (``time.process_time``: what the node pays, whatever else the machine
runs), against two baselines in the same run, in interleaved rounds (medians over the rounds):

* the same step with the holding values on one-element arrays (``holding_values``: the array
  path the replay twin takes, which the core took per sample before its plain-float path);
* one scalar ``solve()`` per sample: the catenary alone, the floor of any step.

The samples: every line in turn, the pretension (372 kN) with 2 kN of noise, at the paper's mean
depth (20.85 m), 1 ms apart.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
from typing import Any, Callable, Iterator, Optional

import numpy as np

__all__ = ['run', 'register']


def _events(config: Any, n: int, seed: int = 1) -> list[Any]:
    from catenary_monitor.core.monitor.events import Tension

    rng = np.random.default_rng(seed)
    lines = len(config.lines)
    values = 372e3 + rng.normal(0.0, 2e3, n)
    return [Tension(10**18 + (i + 1) * 10**6, i % lines, float(values[i])) for i in range(n)]


@contextlib.contextmanager
def _holding_on_arrays() -> Iterator[None]:
    """The core's holding values through ``holding_values`` on one-element arrays."""
    from catenary_monitor.core.monitor import derived
    from catenary_monitor.core.monitor.state import VALUE_INDEX

    def on_arrays(lc: Any, values: Any, tolerance: float = np.inf) -> dict[str, float]:
        named = {k: np.array([values[i]]) for k, i in VALUE_INDEX.items()}
        held = derived.holding_values([lc], named, tolerance)
        return {k: float(v[0]) for k, v in held.items()}

    plain = derived.holding_one
    derived.holding_one = on_arrays
    try:
        yield
    finally:
        derived.holding_one = plain


def _stepper(config: Any, events: list[Any], arrays: bool) -> Callable[[], None]:
    from catenary_monitor.core.monitor.events import Depth
    from catenary_monitor.core.monitor.monitor_core import MonitorCore

    core = MonitorCore(config, 10**18)
    core.step(Depth(10**18 + 1, 20.85))
    shift = [0]

    def run() -> None:
        offset = shift[0]
        shift[0] += 10**10
        with _holding_on_arrays() if arrays else contextlib.nullcontext():
            for ev in events:
                core.step(ev._replace(stamp_ns=ev.stamp_ns + offset))

    return run


def _solver(config: Any, events: list[Any]) -> Callable[[], None]:
    from catenary_monitor.core.physics.solve import solve

    lines = config.lines

    def run() -> None:
        for ev in events:
            lc = lines[ev.line]
            solve(
                lc.weight, 20.85, tension=ev.value, anchor_distance=lc.anchor_distance, mbl=lc.mbl
            )

    return run


def run(
    params_file: Optional[str] = None, samples: int = 2400, rounds: int = 7
) -> dict[str, Any]:
    """The figures: CPU µs per sample of each variant (medians over ``rounds``)."""
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import default_config_path

    config = config_from_params(load_params_file(params_file or default_config_path()))
    events = _events(config, samples)
    variants = {
        'step': _stepper(config, events, arrays=False),
        'step_holding_on_arrays': _stepper(config, events, arrays=True),
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
        'speedup_vs_holding_on_arrays': us['step_holding_on_arrays'] / us['step'],
        'step_over_solve': us['step'] / us['solve_only'],
    }


def report(r: dict[str, Any]) -> str:
    us = r['us_per_sample']
    return '\n'.join(
        [
            f'MonitorCore.step per tension sample, the paper\'s dock ({r["lines"]} lines), '
            f'CPU time, median of {r["rounds"]} rounds of {r["samples"]} samples',
            f'{"step (holding in plain floats)":40s} {us["step"]:8.1f} us',
            f'{"step, holding on one-element arrays":40s} {us["step_holding_on_arrays"]:8.1f} us'
            f'   ({r["speedup_vs_holding_on_arrays"]:.1f}x the step\'s time)',
            f'{"one scalar solve() (the floor)":40s} {us["solve_only"]:8.1f} us'
            f'   (the step is {r["step_over_solve"]:.1f}x it)',
        ]
    )


def register(sub: Any) -> None:
    """Add ``bench-step`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-step',
        help="the monitor core's CPU time per tension sample, against baselines",
        description='MonitorCore.step per tension sample on the paper\'s dock (CPU time), '
        'against the same step with the holding values on one-element arrays and against '
        'one scalar solve(), in the same run.',
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
