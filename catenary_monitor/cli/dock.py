"""Sub-commands of the dock model: ``equilibrium`` and ``envelope`` (docs/dock_body.md).

Wiring only: the physics is in :mod:`catenary_monitor.core.body`. Tables in display units (kN,
m, deg) by default, ``--json`` in SI. Exit status: 0 success; 2 bad input (one line); 3 no
equilibrium under that load (the chains cannot hold it, or the solve did not converge).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.cli.table import format_table, json_ready

__all__ = ['register', 'cmd_equilibrium', 'cmd_envelope']


class UsageError(Exception):
    """Bad input: one line on stderr, exit status 2."""


def _guarded(func: Any) -> Any:
    """Run a command; a UsageError becomes one line on stderr and exit status 2."""

    def run(args: argparse.Namespace) -> int:
        try:
            return int(func(args) or 0)
        except UsageError as err:
            print(f'catenary-monitor: {err}', file=sys.stderr)
            return 2

    run.__doc__ = func.__doc__
    return run


def _model(params_file: str) -> Any:
    """The dock model of a params file (UsageError, one line, if it cannot be built)."""
    from catenary_monitor.core.body.dock_model import DockModel
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )

    try:
        config = config_from_params(load_params_file(params_file), body_only=True)
        return DockModel.from_config(config)
    except (ConfigError, ValueError) as err:
        raise UsageError(f'{params_file}: {err}') from None


def _numbers(text: str, count: int, name: str) -> list[float]:
    parts = text.split(',')
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        what = 'a finite number' if count == 1 else f'{count} finite numbers separated by commas'
        raise UsageError(f'{name} must be {what}, got {text!r}')
    return values


def _depth(text: str) -> float:
    value = _numbers(text, 1, '--depth')[0]
    if not value > 0:
        raise UsageError(f'--depth must be > 0 m, got {text!r}')
    return value


def _environment(args: argparse.Namespace, model: Any) -> tuple[np.ndarray, dict[str, Any]]:
    """The load (Fx, Fy, Mz) from --load or the paper's formulas, and what it was made of."""
    from catenary_monitor.core.body.loads import environmental_load

    if args.load is not None:
        if any(v is not None for v in (args.wind, args.wind_from, args.current, args.hs)):
            raise UsageError('give --load or --wind/--wind-from/--current/--hs, not both')
        load = np.array(_numbers(args.load, 3, '--load'))
        return load, {'load': load.tolist()}
    if args.wind is None or args.wind_from is None:
        raise UsageError('give --load FX,FY,MZ or --wind V --wind-from DEG')
    if args.current is not None and args.current_from is None:
        raise UsageError('--current needs --current-from DEG')
    try:
        loads = environmental_load(
            model.dock,
            wind=args.wind,
            wind_from=args.wind_from,
            current=args.current or 0.0,
            current_from=args.current_from,
            hs=args.hs or 0.0,
        )
    except ValueError as err:
        raise UsageError(str(err)) from None
    env = {
        'wind': args.wind,
        'wind_from': args.wind_from,
        'current': args.current or 0.0,
        'current_from': args.wind_from if args.current_from is None else args.current_from,
        'hs': args.hs or 0.0,
        'wind_load': loads.wind.tolist(),
        'current_load': loads.current.tolist(),
        'wave_load': loads.waves.tolist(),
        'load': loads.total.tolist(),
    }
    return loads.total, env


def _fmt(value: Any, scale: float = 1.0, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return '-'
    return f'{value * scale:.{digits}f}'


def cmd_equilibrium(args: argparse.Namespace) -> int:
    """The dock's offset and every line under a load (table or JSON)."""
    from catenary_monitor.core.body.equilibrium import (
        EquilibriumStatus,
        line_report,
        solve_equilibrium,
    )

    model = _model(args.params_file)
    depth = _depth(args.depth)
    load, env = _environment(args, model)
    eq = solve_equilibrium(model, depth, load)
    if eq.status == EquilibriumStatus.BAD_INPUT:
        raise UsageError(eq.message)
    lines = line_report(model, eq.lines) if eq.lines is not None else []
    ok = eq.status == EquilibriumStatus.CONVERGED
    if args.json:
        out = {
            'status': eq.status.name.lower(),
            'message': eq.message,
            'depth': depth,
            'offset_x': eq.offset_x,
            'offset_y': eq.offset_y,
            'yaw_deg': eq.yaw_deg,
            'load_x': float(load[0]),
            'load_y': float(load[1]),
            'load_mz': float(load[2]),
            'iterations': eq.iterations,
            'residual': eq.residual.tolist(),
            'environment': env,
            'lines': lines,
        }
        print(json.dumps(json_ready(out), allow_nan=False))
    else:
        print(_equilibrium_table(eq, depth, load, env, lines))
    if not ok:
        print(f'catenary-monitor: {eq.message}', file=sys.stderr)
        return 3
    return 0


def _equilibrium_table(
    eq: Any, depth: float, load: np.ndarray, env: dict[str, Any], lines: list[dict[str, Any]]
) -> str:
    head = [
        f'depth {depth:g} m; load Fx {load[0] / 1e3:.1f} kN, Fy {load[1] / 1e3:.1f} kN, '
        f'Mz {load[2] / 1e3:.1f} kN m'
    ]
    if 'wind' in env:
        head.append(
            f"  from wind {env['wind']:g} m/s from {env['wind_from']:g} deg"
            + (
                f", current {env['current']:g} m/s from {env['current_from']:g} deg"
                if env['current']
                else ''
            )
            + (f", Hs {env['hs']:g} m" if env['hs'] else '')
        )
    head.append(
        f'{eq.message.upper() if eq.status else eq.message}: offset x {eq.offset_x:+.3f} m '
        f'(+ to the bow), y {eq.offset_y:+.3f} m (+ to port), yaw {eq.yaw_deg:+.4f} deg '
        f'(+ bow to port; {eq.iterations} Newton steps)'
    )
    rows = [
        (
            r['line'],
            r['state'],
            _fmt(r['anchor_distance'], 1.0, 3),
            _fmt(r['top_tension'], 1e-3, 1),
            _fmt(r['horizontal_tension'], 1e-3, 1),
            _fmt(r['uplift_force'], 1e-3, 1),
            _fmt(r['grounded_length'], 1.0, 2),
            _fmt(r['anchor_margin'], 1.0, 2),
            _fmt(r['load_margin'], 1e-3, 1),
            _fmt(r['safety_factor'], 1.0, 2),
        )
        for r in lines
    ]
    header = (
        'line',
        'state',
        'span m',
        'T kN',
        'R kN',
        'uplift kN',
        'grounded m',
        'anchor margin m',
        'load margin kN',
        'MBL/T',
    )
    broken = [r['line'] for r in lines if r['safety_factor'] < 1.0]
    foot = (
        f'\nABOVE ITS BREAKING LOAD (MBL/T < 1): {", ".join(broken)}: the chain parts before '
        'this equilibrium is reached'
        if broken
        else ''
    )
    return '\n'.join(head) + '\n\n' + format_table(rows, header) + foot


def cmd_envelope(args: argparse.Namespace) -> int:
    """For each direction, the smallest load and wind that lift an anchor (table, JSON, PNG)."""
    from catenary_monitor.core.body.envelope import uplift_envelope

    model = _model(args.params_file)
    depths = (
        [_depth(d) for d in args.depth.split(',')] if ',' in args.depth else [_depth(args.depth)]
    )
    if not 0 < args.step <= 180:
        raise UsageError(f'--step must be in (0, 180] deg, got {args.step:g}')
    directions = np.arange(0.0, 360.0 - 1e-9, args.step)
    wind, why = _wind_ready(model)
    results = []
    for depth in depths:
        progress = None if args.quiet else _progress(depth)
        rows = uplift_envelope(model, depth, directions, wind=wind, progress=progress)
        results.append((depth, rows))
    if args.plot:
        from catenary_monitor.cli.dock_plot import envelope_chart

        envelope_chart(args.plot, results, wind, _title(args.params_file))
    if args.json:
        out = {
            'wind': wind,
            'note': why,
            'depths': [
                {'depth': depth, 'directions': [r._asdict() for r in rows]}
                for depth, rows in results
            ],
        }
        print(json.dumps(json_ready(out), allow_nan=False))
    else:
        for depth, rows in results:
            print(_envelope_table(depth, rows, wind, why))
        if args.plot:
            print(f'chart: {args.plot}')
    failures = [_envelope_failure(rows) for _, rows in results]
    for (depth, _), failed in zip(results, failures):
        if failed:
            print(f'catenary-monitor: depth {depth:g} m: {failed}', file=sys.stderr)
    return 3 if any(failures) else 0


def _title(path: str) -> str:
    from pathlib import Path

    return Path(path).name


def _wind_ready(model: Any) -> tuple[bool, str]:
    from catenary_monitor.core.body.loads import wind_load_per_speed2

    try:
        wind_load_per_speed2(model.dock, 0.0)
    except ValueError as err:
        return False, f'no wind envelope: {err}'
    return True, ''


def _progress(depth: float) -> Any:
    if not sys.stderr.isatty():
        return None

    def report(i: int, n: int) -> None:
        end = '\n' if i == n else ''
        print(f'\renvelope at {depth:g} m: {i}/{n} directions', end=end, file=sys.stderr)

    return report


def _envelope_table(depth: float, rows: Sequence[Any], wind: bool, why: str) -> str:
    head = (
        f'uplift envelope at depth {depth:g} m: smallest load from each direction (deg, '
        'clockwise from the bow) at which the first anchor lifts'
    )
    table_rows = []
    for r in rows:
        row = [f'{r.direction_deg:g}', _fmt(r.force, 1e-3, 1)]
        row += [_lifts(r.force_line, r.force_status)]
        if wind:
            row += [_fmt(r.wind, 1.0, 2), _lifts(r.wind_line, r.wind_status)]
            row += [_fmt(r.wind_load, 1e-3, 1)]
        table_rows.append(row)
    header = ['from deg', 'force kN', 'lifts']
    if wind:
        header += ['wind m/s', 'lifts', 'wind load kN']
    lowest = min((r for r in rows if math.isfinite(r.force)), key=lambda r: r.force, default=None)
    foot = ''
    if lowest is not None:
        foot = (
            f'\nweakest: {lowest.force / 1e3:.1f} kN from {lowest.direction_deg:g} deg '
            f'({lowest.force_line})'
        )
    if wind:
        lw = min((r for r in rows if math.isfinite(r.wind)), key=lambda r: r.wind, default=None)
        if lw is not None:
            foot += f'; wind {lw.wind:.2f} m/s from {lw.direction_deg:g} deg ({lw.wind_line})'
    elif why:
        foot += f'\n{why}'
    failed = _envelope_failure(rows)
    if failed:
        foot += f'\nno envelope at this depth: {failed}'
    at_rest = sorted({r.force_line for r in rows if r.force_status == 'lifted at rest'})
    if at_rest:
        foot += f'\nanchor already lifted with no load at this depth: {", ".join(at_rest)}'
    return head + '\n\n' + format_table(table_rows, header) + foot + '\n'


#: The envelope's own outcomes; any other status is the equilibrium's that stopped the search.
_ENVELOPE_STATUSES = ('lifts', 'lifted at rest', 'none below limit', 'not computed')


def _lifts(line: Optional[str], status: str) -> str:
    """The 'lifts' cell: the line whose anchor lifts first, else what stopped the search."""
    if line:
        return line
    return status if status in _ENVELOPE_STATUSES else 'no equilibrium'


def _envelope_failure(rows: Sequence[Any]) -> str:
    """Why no direction has an envelope (every search stopped by the equilibrium), else ''."""
    from catenary_monitor.core.body.equilibrium import EQUILIBRIUM_MESSAGES, EquilibriumStatus

    if not rows or any(r.force_status in _ENVELOPE_STATUSES for r in rows):
        return ''
    status = EquilibriumStatus[rows[0].force_status.upper()]
    return f'the dock has no equilibrium even unloaded: {EQUILIBRIUM_MESSAGES[status]}'


def _add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        '--params-file',
        required=True,
        metavar='F',
        help='ROS 2 params YAML with the dock geometry (hook_x, hook_y, heading, chain_length)',
    )
    p.add_argument('--json', action='store_true', help='print one JSON object (SI units)')


def register(sub: Any) -> None:
    """Add ``equilibrium`` and ``envelope`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'equilibrium',
        help='the dock in equilibrium under a load: offset, yaw, every line',
        description='Solve the dock with all its chains in static equilibrium (surge, sway, '
        'yaw) under a load given directly or by the seed paper\'s wind, current and wave '
        'formulas; print the offset and every line\'s tensions, uplift and margins.',
    )
    _add_common(p)
    p.add_argument('--depth', required=True, metavar='D', help='tide depth at the hooks [m]')
    p.add_argument('--load', metavar='FX,FY,MZ', help='load on the dock [N, N, N m], dock frame')
    p.add_argument('--wind', type=float, metavar='V', help='wind speed [m/s]')
    p.add_argument(
        '--wind-from', type=float, metavar='DEG', help='wind from [deg, clockwise from the bow]'
    )
    p.add_argument('--current', type=float, metavar='V', help='current speed [m/s]')
    p.add_argument('--current-from', type=float, metavar='DEG', help='current from [deg]')
    p.add_argument(
        '--hs', type=float, metavar='H', help='significant wave height [m], from the wind'
    )
    p.set_defaults(func=_guarded(cmd_equilibrium))

    p = sub.add_parser(
        'envelope',
        help='uplift envelope: the smallest load and wind from each direction that lift an anchor',
        description='For each direction, the smallest horizontal load and the smallest wind '
        'speed (seed paper\'s formula) at which the first anchor lifts, and which line; a '
        'table, --json, and a polar chart with --plot.',
    )
    _add_common(p)
    p.add_argument(
        '--depth',
        required=True,
        metavar='D',
        help='tide depth at the hooks [m]; several, comma-separated, for one curve each',
    )
    p.add_argument(
        '--step', type=float, default=15.0, metavar='DEG', help='direction step (default: 15)'
    )
    p.add_argument('--plot', metavar='FILE.png', help='write the polar chart')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.set_defaults(func=_guarded(cmd_envelope))
