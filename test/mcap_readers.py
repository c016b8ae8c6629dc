"""The independent readers every finished log must satisfy (issue 10).

* the ``mcap`` library with CRC validation: ``get_summary()`` and every message;
* ``rosbags``: ``AnyReader`` on the file, and on the folder as a rosbag2 bag;
* ``pymcap-cli doctor`` (a subprocess; missing is a failure, not a skip).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path


def mcap_messages(path: Path) -> list[tuple[str, int, bytes]]:
    """(topic, log time, data) of every message, read with CRC validation via the summary."""
    from mcap.reader import make_reader

    with open(path, 'rb') as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None, f'{path}: no summary'
        assert summary.chunk_indexes or not summary.statistics.message_count
        out = [(ch.topic, m.log_time, m.data) for _, ch, m in reader.iter_messages()]
    assert len(out) == summary.statistics.message_count, path
    return out


def rosbags_count(paths: list[Path]) -> int:
    """Messages read by rosbags' AnyReader from files or a bag folder (each deserialized)."""
    from rosbags.highlevel import AnyReader

    n = 0
    with AnyReader(paths) as reader:
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)
            n += 1
    return n


def pymcap_cli() -> str:
    """Path of the pymcap-cli script beside this Python (a test failure if not installed)."""
    found = Path(sys.executable).parent / 'pymcap-cli'
    path = str(found) if found.exists() else shutil.which('pymcap-cli')
    assert path, 'pymcap-cli is not installed (pip install -e .[test])'
    return path


def doctor_errors(path: Path) -> list[dict]:
    """Error and warning findings of ``pymcap-cli doctor`` on one file."""
    r = subprocess.run(
        [pymcap_cli(), 'doctor', '--format', 'jsonl', str(path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    lines = [json.loads(line) for line in r.stdout.splitlines() if line.startswith('{')]
    summary = [x for x in lines if x.get('type') == 'summary']
    assert summary, f'pymcap-cli doctor gave no summary for {path}: {r.stdout} {r.stderr}'
    return [
        x for x in lines if x.get('type') == 'finding' and x['severity'] in ('error', 'warning')
    ]


def check_file(path: Path) -> list[tuple[str, int, bytes]]:
    """Assert that all three readers open ``path``; return its messages (mcap library)."""
    messages = mcap_messages(path)
    assert rosbags_count([path]) == len(messages)
    assert doctor_errors(path) == [], path
    return messages


def check_folder(folder: Path) -> int:
    """Assert every ``*.mcap`` opens in all readers and the folder opens as a bag; return the
    number of messages."""
    total = sum(len(check_file(p)) for p in sorted(folder.glob('*.mcap')))
    assert (folder / 'metadata.yaml').exists()
    assert rosbags_count([folder]) == total
    return total
