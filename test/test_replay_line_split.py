"""Replay's lines in two processes (``--line-processes 2``): the same bytes as one process,
one process where two are not to be had, and no process left behind on an error or Ctrl-C."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from replay_data import dock_config, generate, params_yaml, write_log

from catenary_monitor.cli.main import main
from catenary_monitor.io import mcap_scan
from catenary_monitor.replay import driver, line_split

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def log(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('split')
    config = dock_config(5)
    tensions, depth = generate(config, seconds=90.0, seed=5, storm_line=3)
    path = write_log(tmp / 'log.mcap', config, tensions, depth, chunk_size=2048)
    return dict(config=config, log=path, params=params_yaml(config, tmp / 'params.yaml'))


@pytest.fixture
def two_cpus(monkeypatch):
    """Two usable CPUs whatever the machine, and a count of the workers forked."""
    monkeypatch.setattr(line_split, 'usable_cpus', lambda: 2)
    made = []
    real = line_split.LineSplit.__init__

    def spy(self, *a, **k):
        real(self, *a, **k)
        made.append(self.pid)

    monkeypatch.setattr(line_split.LineSplit, '__init__', spy)
    return made


def _replay(log, tmp, capsys, processes, *extra):
    code = main(
        [
            'replay',
            str(log['log']),
            '--params-file',
            str(log['params']),
            '--json',
            '--quiet',
            '--window-messages',
            '97',
            '--line-processes',
            str(processes),
            *extra,
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    summary = json.loads(captured.out)
    for key in ('timing', 'outputs'):
        summary.pop(key)
    return summary


def _reaped(pid: int) -> None:
    """The worker ``pid`` was reaped (no child of that id is left, running or a zombie)."""
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)


@pytest.mark.parametrize('csv', [False, True])
def test_two_processes_give_one_process_bytes(log, tmp_path, capsys, monkeypatch, two_cpus, csv):
    monkeypatch.setattr(mcap_scan, '_BATCH_BYTES', 1)  # windows end anywhere
    extra = ['--csv', str(tmp_path / 'a.csv'), '--csv-columns', 'all'] if csv else []
    one = _replay(log, tmp_path, capsys, 1, *extra)
    assert not two_cpus
    a = (tmp_path / 'a.csv').read_bytes() if csv else b''
    extra = ['--csv', str(tmp_path / 'b.csv'), '--csv-columns', 'all'] if csv else []
    two = _replay(log, tmp_path, capsys, 2, *extra)
    assert len(two_cpus) == 1  # the lines went over two processes
    assert two['streaming']['windows'] > 20
    assert any(line['episodes'] for line in one['lines'].values())
    assert two == one
    if csv:
        assert (tmp_path / 'b.csv').read_bytes() == a
    _reaped(two_cpus[0])


def test_one_process_where_two_are_not_to_be_had(log, monkeypatch):
    config = log['config']
    monkeypatch.setattr(line_split, 'usable_cpus', lambda: 2)
    assert driver.split_lines(config, 2)
    assert not driver.split_lines(config, 1)
    assert not driver.split_lines(config, 2, snapshots='columns')  # --out
    assert not driver.split_lines(config, 2, jobs=2)  # decoding processes
    monkeypatch.setattr(line_split, 'usable_cpus', lambda: 1)
    assert not driver.split_lines(config, 2)
    monkeypatch.setattr(line_split, 'usable_cpus', lambda: 2)
    monkeypatch.delattr(os, 'fork')
    assert not driver.split_lines(config, 2)
    # the command's default: two where a CPU is left idle by the load, else one
    for load, cpus, want in ((0.3, 2, 2), (0.99, 2, 2), (1.5, 2, 1), (7.0, 2, 1), (0.0, 1, 1)):
        monkeypatch.setattr(os, 'getloadavg', lambda: (load, load, load))
        monkeypatch.setattr(line_split, 'usable_cpus', lambda: cpus)
        assert line_split.default_processes() == want, (load, cpus)


def test_a_failing_worker_is_reaped(log, tmp_path, monkeypatch, two_cpus):
    parent = os.getpid()
    real = line_split.advance_lines

    def fails_in_worker(*a, **k):
        if os.getpid() != parent:
            raise ValueError('boom in the worker')
        return real(*a, **k)

    monkeypatch.setattr(line_split, 'advance_lines', fails_in_worker)
    with pytest.raises(line_split.LineSplitError, match='boom in the worker'):
        driver.drive(
            [log['log']],
            log['config'],
            lambda _: driver._Collect(),
            window_messages=97,
            line_processes=2,
        )
    assert len(two_cpus) == 1
    _reaped(two_cpus[0])


def test_a_worker_killed_midway_its_lines_go_on_here(log, tmp_path, capsys, monkeypatch, two_cpus):
    monkeypatch.setattr(mcap_scan, '_BATCH_BYTES', 1)  # windows end anywhere: many of them
    one = _replay(log, tmp_path, capsys, 1)
    parent = os.getpid()
    real = line_split.advance_lines
    calls = []

    def kills_the_worker(*a, **k):
        if os.getpid() == parent:
            calls.append(1)
            if len(calls) == 4:  # while the worker has its lines of this window
                os.kill(two_cpus[-1], signal.SIGKILL)
        return real(*a, **k)

    monkeypatch.setattr(line_split, 'advance_lines', kills_the_worker)
    with pytest.warns(RuntimeWarning, match='line worker went away'):
        two = _replay(log, tmp_path, capsys, 2)
    assert two == one
    _reaped(two_cpus[-1])


def test_an_interrupt_here_kills_and_reaps_the_worker(log, monkeypatch, two_cpus):
    parent = os.getpid()
    real = line_split.advance_lines
    calls = []

    def interrupted(*a, **k):
        if os.getpid() == parent:
            calls.append(1)
            if len(calls) == 3:
                raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(line_split, 'advance_lines', interrupted)
    with pytest.raises(KeyboardInterrupt):
        driver.drive(
            [log['log']], log['config'], lambda _: driver._Collect(), window_messages=97,
            line_processes=2,
        )  # fmt: skip
    assert len(two_cpus) == 1
    _reaped(two_cpus[0])


_SLOW = textwrap.dedent(
    """
    import os, sys, time
    from catenary_monitor.replay import line_split
    from catenary_monitor.cli.main import main
    line_split.usable_cpus = lambda: 2
    real = line_split.advance_lines
    def slow(*a, **k):
        time.sleep(0.2)
        return real(*a, **k)
    line_split.advance_lines = slow
    sys.exit(main(sys.argv[1:]))
    """
)


def _worker_of(pid: int, timeout: float = 20.0) -> int:
    """The first child process of ``pid`` (waits for it)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for task in os.listdir(f'/proc/{pid}/task'):
            kids = Path(f'/proc/{pid}/task/{task}/children').read_text().split()
            if kids:
                return int(kids[0])
        time.sleep(0.02)
    raise AssertionError('no worker process appeared')


def _gone(pid: int, timeout: float = 10.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            state = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0]
        except OSError:
            return True
        if state == 'Z':  # exited, its parent (or init) about to reap it
            return True
        time.sleep(0.02)
    return False


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='reads /proc')
@pytest.mark.parametrize('how', ['ctrl-c', 'kill -9'])
def test_no_orphan_after_ctrl_c_or_kill(log, how):
    command = [sys.executable, '-c', _SLOW, 'replay', str(log['log']), '--params-file',
               str(log['params']), '--json', '--quiet', '--window-messages', '97',
               '--line-processes', '2']  # fmt: skip
    proc = subprocess.Popen(
        command, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )  # fmt: skip
    try:
        worker = _worker_of(proc.pid)
        time.sleep(0.5)  # mid-replay
        if how == 'ctrl-c':  # a terminal's Ctrl-C: the whole foreground group
            os.killpg(proc.pid, signal.SIGINT)
        else:
            os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=20)
        assert _gone(worker), f'the worker {worker} outlived the replay ({how})'
        if how == 'ctrl-c':
            assert b'Traceback' not in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stderr.close()
