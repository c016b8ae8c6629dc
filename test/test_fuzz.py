"""The fuzz targets (``catenary_monitor_study.fuzz``) on a bounded number of cases each, the
same every run (Hypothesis derandomized): the MCAP reader and recovery, the CDR decoders, the
params file and the console's HTTP take every mutated input with their named errors only. The
long run is ``catenary-monitor fuzz --minutes N`` (docs/fuzzing.md); here also that the harness
does find a planted failure, and the command's exit status and figures.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip('hypothesis')

from catenary_monitor_study.fuzz import TARGETS, Finding, Target, fuzz_target  # noqa: E402

#: Cases per target in the suite (about a second or two each here).
CASES = {'mcap_read': 200, 'mcap_recover': 80, 'cdr': 400, 'params': 200, 'http': 120}


@pytest.mark.parametrize('name', sorted(CASES))
def test_target_takes_every_mutated_input(name: str, tmp_path: Path) -> None:
    outcome = fuzz_target(TARGETS[name], CASES[name], tmp_path / name, out=tmp_path / 'found')
    assert outcome.failures == [], outcome.failures
    assert outcome.cases == CASES[name]


def test_the_harness_finds_a_planted_failure(tmp_path: Path) -> None:
    """A reader that fails on a cut input, one that raises, one that hangs: each found, its
    input written, one entry per kind of failure."""

    def fragile(data: bytes, work: Path) -> None:
        if len(data) < 8:
            raise IndexError('read past the end')
        if data[:1] == b'\xff':
            raise Finding('a value of the wrong shape')

    seeds = lambda work: [b'\x00' * 16, b'\x01' * 16]  # noqa: E731
    target = Target('planted', seeds, fragile, (b'\xff',), 64)
    outcome = fuzz_target(target, 300, tmp_path / 'w', out=tmp_path / 'found')
    kinds = sorted(f['why'].split(' at ')[0].split(':')[0] for f in outcome.failures)
    assert kinds == ['IndexError', 'a value of the wrong shape'], outcome.failures
    for found in outcome.failures:
        assert Path(found['input']).exists()


def test_fuzz_command_reports_its_figures(tmp_path: Path, capsys: Any) -> None:
    """``catenary-monitor fuzz --minutes 0.1 --target cdr --target params --json``: the
    progress lines, then the cases and failures per target; exit 0."""
    import resource

    from catenary_monitor.cli.main import main

    limit = resource.getrlimit(resource.RLIMIT_AS)
    code = main(['fuzz', '--minutes', '0.1', '--target', 'cdr', '--target', 'params',
                 '--out', str(tmp_path / 'found'), '--seed', '3', '--json'])  # fmt: skip
    out = capsys.readouterr().out
    rows = json.loads(out[out.index('\n{') + 1 :])
    assert code == 0 and set(rows) == {'cdr', 'params'}, out
    assert all(r['cases'] > 0 and r['failures'] == [] for r in rows.values()), rows
    assert main(['fuzz', '--minutes', '0.01', '--target', 'nothing']) == 2
    # the memory limit is the run's own: this process starts browsers and nodes afterwards
    assert resource.getrlimit(resource.RLIMIT_AS) == limit


@pytest.mark.xfail(
    strict=True,
    reason='found by the fuzzer, in io/mcap_read.py (being split elsewhere): a chunk whose '
    'opcode byte is damaged is skipped as an unknown record, its messages lost without a '
    "skip, though the summary's chunk index and statistics name them",
)
def test_a_chunk_with_a_damaged_opcode_is_not_lost_silently(tmp_path: Path) -> None:
    """The node's log (zstd) with its first chunk's opcode 0x06 turned into 0xE9: the ``mcap``
    library (CRCs checked) reads every message through the summary's chunk index; the reader
    must read them too or name what it skipped."""
    import struct

    from catenary_monitor.io.mcap_read import ReadReport, iter_messages
    from catenary_monitor_study.fuzz import _mcap_library_messages, _mcap_seeds

    data = bytearray(_mcap_seeds(tmp_path)[0])
    at = 8
    while data[at] != 0x06:  # the first Chunk record
        at += 9 + struct.unpack_from('<Q', data, at + 1)[0]
    data[at] = 0xE9
    path = tmp_path / 'damaged.mcap'
    path.write_bytes(bytes(data))
    theirs = _mcap_library_messages(bytes(data))
    report = ReadReport()
    ours = {
        (m.topic, m.log_time_ns, m.sequence, m.data) for m in iter_messages(path, None, report)
    }
    assert theirs is not None and len(theirs) == 27
    assert theirs <= ours or not report.complete, (len(ours), report.skips)
