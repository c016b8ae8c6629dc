"""``catenary-monitor log recover PATH``: finish MCAP logs left unfinished by a crash.

PATH is one file or a folder (every ``*.mcap`` in it; its rosbag2 ``metadata.yaml`` is
rewritten). Each unfinished file gets a summary, chunk and message indexes, statistics and CRCs
(:mod:`catenary_monitor.io.mcap_recover`); its original is kept as ``NAME.unfinished`` unless
``--discard-original``. Finished files are left alone ("already finished"), so running it
twice changes nothing. ``--out DIR`` writes the finished files to DIR instead (another disk when
this one is full) and leaves the originals as they are; without it, a file whose copy does not
fit on a full disk is finished in place ("finished in place": cut after its last whole chunk,
its summary appended: a summary's room is all it needs).

A file that a running logger is writing (it holds a lock on it) is left alone ("being
written").

Exit status: 0 every file is finished now, or being written by a running logger (damaged parts
that were skipped are listed);
2 PATH does not exist, a folder without ``*.mcap`` files, or no folder DIR; 3 at least one
file could not be finished (not MCAP, unreadable or unwritable: its line says why); 1
unexpected failure.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from catenary_monitor.cli.table import format_table

__all__ = ['register', 'cmd_recover', 'EXIT_NOT_FINISHED']

#: Exit status when at least one file could not be finished.
EXIT_NOT_FINISHED = 3

_STATUS_TEXT = {
    'recovered': 'recovered',
    'finished_in_place': 'finished in place',
    'already_finished': 'already finished',
    'in_use': 'being written',
    'not_mcap': 'NOT MCAP',
    'failed': 'FAILED',
}


def register(sub: Any) -> None:
    """Add the ``log`` command group (``log recover``) to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'log',
        help='work on MCAP log files (recover)',
        description='Work on the monitor\'s MCAP log files.',
    )
    group = p.add_subparsers(dest='log_command', required=True, metavar='LOG_COMMAND')
    r = group.add_parser(
        'recover',
        help='finish MCAP files left unfinished by a crash (summary, indexes, CRCs)',
        description='Turn unfinished MCAP files (writer killed: no summary, maybe a cut last '
        'chunk) into finished ones, keeping every readable message; finished files are left '
        'alone. A folder also gets its rosbag2 metadata.yaml. Exit 0: every file finished; '
        '2: no such path, or a folder without *.mcap files; 3: a file could not be finished '
        '(not MCAP, unreadable or unwritable).',
    )
    r.add_argument('path', metavar='PATH', help='an MCAP file or a folder of them')
    r.add_argument('--json', action='store_true', help='print one JSON object instead of a table')
    r.add_argument(
        '--discard-original',
        action='store_true',
        help='do not keep the unfinished original as NAME.unfinished',
    )
    r.add_argument(
        '--out',
        metavar='DIR',
        help='write the finished files to DIR (another disk, when this one is full) and leave '
        'the originals as they are; without it, a file whose copy does not fit is finished in '
        'place (its summary appended)',
    )
    r.set_defaults(func=cmd_recover)


def cmd_recover(args: argparse.Namespace) -> int:
    """Recover PATH; print a table (or JSON); exit status as in the module docstring."""
    from catenary_monitor.io.mcap_recover import RECOVERED, recover_path

    path = Path(args.path)
    if not path.exists():
        print(f'catenary-monitor: no such MCAP file or folder: {path}', file=sys.stderr)
        return 2
    if path.is_dir() and not any(path.glob('*.mcap')):
        print(f'catenary-monitor: no *.mcap file in {path}', file=sys.stderr)
        return 2
    if args.out is not None and not Path(args.out).is_dir():
        print(f'catenary-monitor: --out {args.out}: no such folder', file=sys.stderr)
        return 2
    results, metadata = recover_path(
        path, keep_original=not args.discard_original, out_dir=args.out
    )
    failed = [r for r in results if r.status in ('failed', 'not_mcap')]
    if args.json:
        print(
            json.dumps(
                {
                    'files': [r.to_dict() for r in results],
                    'metadata_yaml': str(metadata) if metadata else None,
                    'finished': not failed,
                }
            )
        )
    else:
        rows = []
        for r in results:
            note = r.error or '; '.join(r.damaged)
            rows.append(
                (
                    Path(r.path).name,
                    _STATUS_TEXT.get(r.status, r.status),
                    str(r.messages) if r.status in RECOVERED else '',
                    str(len(r.damaged)) if r.status in RECOVERED else '',
                    note,
                )
            )
        print(format_table(rows, ('file', 'status', 'messages', 'damaged parts', 'note')))
        if metadata is not None:
            print(f'\nrosbag2 bag: {metadata} written')
    for r in failed:
        print(f'catenary-monitor: {r.path}: not finished: {r.error}', file=sys.stderr)
    return EXIT_NOT_FINISHED if failed else 0
