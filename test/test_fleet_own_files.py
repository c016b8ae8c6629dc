"""``catenary-monitor fleet`` and what is not its own: a folder in a symlink loop is one line for
that folder while the other docks are replayed; ``--out`` in a loop is one line; files a user
put in the results folder (beside the datasets, in a dock's partition, in ``_fleet/tmp``)
survive every run, while the fleet's own stale files and temporary folders go.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fleet_data import write_dock

pytest.importorskip('pyarrow')
pytest.importorskip('distributed')

from catenary_monitor.cli.main import main  # noqa: E402


def _fleet(capsys: Any, *args: str) -> tuple[int, str, str]:
    code = main(['fleet', *args, '--workers', '1', '--quiet'])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_symlink_loop_fails_its_folder_alone(tmp_path: Path, capsys: Any) -> None:
    dock = write_dock(tmp_path / 'in' / 'dock_a', seconds=20.0, files=2, seed=1)
    (tmp_path / 'in' / 'loop1').symlink_to('loop2')
    (tmp_path / 'in' / 'loop2').symlink_to('loop1')
    results = tmp_path / 'results'
    loop = str(tmp_path / 'in' / 'loop1')
    code, out, err = _fleet(capsys, str(dock), loop, '--out', str(results))
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert 'loop1: a symlink loop' in lines[0] and 'Traceback' not in out + err
    assert 'dock_a ' in out and any((results / 'messages' / 'dock=dock_a').rglob('*.parquet'))
    (tmp_path / 'out1').symlink_to('out2')
    (tmp_path / 'out2').symlink_to('out1')
    code, out, err = _fleet(capsys, str(dock), '--out', str(tmp_path / 'out1'))
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and f'--out {tmp_path / "out1"}: ' in lines[0], err
    assert 'a symlink loop' in lines[0] or 'symbolic links' in lines[0], err  # 3.11, 3.13


def test_the_results_folder_keeps_what_the_fleet_did_not_write(
    tmp_path: Path, capsys: Any
) -> None:
    dock = write_dock(tmp_path / 'in' / 'dock_a', seconds=20.0, files=2, seed=1)
    results = tmp_path / 'results'
    mine = {
        results / 'README.txt': 'what these results are',
        results / 'episodes' / 'dock=dock_a' / 'notes.txt': 'storm of the 23rd: see log book',
        results / 'episodes' / 'dock=dock_a' / 'date=2001-01-01' / 'mine.txt': 'kept',
        results / 'daily' / 'dock=dock_a' / 'checked.txt': 'checked by J.',
        results / '_fleet' / 'tmp' / 'keep.txt': 'a user file in the fleet\'s tmp',
        results / '_fleet' / 'tmp' / 'dock_a-000001-1a2b3c4d' / 'x.txt': 'an old-style name',
    }
    for path, text in mine.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    # the fleet's own: a stale partition of a date no longer in the log, a killed task's tmp
    stale = results / 'episodes' / 'dock=dock_a' / 'date=2001-01-02' / 'part-0.parquet'
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b'PAR1')
    leftover = results / '_fleet' / 'tmp' / 'fleet-tmp-dock_a-000000-deadbeef' / 'x.parquet'
    leftover.parent.mkdir(parents=True)
    leftover.write_bytes(b'PAR1')
    for _ in range(2):  # the second run is up to date; a third after a change
        code, out, err = _fleet(capsys, str(dock), '--out', str(results))
        assert code == 0, err
    for name in ('dock_002.mcap',):
        write_dock(tmp_path / 'more' / 'dock_a', seconds=40.0, files=3, seed=1)
        (dock / name).write_bytes((tmp_path / 'more' / 'dock_a' / name).read_bytes())
    code, out, err = _fleet(capsys, str(dock), '--out', str(results))
    assert code == 0, err
    for path, text in mine.items():
        assert path.read_text() == text, path
    assert not stale.exists() and not stale.parent.exists()
    assert not leftover.parent.exists()
    assert any((results / 'episodes' / 'dock=dock_a').glob('date=*/part-0.parquet'))
    assert any((results / 'daily' / 'dock=dock_a').glob('date=*/part-0.parquet'))
