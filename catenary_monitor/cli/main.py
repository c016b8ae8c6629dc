"""``catenary-monitor``: the command line.

``solve``, ``paper`` and ``bench`` live here; run, demo, replay and the other benchmarks come
from their own modules.

Exit status: 0 success, 2 invalid or physically impossible input (one line on stderr naming it),
1 unexpected failure.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import re
import signal
import sys
from typing import Any, Callable, Optional, Sequence

import numpy as np

from catenary_monitor.cli.table import format_table
from catenary_monitor.core.physics.result import INF_MARGINS
from catenary_monitor.core.physics.solve import STATUS_MESSAGES, SolveResult, Status, solve

#: Display unit, scale from SI and format for each key of the human-readable table.
DISPLAY = {
    'horizontal_tension': ('horizontal tension R', 'kN', 1e-3, '{:.4f}'),
    'top_tension': ('hook tension T', 'kN', 1e-3, '{:.4f}'),
    'min_anchor_distance': ('minimum anchor distance', 'm', 1.0, '{:.4f}'),
    'suspended_length': ('suspended length L', 'm', 1.0, '{:.4f}'),
    'top_angle_deg': ('top angle beta', 'deg', 1.0, '{:.5f}'),
    'anchor_angle_deg': ('anchor angle alpha', 'deg', 1.0, '{:.5f}'),
    'uplift_force': ('uplift force F', 'kN', 1e-3, '{:.4f}'),
    'anchor_margin': ('anchor margin', 'm', 1.0, '{:+.4f}'),
    'tide_margin': ('tide margin', 'm', 1.0, '{:+.4f}'),
    'load_margin': ('load margin', 'kN', 1e-3, '{:+.4f}'),
    'grounded_length': ('grounded length', 'm', 1.0, '{:.4f}'),
    'safety_factor': ('safety factor MBL/T', '-', 1.0, '{:.3f}'),
}


class UsageError(Exception):
    """Invalid input: reported as one line on stderr with exit status 2."""


#: One number in any float syntax (``-5``, ``-.5e3``, ``-1E+06``, ``-1_000.5``, ``-inf``).
_NUMBER = r'(?:(?:\d[\d_]*\.?[\d_]*|\.\d[\d_]*)(?:[eE][-+]?\d[\d_]*)?|inf(?:inity)?|nan)'
#: What argparse should read as a value, not an option: a negative number, or a comma-separated
#: list of numbers that starts with one (``--load -1e5,0,2e6``).
NEGATIVE_VALUE = re.compile(rf'^-{_NUMBER}(?:\s*,\s*[-+]?{_NUMBER})*$', re.IGNORECASE)


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr (exit 2), usage left to --help.

    Every sub-command's parser is one (``parser_class``), and each reads a negative number in
    any float syntax as an option's value (``--tension -1e6``; argparse itself takes only
    ``-5`` and ``-.5``, and ``-1e6`` for an unknown option).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # argparse's own test of "looks like a negative number" (Python 3.11: -5 and -.5 only)
        self._negative_number_matcher = NEGATIVE_VALUE

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f'{self.prog}: error: {message} (see --help)\n')


def result_table(result: SolveResult) -> str:
    """Human-readable table of a scalar result, display units (kN, m, deg)."""
    rows = []
    for key in result.keys:
        label, unit, scale, fmt = DISPLAY[key]
        rows.append((label, _shown(fmt, getattr(result, key) * scale), unit, key))
    return format_table(rows, ('quantity', 'value', 'unit', 'json key'))


def _shown(fmt: str, value: float) -> str:
    """``value`` in its column format, or in 7 significant digits where that would be longer
    than a column (a 1e300 N reading stays one readable cell)."""
    if value == math.inf:
        return 'beyond float64'
    if abs(value) >= 1e9:
        return f'{value:+.7g}' if fmt.startswith('{:+') else f'{value:.7g}'
    return fmt.format(value)


def _positive_or_any(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None


def _status_line(result: SolveResult, args: argparse.Namespace) -> str:
    code = Status(int(result.status))
    detail = ''
    if code == Status.TENSION:
        detail = f' (T = {args.tension:g} N, w*h = {args.weight * args.depth:g} N)'
    elif code == Status.CHAIN_TOO_SHORT:
        chord = math.hypot(args.anchor_distance, args.depth)
        detail = f' (Lm = {args.chain_length:g} m, sqrt(x^2+h^2) = {chord:g} m)'
    elif code == Status.CHAIN_SLACK:
        detail = (
            f' (Lm = {args.chain_length:g} m, x + h = {args.anchor_distance + args.depth:g} m)'
        )
    return f'invalid input: {STATUS_MESSAGES[code]}{detail}'


def cmd_solve(args: argparse.Namespace) -> int:
    """Solve one catenary problem and print a table or JSON."""
    if args.chain_length is not None and args.anchor_distance is None:
        raise UsageError(
            '--chain-length needs --anchor-distance (the chain runs from hook to anchor)'
        )
    result = solve(
        args.weight,
        args.depth,
        tension=args.tension,
        horizontal=args.horizontal,
        anchor_distance=args.anchor_distance,
        chain_length=args.chain_length,
        mbl=args.mbl,
    )
    if int(result.status) != Status.OK:
        raise UsageError(_status_line(result, args))
    values = result.to_dict()
    # a solved result is finite but for a margin beyond float64 (result.INF_MARGINS: +inf);
    # JSON has no infinity: such a margin is null there, named under 'unbounded'
    unbounded = [k for k in INF_MARGINS if values.get(k) == math.inf]
    bad = [k for k, v in values.items() if not math.isfinite(v) and k not in unbounded]
    if bad:  # never print a NaN (solve() marks such elements OUT_OF_RANGE)
        raise UsageError(
            f'{bad[0]} is not finite: the inputs are beyond the range the solver handles in '
            'float64'
        )
    if args.json:
        lifted = bool(result.uplift_force > 0)
        values.update(dict.fromkeys(unbounded))
        extra: dict[str, Any] = {'model': result.model, 'anchor_lifted': lifted}
        if unbounded:
            extra['unbounded'] = unbounded
        print(json.dumps({**values, **extra}, allow_nan=False))
    else:
        given = f'w = {args.weight:g} N/m, h = {args.depth:g} m'
        for name, unit in (
            ('tension', 'N'),
            ('horizontal', 'N'),
            ('chain_length', 'm'),
            ('anchor_distance', 'm'),
            ('mbl', 'N'),
        ):
            v = getattr(args, name)
            if v is not None:
                given += f', {name} = {v:g} {unit}'
        lifted = result.uplift_force > 0
        state = 'ANCHOR LIFTED' if lifted else 'anchor on the seabed (no uplift)'
        print(f'{given}\n{state}; model: {result.model}\n')
        print(result_table(result))
    return 0


def paper_table() -> str:
    """The seed paper's floating-dock worked examples (Hu & Tang 2004), solved exactly."""
    w, h = 1300.0, 20.85
    cases = [
        ('T2 pretension', dict(horizontal=372e3, anchor_distance=120.0)),
        ('T3 typhoon, line 11', dict(horizontal=1584.6e3, anchor_distance=121.06)),
        ('T4 measured T', dict(tension=1623.5e3)),
        ('T4 measured T, line 11', dict(tension=1623.5e3, anchor_distance=121.06)),
    ]
    rows = []
    for label, kw in cases:
        r = solve(w, h, **kw)
        rows.append(
            (
                label,
                f'{r.horizontal_tension / 1e3:.3f}',
                f'{r.top_tension / 1e3:.3f}',
                f'{r.min_anchor_distance:.4f}',
                f'{r.suspended_length:.4f}',
                f'{r.top_angle_deg:.5f}',
                f'{r.anchor_angle_deg:.5f}',
                f'{r.uplift_force / 1e3:.3f}',
                '' if np.isnan(r.anchor_margin) else f'{r.anchor_margin:+.3f}',
            )
        )
    header = (
        'case (w = 1.3 kN/m, h = 20.85 m)',
        'R kN',
        'T kN',
        'x_min m',
        'L m',
        'beta deg',
        'alpha deg',
        'F kN',
        'margin m',
    )
    return format_table(rows, header)


def cmd_paper(args: argparse.Namespace) -> int:
    """Print the seed paper's dock examples solved by the core."""
    print(
        'Floating dock of Hu & Tang (2004): 12 x U3 chain, 81 mm, '
        'w = 1300 N/m submerged (g = 10)\n'
    )
    print(paper_table())
    print(
        '\nErrata: table 4 prints x = 255.9719 m (transposed digits: 225.97 m); table 3 prints '
        'beta = 15.5595 deg (12.559 deg).'
    )
    return 0


def build_parser(command: Optional[str] = None) -> argparse.ArgumentParser:
    """The command line's parser; with ``command`` one of :data:`ALONE`, only that command's
    own module registered beside ``solve`` and ``paper`` (its parser is the same)."""
    parser = OneLineParser(
        prog='catenary-monitor', description='Anchor-chain catenary monitor for moored docks.'
    )
    sub = parser.add_subparsers(
        dest='command', required=True, metavar='COMMAND', parser_class=OneLineParser
    )

    p = sub.add_parser(
        'solve',
        help='solve one catenary problem (SI units)',
        description='Solve the chain catenary: minimum anchor distance, uplift, margins.',
    )
    p.add_argument(
        '--weight',
        type=_positive_or_any,
        required=True,
        metavar='W',
        help='submerged chain weight per metre [N/m]',
    )
    p.add_argument(
        '--depth',
        type=_positive_or_any,
        required=True,
        metavar='H',
        help='vertical distance anchor -> hook point [m]',
    )
    load = p.add_mutually_exclusive_group(required=True)
    load.add_argument(
        '--tension', type=_positive_or_any, metavar='T', help='measured hook tension [N]'
    )
    load.add_argument(
        '--horizontal', type=_positive_or_any, metavar='R', help='horizontal tension [N]'
    )
    load.add_argument(
        '--chain-length',
        type=_positive_or_any,
        metavar='LM',
        help='paid-out chain length [m] (needs --anchor-distance)',
    )
    p.add_argument(
        '--anchor-distance',
        type=_positive_or_any,
        metavar='X',
        help='installed horizontal distance hook -> anchor [m]',
    )
    p.add_argument('--mbl', type=_positive_or_any, metavar='M', help='minimum breaking load [N]')
    p.add_argument('--json', action='store_true', help='print one JSON object instead of a table')
    p.set_defaults(func=cmd_solve)

    p = sub.add_parser('paper', help="print the seed paper's floating-dock examples, solved")
    p.set_defaults(func=cmd_paper)

    if command in ALONE:
        importlib.import_module(ALONE[command]).register(sub)
        return parser
    for register in _extensions():
        register(sub)
    return parser


#: Commands whose module's registrar adds them alone: a command line naming one as its first
#: word builds only its parser, without every other command's imports and the entry points'
#: (0.2 s of CPU at each start, a tenth of a 3e6-message replay's CPU).
ALONE = {
    'replay': 'catenary_monitor.cli.replay',
    'fleet': 'catenary_monitor.cli.fleet',
    'whatif': 'catenary_monitor.cli.whatif',
    'alarms': 'catenary_monitor.cli.report_alarms',
}


#: Entry-point group through which the console and installed extensions (the benchmarks of
#: ``catenary_monitor_study``) add sub-commands; the command line never imports them itself.
COMMAND_GROUP = 'catenary_monitor.commands'


def _extensions() -> list[Callable[[argparse._SubParsersAction], None]]:
    """Sub-command registrars: the shell's own (imported lazily: no rclpy for ``solve``), then
    those installed under the :data:`COMMAND_GROUP` entry points."""
    from importlib.metadata import entry_points

    from catenary_monitor.cli import (
        console_client,
        dock,
        dock_setup,
        fleet,
        log,
        replay,
        report_alarms,
        run,
        whatif,
    )

    found: list[Callable[[argparse._SubParsersAction], None]] = [
        run.register,
        replay.register,
        fleet.register,
        report_alarms.register,
        dock.register,
        whatif.register,
        log.register,
        console_client.register,
        dock_setup.register,
    ]
    # the console first (as before the benchmarks), then the others by name
    for ep in sorted(
        entry_points(group=COMMAND_GROUP), key=lambda e: (e.name != 'console', e.name)
    ):
        try:
            found.append(ep.load())
        except ImportError:  # an extension whose dependencies are missing: leave it out
            continue
    return found


def long_running(args: argparse.Namespace) -> bool:
    """True for a command that serves until stopped (``run``, ``demo``, ``console``,
    ``replay --publish``): its parser sets ``long_running`` (True, or a test of the args)."""
    keep = getattr(args, 'long_running', False)
    return bool(keep(args) if callable(keep) else keep)


def main(argv: Optional[Sequence[str]] = None) -> int:
    if hasattr(signal, 'SIGPIPE'):  # `... | head`: end quietly, as Unix tools do (no traceback)
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    words = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(words[0] if words else None)
    args = parser.parse_args(words)
    if hasattr(signal, 'SIGPIPE') and long_running(args):
        # A server survives any client that goes away (a closed socket is an error, not death).
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    try:
        return int(args.func(args) or 0)
    except UsageError as exc:
        print(f'catenary-monitor: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == '__main__':
    sys.exit(main())
