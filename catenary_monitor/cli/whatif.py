"""``catenary-monitor whatif``: every line's margins, uplift, holding and time to uplift for one
scene, as the monitor core decides them
(:func:`catenary_monitor.core.monitor.whatif_scene.whatif`).

Which values a line takes: ``--tension NAME=N`` and ``--anchor-distance NAME=X`` where given;
otherwise the newest tension sample of that line in ``--log`` (the last one recorded) and its
installed ``NAME.anchor_distance`` from the params file; a line with neither hangs as installed
(its ``NAME.chain_length`` at its anchor distance and this depth, in still water), and a line
without a chain length either is an error naming it. The table's ``from`` column says which. The
tide's rate is ``--tide-rate`` (m/s) or, with ``--log``, the monitor's trend at the log's last
depth sample; without either the trend is unknown (``time_to_uplift`` NaN, shown as
``unknown``, as the core has it then; ``not coming`` is a tide that does not rise). Exit 2
with one line on bad input.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, Optional, Sequence

from catenary_monitor.cli.table import format_table

__all__ = ['register', 'cmd_whatif', 'scene_table']


class WhatIfError(Exception):
    """Bad input: one line on stderr, exit status 2."""


def _pairs(items: Optional[Sequence[str]], what: str) -> dict[str, float]:
    """``NAME=VALUE`` arguments as a mapping (WhatIfError naming a bad one)."""
    out: dict[str, float] = {}
    for item in items or ():
        name, sep, text = item.partition('=')
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not sep or not name or not math.isfinite(value):
            raise WhatIfError(f'--{what} {item!r}: expected NAME=NUMBER')
        out[name] = value
    return out


def _from_log(paths: Sequence[str], config: Any) -> tuple[dict[str, float], float]:
    """The newest tension per line (a load cell's from all its channels, as the monitor fuses
    them) and the tide's trend (m/s) at the last depth sample."""
    import numpy as np

    from catenary_monitor.core.rules import tide_trend
    from catenary_monitor.replay.driver import ReplayError, expand, read_inputs

    try:
        tensions, depth, _ = read_inputs(expand(list(paths)), config)
    except ReplayError as err:
        raise WhatIfError(f'--log: {err}') from None
    last = {name: float(v[-1]) for name, (_, v) in tensions.items() if len(v)}
    dd, dv = depth
    rates, _, _ = tide_trend.series(
        tide_trend.TrendState(), np.asarray(dd), np.asarray(dv), config.alarm.tide_trend_window
    )
    return last, float(rates[-1]) if len(rates) else math.nan


def _cell(value: float, scale: float = 1.0, digits: int = 1) -> str:
    return '-' if not math.isfinite(value) else f'{value * scale:.{digits}f}'


def _time(value: float) -> str:
    if math.isnan(value):
        return 'unknown'
    if math.isinf(value):
        return 'not coming'
    return 'lifted' if value <= 0 else f'{value / 60.0:.0f} min'


def scene_table(scene: Any) -> str:
    """The scene as a readable table (kN, m, minutes) and the message of every line not OK."""
    header = [
        'line',
        'level',
        'T kN',
        'from',
        'x m',
        'uplift kN',
        'upper kN',
        'anchor m',
        'tide m',
        'tide@L m',
        'drag kN',
        'implied x m',
        'to uplift',
    ]
    rows = []
    for ls in scene.lines:
        v = ls.values
        rows.append(
            [
                ls.line,
                ls.level,
                _cell(ls.tension, 1e-3),
                ls.source,
                _cell(ls.anchor_distance, 1.0, 2),
                _cell(v['uplift_force'], 1e-3),
                _cell(v['uplift_force_upper'], 1e-3),
                _cell(v['anchor_margin'], 1.0, 2),
                _cell(v['tide_margin'], 1.0, 2),
                _cell(v['tide_margin_at_length'], 1.0, 2),
                _cell(v['drag_margin'], 1e-3),
                _cell(v['implied_anchor_distance'], 1.0, 2),
                _time(v['time_to_uplift']),
            ]
        )
    rate = scene.tide_rate
    tide = 'tide trend unknown' if math.isnan(rate) else f'tide {rate * 3600:+.2f} m/h'
    head = f'what-if at depth {scene.depth:g} m, {tide}'
    notes = [f'{ls.line}: {ls.message}' for ls in scene.lines if ls.level != 'OK']
    return '\n'.join([head, '', format_table(rows, header), *([''] + notes if notes else [])])


def cmd_whatif(args: argparse.Namespace) -> int:
    """Run the scene; print the table or the JSON."""
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )
    from catenary_monitor.core.monitor.whatif_scene import (
        hanging_tensions,
        scene_dict,
        unhung_reason,
        whatif,
        with_distances,
    )

    try:
        config = config_from_params(load_params_file(args.params_file))
    except ConfigError as err:
        raise WhatIfError(f'{args.params_file}: {err}') from None
    try:
        depth = float(args.depth)
    except ValueError:
        depth = math.nan
    if not (math.isfinite(depth) and depth > 0):
        raise WhatIfError(f'--depth {args.depth!r}: must be a positive number of metres')
    tensions = _pairs(args.tension, 'tension')
    distances = _pairs(args.anchor_distance, 'anchor-distance')
    rate = math.nan if args.tide_rate is None else float(args.tide_rate)
    if args.log:
        logged, log_rate = _from_log(args.log, config)
        blind = [k for k, v in logged.items() if v != v and k not in tensions]
        if blind:
            raise WhatIfError(
                f'line {blind[0]}: its newest tension in --log is unknown (a load cell below '
                f'min_channels healthy channels): give --tension {blind[0]}=N'
            )
        tensions = {**{k: v for k, v in logged.items()}, **tensions}
        rate = log_rate if args.tide_rate is None else rate
    names = [line.name for line in config.lines]
    try:
        placed = with_distances(config, distances)
    except ValueError as err:
        raise WhatIfError(str(err)) from None
    hanging = hanging_tensions(placed, depth, [n for n in names if n not in tensions])
    missing = [n for n in names if n not in tensions and n not in hanging]
    if missing:
        where = ' or a sample in --log' if not args.log else ' (the log has no sample of it)'
        raise WhatIfError(
            f'line {missing[0]}: no tension given, and {unhung_reason(placed, depth, missing[0])}'
            f': give --tension {missing[0]}=N{where}'
        )
    try:
        scene = whatif(config, depth, tensions, distances, rate)
    except ValueError as err:
        raise WhatIfError(str(err)) from None
    given = set(_pairs(args.tension, 'tension'))
    scene = scene._replace(
        lines=tuple(
            ls._replace(source='log') if ls.source == 'given' and ls.line not in given else ls
            for ls in scene.lines
        )
    )
    if args.json:
        print(json.dumps(scene_dict(scene), indent=1, allow_nan=False))
    else:
        print(scene_table(scene))
    return 0


def _guarded(args: argparse.Namespace) -> int:
    try:
        return cmd_whatif(args)
    except WhatIfError as err:
        print(f'catenary-monitor whatif: {err}', file=sys.stderr)
        return 2


def register(sub: Any) -> None:
    """Add ``whatif`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'whatif',
        help='margins, uplift, holding and time to uplift of every line for one scene',
        description='Run the monitor core on one scene (a depth, the tensions and anchor '
        'distances given, the others from --log or the params file) and print every line\'s '
        'level, margins, uplift bound, drag margin, implied anchor distance and time to '
        'uplift.',
    )
    p.add_argument('--params-file', required=True, metavar='F', help='ROS 2 params YAML')
    p.add_argument('--depth', required=True, metavar='D', help='tide depth at the hooks [m]')
    p.add_argument(
        '--tension', action='append', metavar='NAME=N', help='hook tension of a line [N]'
    )
    p.add_argument(
        '--anchor-distance',
        action='append',
        metavar='NAME=X',
        help='anchor distance of a line [m] (default: its NAME.anchor_distance)',
    )
    p.add_argument(
        '--tide-rate',
        type=float,
        metavar='R',
        help='tide rising at R [m/s] (default: the trend of --log, else unknown)',
    )
    p.add_argument(
        '--log',
        action='append',
        metavar='PATH',
        help='MCAP log (file or directory): lines not given take their newest sample',
    )
    p.add_argument('--json', action='store_true', help='print one JSON object (SI units)')
    p.set_defaults(func=_guarded)
