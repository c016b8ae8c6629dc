"""Our MCAP files in an independent reader: Foxglove's ``@mcap/core`` (indexed and stream readers,
CRCs validated) with ``@foxglove/rosmsg2-serialization`` decoding every message, run by Node.js.

The node's logger (each compression) and replay's ``--out`` results are read; every message must
decode and the counts must equal the mcap library's. The npm packages are pinned by
``test/js/package-lock.json`` and installed once per run with ``npm ci``.
"""

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rclpy.serialization import serialize_message

from catenary_monitor.cli.main import main
from catenary_monitor.io.mcap_log import McapLogger

from replay_data import dock_config, generate, params_yaml, write_log

JS = Path(__file__).parent / 'js'
T0 = 1_700_000_000 * 10**9


@pytest.fixture(scope='module')
def js_reader(tmp_path_factory) -> Path:
    """The reader script with its pinned packages installed beside it."""
    for tool in ('node', 'npm'):
        if shutil.which(tool) is None:
            pytest.fail(f'{tool} is not installed (the README test command installs nodejs, npm)')
    where = tmp_path_factory.mktemp('js')
    for name in ('package.json', 'package-lock.json', 'read_mcap.mjs'):
        shutil.copy(JS / name, where / name)
    subprocess.run(
        ['npm', 'ci', '--no-audit', '--no-fund', '--loglevel=error'],
        cwd=where,
        check=True,
        capture_output=True,
        timeout=300,
    )
    return where / 'read_mcap.mjs'


def read_js(script: Path, paths: list[Path]) -> list[dict]:
    done = subprocess.run(
        ['node', str(script), *map(str, paths)],
        check=True,
        capture_output=True,
        text=True,
        timeout=300,
    )
    return [json.loads(line) for line in done.stdout.splitlines()]


def library_counts(path: Path) -> dict[str, int]:
    """Messages per topic as the mcap library reads them (CRCs validated)."""
    counts: dict[str, int] = {}
    with open(path, 'rb') as handle:
        for _, channel, _ in make_reader(handle, validate_crcs=True).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


def assert_read_alike(result: dict, path: Path) -> None:
    assert 'indexed_error' not in result and 'stream_error' not in result, result
    expected = library_counts(path)
    assert result['indexed']['counts'] == expected
    assert result['indexed']['statistics_messages'] == sum(expected.values())
    assert result['stream'] == {'messages': sum(expected.values()), 'footer': True, 'done': True}


@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_node_logger_files(js_reader, tmp_path, compression) -> None:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from std_msgs.msg import Float64, Float64MultiArray

    status = DiagnosticStatus(
        level=DiagnosticStatus.ERROR,
        name='catenary_monitor: line_11',
        message='anchor uplift',
        values=[KeyValue(key='uplift_force', value='193000.0')],
    )
    with McapLogger(tmp_path, fsync=False, compression=compression, chunk_size=4096) as log:
        log.register('/mooring/line_11/tension', 'std_msgs/msg/Float64', qos='sensor_data')
        log.register('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', qos='latched')
        log.register('/catenary_monitor/line_11', 'std_msgs/msg/Float64MultiArray')
        for i in range(2000):
            stamp = T0 + i * 50_000_000
            log.write(
                '/mooring/line_11/tension', serialize_message(Float64(data=372e3 + i)), stamp
            )
            if i % 20 == 0:
                diag = serialize_message(DiagnosticArray(status=[status]))
                log.write('/diagnostics', diag, stamp)
                out = Float64MultiArray(data=[float(i), 2.5, -1.0])
                log.write('/catenary_monitor/line_11', serialize_message(out), stamp)
    [path] = log.files
    [result] = read_js(js_reader, [path])
    assert_read_alike(result, path)
    indexed = result['indexed']
    assert indexed['chunks'] > 1
    assert indexed['first']['/mooring/line_11/tension'] == 372e3
    assert indexed['last']['/mooring/line_11/tension'] == 372e3 + 1999
    assert indexed['last']['/diagnostics'] == [['catenary_monitor: line_11', 2]]
    assert indexed['last']['/catenary_monitor/line_11'] == 3


def test_replay_results_file(js_reader, tmp_path, capsys) -> None:
    config = dock_config(3)
    tensions, depth = generate(config, seconds=60.0, seed=3)
    log = write_log(tmp_path / 'dock.mcap', config, tensions, depth)
    params = params_yaml(config, tmp_path / 'params.yaml')
    results = tmp_path / 'results.mcap'
    args = ['replay', str(log), '--params-file', str(params), '--out', str(results), '--quiet']
    code = main(args)
    capsys.readouterr()
    assert code in (0, 1)  # 1: the storm raised an alarm
    for result, path in zip(read_js(js_reader, [log, results]), [log, results]):
        assert_read_alike(result, path)
    decoded = read_js(js_reader, [results])[0]['indexed']
    assert '/diagnostics' in decoded['counts'] and len(decoded['counts']) > 3


@pytest.mark.parametrize('compression', ['zstd', 'lz4'])
def test_recovered_files(js_reader, tmp_path, compression) -> None:
    """A logger file cut inside its last chunk (as SIGKILL leaves it) fails the indexed reader;
    after ``recover_file`` both of Foxglove's readers decode every message."""
    from mcap_recover_helpers import cut_log

    from catenary_monitor.io.mcap_recover import recover_file

    path = cut_log(tmp_path, compression)
    [before] = read_js(js_reader, [path])
    assert 'indexed_error' in before
    assert recover_file(path).status == 'recovered'
    [result] = read_js(js_reader, [path])
    assert_read_alike(result, path)
