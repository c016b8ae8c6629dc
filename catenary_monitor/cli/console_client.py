"""``catenary-monitor ack`` and ``shelve``: an operator's action on the console from a program
(a hardware button's script, a SCADA), in the name of the operator whose token it holds.

``catenary-monitor ack LINE|all [--condition C] --console URL --token-file F``
``catenary-monitor shelve LINE [--condition C] --minutes M --console URL --token-file F``
(``--minutes 0`` unshelves).

Each POSTs the console's own action (``/api/ack``, ``/api/shelve``) with ``Authorization: Bearer
TOKEN`` and no ``Origin``: the console (started with ``--token-file``) takes it as a program's
request in that operator's name. ``ack --condition C`` first reads the alarm list
(``/api/frame``) and acknowledges only if the line's alarm stands for condition ``C``, so a
button wired for one condition never acknowledges another. The token file holds the
operator's token alone, or the operator's ``NAME:TOKEN`` line of the console's token file.

Prints one line: what the console accepted (exit 0), or why it or the monitor refused (exit 1:
401 no valid token, 403, 404 unknown line, 409 the monitor refused, 503 no monitor listening,
or the console unreachable). Exit 2: bad arguments or an unusable token file.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import ssl
import stat
import sys
import urllib.error
import urllib.request
from typing import Any, Optional

__all__ = ['register', 'read_token', 'ClientError']

#: How long one request may take (s): a shelving request waits up to 2 s for the monitor.
TIMEOUT = 10.0
_NAME_TOKEN = re.compile(r'([A-Za-z0-9._-]{1,64}):(\S+)')


class ClientError(Exception):
    """A refused or failed action: ``str()`` is one line (never the token); ``code`` the exit
    status."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


def read_token(path: str) -> str:
    """The token in ``path``: its first line that is not blank nor a ``#`` comment, either the
    token itself or ``NAME:TOKEN``. A file others may read is one warning on stderr."""
    try:
        with open(path, encoding='utf-8') as f:
            info = stat.S_IMODE(os.fstat(f.fileno()).st_mode)
            text = f.read(64 * 1024)
    except (OSError, UnicodeDecodeError) as err:
        raise ClientError(f'cannot read the token file {path}: {getattr(err, "strerror", err)}', 2)
    lines = [s.strip() for s in text.splitlines() if s.strip() and not s.strip().startswith('#')]
    if not lines or any(c.isspace() for c in lines[0]):
        raise ClientError(f'{path}: expected one line: TOKEN, or NAME:TOKEN', 2)
    match = _NAME_TOKEN.fullmatch(lines[0])
    if info & 0o077:
        print(f'catenary-monitor: warning: {path} may be read by other users than its owner '
              f'(chmod 600 {path})', file=sys.stderr)  # fmt: skip
    return match.group(2) if match else lines[0]


def _request(args: argparse.Namespace, path: str, body: Optional[dict[str, Any]]) -> Any:
    """GET (``body`` None) or POST ``path`` on the console; the JSON answer, or ClientError."""
    url = args.console.rstrip('/') + path
    headers = {'Authorization': f'Bearer {read_token(args.token_file)}'}
    data = None
    if body is not None:
        data = json.dumps(body).encode()
        headers['Content-Type'] = 'application/json'
    request = urllib.request.Request(url, data=data, headers=headers)
    context = None
    if url.startswith('https:'):
        context = ssl.create_default_context(cafile=args.ca_file)
    try:
        with urllib.request.urlopen(request, timeout=TIMEOUT, context=context) as reply:
            return json.loads(reply.read() or b'{}')
    except urllib.error.HTTPError as err:
        try:
            reason = json.loads(err.read()).get('error', err.reason)
        except (ValueError, AttributeError):
            reason = err.reason
        raise ClientError(f'refused ({err.code}): {reason}') from None
    except (urllib.error.URLError, OSError, ValueError) as err:
        reason = getattr(err, 'reason', err)
        raise ClientError(f'cannot reach the console at {args.console}: {reason}') from None


def _alarm_condition(args: argparse.Namespace) -> Optional[str]:
    """The condition the line's alarm stands for now (None: the line has no alarm listed)."""
    frame = _request(args, '/api/frame', None)
    for row in frame.get('alarms', []):
        if row.get('line') == args.line:
            return str(row.get('condition', ''))
    return None


def cmd_ack(args: argparse.Namespace) -> int:
    """Acknowledge a line's alarm (or all) on the console, as the token's operator."""
    try:
        if args.condition:
            if args.line == 'all':
                raise ClientError('--condition needs one LINE, not all', 2)
            found = _alarm_condition(args)
            if found != args.condition:
                now = 'has no alarm' if found is None else f"stands for '{found}'"
                raise ClientError(
                    f'not acknowledged: the alarm of {args.line} {now}, not '
                    f"'{args.condition}'"
                )
        answer = _request(args, '/api/ack', {'line': args.line})
    except ClientError as err:
        print(f'catenary-monitor ack: {err}', file=sys.stderr)
        return err.code
    print(f"acknowledged {args.line} as {answer.get('operator') or 'the console'}: "
          f"{answer.get('sent', '')}")  # fmt: skip
    return 0


def cmd_shelve(args: argparse.Namespace) -> int:
    """Shelve (``--minutes 0``: unshelve) a line's alarm or one condition of it."""
    body = {'line': args.line, 'condition': args.condition or 'all', 'seconds': args.minutes * 60}
    try:
        answer = _request(args, '/api/shelve', body)
    except ClientError as err:
        print(f'catenary-monitor shelve: {err}', file=sys.stderr)
        return err.code
    said = answer.get('answer') or 'sent; the monitor has not answered yet'
    print(f"shelving {args.line} as {answer.get('operator') or 'the console'}: {said}")
    return 0


def _minutes(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 <= value < float('inf'):
        raise argparse.ArgumentTypeError(f'expected minutes >= 0, got {text!r}')
    return value


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        '--console', required=True, metavar='URL', help="the console's URL, e.g. "
        'http://127.0.0.1:8080/ (it must run with --token-file)',
    )  # fmt: skip
    p.add_argument(
        '--token-file', required=True, metavar='FILE',
        help="the operator's token (TOKEN, or the NAME:TOKEN line of the console's file)",
    )  # fmt: skip
    p.add_argument('--ca-file', metavar='FILE', help="the console's certificate (https, PEM)")


def register(sub: Any) -> None:
    """Add ``ack`` and ``shelve`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'ack',
        help="acknowledge an alarm on the console, as an operator (a button's script)",
        description="Acknowledge LINE's alarm (or all) on the operator's console, in the name of "
        'the operator whose token the file holds.',
    )
    p.add_argument(
        'line', metavar='LINE', help='the line (or sensors, a component status: tide, ..., or all)'
    )
    p.add_argument(
        '--condition', metavar='C',
        help="only if the line's alarm stands for this condition (uplift, anchor_margin, ...)",
    )  # fmt: skip
    _common(p)
    p.set_defaults(func=cmd_ack)
    p = sub.add_parser(
        'shelve',
        help="shelve an alarm on the console for a while, as an operator",
        description="Shelve LINE's alarm, or one condition of it, on the operator's console "
        'for M minutes (0: unshelve); the monitor decides and answers (never the uplift ERROR).',
    )
    p.add_argument('line', metavar='LINE', help='the line (or sensors)')
    p.add_argument('--condition', metavar='C', help='one condition only (default: all)')
    p.add_argument(
        '--minutes', type=_minutes, required=True, metavar='M', help='how long (0: unshelve)'
    )
    _common(p)
    p.set_defaults(func=cmd_shelve)
