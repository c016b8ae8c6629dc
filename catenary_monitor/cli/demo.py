"""``catenary-monitor demo``: the paper's dock through a storm, simulator and monitor as processes.

Prints the episode's story (:meth:`catenary_monitor.sim.scenario.Scenario.story`: the storm's
load, the anchors it lifts and the tension it brings, how fast its time runs). Starts the dock
simulator (``python -m catenary_monitor.ros.simulator``; with ``moordyn``, its tensions from
MoorDyn and the lines given MoorDyn's chain stiffness), which begins its episode as the monitor
subscribes (the monitor never waits for its sensors), the monitor (``python -m
catenary_monitor.ros.node``) on config/floating_dock.yaml and the operator's console
(``catenary-monitor console``, its URL printed; :func:`start_console`); prints each alarm
transition the monitor reports as it happens (its headline); after the episode stops the
console and the monitor with SIGINT (the MCAP file gets its summary), reads the log back and
draws a PNG chart (matplotlib, Agg backend).
The demo itself imports no rclpy except to decode the logged outputs for the chart.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.alarms.texts import headline
from catenary_monitor.sim.scenario import default_config_path

__all__ = ['run_demo', 'start_console', 'DEMO_OVERRIDES']

#: Alarm timings for the compressed episode (the storm and a tide cycle in under a minute, the
#: tide 813 times fast): clear holds longer than the simulator's 4 s wave period, shorter than
#: the episode; a tide trend over 10 s (2.3 h of that tide) and a time-to-uplift warning at
#: 15 s (3.4 h); the anchor-margin warning at 2 m, so that the rising tide's time-to-uplift
#: warning is line 11's first; the wave window two wave periods (the default 30 s would hold
#: the storm's peak tension past its easing: uplift alarms the story no longer has).
DEMO_OVERRIDES = {
    'clear_hold': 6.0,
    'warn_clear_hold': 6.0,
    'margin_clear_hold': 6.0,
    'tide_trend_window': 10.0,
    'uplift_time_warn': 8.0,
    'uplift_time_deadband': 3.0,
    'anchor_margin_warn': 2.0,
    'wave_window': 8.0,
}

_ALARM = re.compile(r'\[(\d+\.\d+)\] \[[^\]]+\]: ALARM (\S+): (\S+) -> (\S+): (.*)$')
_LEVEL_COLOURS = {'OK': '', 'WARN': '\033[33m', 'ERROR': '\033[31;1m', 'STALE': '\033[35m'}


def child_env(domain_base: int = 1) -> dict[str, str]:
    """Child environment: this package importable, discovery on this machine, a private domain
    (``domain_base + pid % 100`` unless ROS_DOMAIN_ID is set; the demo and the latency
    benchmark use different bases so that both can run at once)."""
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[2])  # the directory holding the package
    env['PYTHONPATH'] = os.pathsep.join(p for p in (root, env.get('PYTHONPATH')) if p)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env.setdefault('ROS_DOMAIN_ID', str(domain_base + os.getpid() % 100))
    env['PYTHONUNBUFFERED'] = '1'
    env['RCUTILS_LOGGING_BUFFERED_STREAM'] = '0'
    return env


def _relay(
    proc: subprocess.Popen,
    origin: list[float],
    colour: bool,
    events: list,
    ready: threading.Event,
    transcript: list,
) -> None:
    """Print the monitor's alarm transitions as they arrive; keep everything it says.

    Times are the monitor's log stamps in s since ``origin[0]`` (wall time the simulator
    started, as on the chart). The lines and the tide start blind (STALE); their first
    STALE -> OK, when data arrives, is shown as one line for all of them.
    """
    assert proc.stdout is not None
    seen: set[str] = set()
    online: list[tuple[float, str]] = []

    def flush_online() -> None:
        if online:
            names = ', '.join(name for _, name in online)
            print(f'  t = {online[-1][0]:5.1f} s  receiving data (STALE -> OK): {names}')
            online.clear()

    for raw in proc.stdout:
        line = raw.rstrip('\n')
        transcript.append(line)
        if 'monitoring' in line:
            ready.set()
        m = _ALARM.search(line)
        if m:
            stamp, name, old, new, text = m.groups()
            t = float(stamp) - origin[0]
            events.append((t, name, old, new, text))
            first = name not in seen
            seen.add(name)
            if first and (old, new) == ('STALE', 'OK'):
                online.append((t, name))
                continue
            flush_online()
            on, off = (_LEVEL_COLOURS.get(new, ''), '\033[0m') if colour else ('', '')
            head = headline(text)  # the operator's headline; the log keeps the full text
            print(
                f'  t = {t:5.1f} s  {on}{name:8s} {old:>5s} -> {new:5s}{off}  {head}', flush=True
            )
        elif 'Traceback' in line or line.startswith('catenary_monitor:'):
            print(f'  monitor: {line}', file=sys.stderr, flush=True)
    flush_online()


def start_console(
    params: str, env: dict[str, str], port: int = 8080, timeout: float = 30.0
) -> tuple[Optional[subprocess.Popen], str]:
    """Start ``catenary-monitor console`` as its own process; (process, URL) once it listens,
    (None, why) if it did not. A busy ``port`` falls back to any free port."""
    why = ''
    for p in dict.fromkeys([port, 0]):
        proc = subprocess.Popen(
            [sys.executable, '-m', 'catenary_monitor.cli.main', 'console', '--params-file']
            + [params, '--port', str(p)],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=env,
        )
        found: list[str] = []
        out = proc.stdout
        assert out is not None
        reader = threading.Thread(target=lambda: found.append(out.readline()), daemon=True)
        reader.start()
        reader.join(timeout)
        line = found[0] if found else ''
        match = re.search(r'console: (http://\S+)', line)
        if match:
            threading.Thread(target=out.read, daemon=True).start()  # drain
            return proc, match.group(1)
        why = line.strip() or f'no URL within {timeout:g} s'
        if proc.poll() is None:
            proc.kill()
        proc.wait(5)
    return None, why


#: With MoorDyn (``--moordyn``): its chains' axial stiffness [N] (the paper chain's estimate,
#: config/floating_dock.yaml), given to every line so that the monitor's model is MoorDyn's
#: chain (an inextensible model of elastic chains makes the lee lines disagree with the others),
#: and the tension rate [Hz] (the elastic solve costs the node about five times the rigid one).
MOORDYN_EA = 6.63e8
MOORDYN_RATE = 10.0
#: The MoorDyn tensions of the episode, computed before the monitor starts (beside the params).
MOORDYN_TABLE = 'moordyn_tensions.npz'


def demo_params(params: str, out: Path, ea: Optional[float] = None) -> str:
    """``params`` with :data:`DEMO_OVERRIDES` (and ``ea`` [N] on every line where given),
    written to ``out``/demo_params.yaml: the one file the monitor, the console and the chart
    all read (the console's highlights use the same thresholds as the monitor's alarms)."""
    from catenary_monitor.core.config.parameters import (
        config_from_params,
        config_to_params,
        load_params_file,
        params_file_text,
    )

    flat = {**load_params_file(params), **DEMO_OVERRIDES}
    if ea is not None:
        flat.update({f'{name}.ea': ea for name in flat['lines']})
    config = config_from_params(flat)
    path = out / 'demo_params.yaml'
    path.write_text(params_file_text(config_to_params(config)))
    return str(path)


def demo_story(params: str, duration: float, moordyn: bool = False) -> list[str]:
    """The banner's sentences: the episode's own storm, the tension it brings and how fast
    its time runs (:meth:`catenary_monitor.sim.scenario.Scenario.story`)."""
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import Scenario

    scenario = Scenario(config_from_params(load_params_file(params)), duration)
    return scenario.story(moordyn)


def _start_monitor(params: str, log_dir: Path, env: dict[str, str]) -> subprocess.Popen:
    """The monitor node as its own process, logging into ``log_dir``, output piped."""
    return subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.ros.node',
            '--ros-args',
            '--params-file',
            params,
            '-p',
            f'log_dir:={log_dir}',
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )


def _start_simulator(
    params: str,
    duration: float,
    env: dict[str, str],
    origin: list[float],
    moordyn: bool = False,
    timeout: float = 180.0,
) -> subprocess.Popen:
    """The dock simulator (``moordyn``: its tensions from MoorDyn), started before the monitor
    and returned once it has computed its episode (or ``timeout`` s passed); it begins the
    episode as the monitor subscribes, so the monitor never waits for its sensors. ``origin[0]``
    becomes the episode's start (wall time, s)."""
    table = str(Path(params).parent / MOORDYN_TABLE)
    dynamics = ['--dynamics', 'moordyn', '--moordyn-table', table, '--rate', str(MOORDYN_RATE)]
    dynamics = dynamics if moordyn else []
    sim = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.ros.simulator',
            '--params-file',
            params,
            '--duration',
            str(duration),
            '--wait-for-subscribers',
            '120',
            *dynamics,
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )

    ready = threading.Event()

    def read() -> None:
        assert sim.stdout is not None
        for line in sim.stdout:
            if line.startswith('waiting for subscribers'):
                ready.set()
            elif line.startswith('episode start '):
                origin[0] = float(line.split()[2])
        ready.set()  # it ended (its stderr says why)

    threading.Thread(target=read, daemon=True).start()
    ready.wait(timeout)
    return sim


def _finish_simulator(sim: subprocess.Popen, duration: float) -> Optional[str]:
    """Wait for the simulator's episode to end; its stderr if it failed."""
    try:
        sim.wait(timeout=duration + 180.0)
    finally:
        if sim.poll() is None:
            sim.send_signal(signal.SIGINT)
            sim.wait(10)
    err = sim.stderr.read() if sim.stderr is not None else ''
    return err if sim.returncode != 0 else None


def _moordyn_table(params: str, duration: float, path: Path) -> float:
    """The episode's tensions from MoorDyn into ``path`` (the simulator publishes them);
    the seconds it took."""
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import MoorDynTensions, Scenario

    start = time.monotonic()
    scenario = Scenario(config_from_params(load_params_file(params)), duration=duration)
    MoorDynTensions.compute(scenario).save(str(path))
    return time.monotonic() - start


def _stop(proc: Optional[subprocess.Popen], wait: float) -> None:
    """SIGINT (a clean stop: the monitor closes its log), then kill after ``wait`` s."""
    if proc is None:
        return
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(wait)
    except subprocess.TimeoutExpired:
        proc.kill()


def _report(
    files: list[Path], out: Path, params: str, origin_ns: int, monitor_rc: Optional[int]
) -> int:
    """Draw the chart and print where the log and the chart are; the demo's exit status."""
    if not files:
        print('catenary_monitor demo: no MCAP log was written', file=sys.stderr)
        return 1
    chart: Optional[Path] = out / 'demo.png'  # None if it could not be drawn
    try:
        plot_episode(files, out / 'demo.png', params, origin_ns)
    except Exception as exc:  # noqa: BLE001 - the log is the product; the chart is a bonus
        print(f'catenary_monitor demo: could not draw the chart: {exc}', file=sys.stderr)
        chart = None
    for f in files:
        print(f'  MCAP log: {f}')
    if chart is not None:
        print(f'  chart:    {chart}')
    return 0 if monitor_rc == 0 else 1


def run_demo(
    out_dir: str = 'catenary_monitor_demo',
    duration: float = 55.0,
    params_file: Optional[str] = None,
    console_port: Optional[int] = 8080,
    moordyn: bool = False,
) -> int:
    """Run the demo; return 0 on success. Leaves the MCAP log and ``demo.png`` in ``out_dir``.
    ``moordyn``: the tensions from MoorDyn (exit 2 with one line where it is not installed)."""
    if moordyn:
        from catenary_monitor.sim.moordyn_dock import available

        if not available():
            print(
                'catenary_monitor demo: --moordyn needs MoorDyn '
                '(pip install "catenary_monitor[dynamics]")',
                file=sys.stderr,
            )
            return 2
    given = params_file or default_config_path()
    out = Path(out_dir).resolve()
    log_dir = out / 'log'
    log_dir.mkdir(parents=True, exist_ok=True)
    params = demo_params(given, out, MOORDYN_EA if moordyn else None)
    before = set(log_dir.glob('*.mcap'))
    env = child_env()
    print(f'catenary_monitor demo: the floating dock of Hu & Tang (2004), 12 chains, {given}')
    for line in demo_story(params, duration, moordyn):
        print(f'  {line}')
    print(f'  (ROS_DOMAIN_ID={env["ROS_DOMAIN_ID"]})')
    if moordyn:
        print(
            f'  the hook tensions from MoorDyn (12 chains with inertia, drag and seabed '
            f'contact; EA {MOORDYN_EA:g} N given to every line, {MOORDYN_RATE:g} Hz): '
            'computing the episode...',
            end='',
            flush=True,
        )
        spent = _moordyn_table(params, duration, out / MOORDYN_TABLE)
        print(f' {spent:.0f} s')
    t0 = time.time()
    origin = [t0]  # becomes the episode's start: the printed times and the chart's
    sim = _start_simulator(params, duration, env, origin, moordyn)
    monitor = _start_monitor(params, log_dir, env)
    events: list = []
    transcript: list = []
    ready = threading.Event()
    relay = threading.Thread(
        target=_relay,
        args=(monitor, origin, sys.stdout.isatty(), events, ready, transcript),
        daemon=True,
    )
    relay.start()
    console: Optional[subprocess.Popen] = None
    try:
        if not ready.wait(30.0) or monitor.poll() is not None:
            print(
                'catenary_monitor demo: the monitor did not start:\n' + '\n'.join(transcript),
                file=sys.stderr,
            )
            return 1
        print(
            '  monitor running; the dock simulator begins its episode as the monitor '
            'subscribes (alarm transitions follow, t in s since the episode began, as on the '
            'chart)\n'
        )
        if console_port is not None:
            console, url = start_console(params, env, console_port)
            if console is None:
                print(f'  the console did not start ({url}); the demo goes on without it')
            else:
                print(f'  console: {url}  (open it in a browser on this machine)')
        sim_err = _finish_simulator(sim, duration)
        if sim_err is not None:
            print(f'catenary_monitor demo: simulator failed:\n{sim_err}', file=sys.stderr)
            return 1
    except KeyboardInterrupt:
        print('\n  interrupted')
    finally:
        _stop(sim, 10)
        _stop(console, 10)
        _stop(monitor, 15)
        relay.join(5)
    files = sorted(set(log_dir.glob('*.mcap')) - before)
    print(
        f'\n  {len(events)} alarm transitions in {time.time() - t0:.0f} s; monitor exit status '
        f'{monitor.returncode}'
    )
    return _report(files, out, params, int(origin[0] * 1e9), monitor.returncode)


def _outputs(files: list[Path], topics: list[str]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Logged output arrays per topic: (log time ns, values (n, k))."""
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64MultiArray

    from catenary_monitor.io.mcap_read import iter_messages

    acc: dict[str, tuple[list, list]] = {t: ([], []) for t in topics}
    for m in iter_messages(files, topics):
        acc[m.topic][0].append(m.log_time_ns)
        acc[m.topic][1].append(np.asarray(deserialize_message(m.data, Float64MultiArray).data))
    return {
        t: (np.asarray(a, dtype=np.int64), np.vstack(b) if b else np.zeros((0, 0)))
        for t, (a, b) in acc.items()
    }


def uplift_warning_times(
    t: np.ndarray, data: np.ndarray, idx: dict[str, int], warn: float
) -> tuple[Optional[float], Optional[float]]:
    """(first time the line's time to uplift is below ``warn`` while not lifted, first time
    its anchor lifts) [s] from its outputs (None: never)."""
    ttu, up = data[:, idx['time_to_uplift']], data[:, idx['uplift_force']]
    with np.errstate(invalid='ignore'):
        w = np.flatnonzero((ttu > 0.0) & (ttu < warn) & ~(up > 0.0))
        lift = np.flatnonzero(up > 0.0)
    first_w = float(t[w[0]]) if w.size else None
    return first_w, (float(t[lift[0]]) if lift.size else None)


def _mark_uplift_warning(
    axes: Any, t: np.ndarray, data: np.ndarray, idx: dict[str, int], warn: float, name: str
) -> None:
    """Mark the time-to-uplift WARN and the uplift of line ``name`` on every panel."""
    first_w, lift = uplift_warning_times(t, data, idx, warn)
    for when, colour, text, side in (
        (first_w, 'tab:orange', f'{name} time-to-uplift WARN', 'right'),
        (lift, 'tab:red', f'{name} anchor lifts', 'left'),
    ):
        if when is None:
            continue
        for a in axes:
            a.axvline(when, color=colour, ls='-.', lw=1.0)
        axes[0].text(
            when,
            0.02,
            f' {text} \n t = {when:.1f} s ',
            color=colour,
            fontsize=8,
            ha=side,
            va='bottom',
            transform=axes[0].get_xaxis_transform(),
        )


class _Episode(NamedTuple):
    """What the chart draws, read from the log: times in s since the origin."""

    config: Any
    names: list[str]
    focus: list[str]
    colours: dict[str, str]
    cols: dict[str, tuple[np.ndarray, np.ndarray]]  # topic -> (s, values)
    outs: dict[str, tuple[np.ndarray, np.ndarray]]  # line -> (s, outputs (n, k))
    idx: dict[str, int]  # output field -> column


def _read_episode(files: list[Path], params: str, origin_ns: Optional[int]) -> _Episode:
    """The depth, the hook tensions and every line's outputs from the MCAP log."""
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.io.mcap_read import read_float64_topics
    from catenary_monitor.ros.node import NODE_NAME, OUTPUT_FIELDS

    config = config_from_params({**load_params_file(params), **DEMO_OVERRIDES})  # as the node
    names = [line.name for line in config.lines]
    topics = [config.depth_topic, *(line.tension_topic for line in config.lines)]
    cols, _ = read_float64_topics(files, topics)
    out_topics = {n: f'/{NODE_NAME}/{n}/outputs' for n in names}
    outs = _outputs(files, list(out_topics.values()))
    t_all = [c[0][:1] for c in cols.values() if c[0].size]
    t0 = min(int(t[0]) for t in t_all) if t_all else 0
    if origin_ns is not None:
        t0 = origin_ns

    def sec(ns: np.ndarray) -> np.ndarray:
        return (np.asarray(ns) - t0) * 1e-9

    focus: list[str] = [n for n in ('line_11', 'line_10', 'line_12', 'line_01') if n in names]
    focus = focus or names[:3]
    return _Episode(
        config,
        names,
        focus,
        dict(zip(focus, ('tab:red', 'tab:orange', 'tab:purple', 'tab:green'))),
        {topic: (sec(t), v) for topic, (t, v) in cols.items()},
        {n: (sec(outs[out_topics[n]][0]), outs[out_topics[n]][1]) for n in names},
        {k: i for i, k in enumerate(OUTPUT_FIELDS)},
    )


def _draw_tensions(ax: Any, ep: _Episode) -> None:
    """Every line's hook tension, the focus lines in colour."""
    for line in ep.config.lines:
        n = line.name
        t, v = ep.cols[line.tension_topic]
        ax.plot(
            t,
            v / 1e3,
            lw=1.2 if n in ep.focus else 0.5,
            color=ep.colours.get(n, 'grey'),
            alpha=1.0 if n in ep.focus else 0.5,
            label=n if n in ep.focus else None,
        )
    ax.plot([], [], color='grey', lw=0.5, label='other lines')
    ax.set_ylabel('hook tension [kN]')
    ax.legend(loc='upper left', fontsize=8)


def _draw_uplift(axes: Any, ep: _Episode) -> None:
    """The first focus line's uplift force and the focus lines' anchor margins (panel 3), its
    time-to-uplift WARN and uplift marked on every panel."""
    ax, idx, first = axes[2], ep.idx, ep.focus[0]
    t, data = ep.outs[first]
    if data.size:
        ax.plot(
            t, data[:, idx['uplift_force']] / 1e3, color='k', lw=1.5,
            label=f'{first} uplift force [kN]',
        )  # fmt: skip
        ax2 = ax.twinx()
        for n in ep.focus:
            tt, dd = ep.outs[n]
            if dd.size:
                ax2.plot(
                    tt, dd[:, idx['anchor_margin']], color=ep.colours[n], lw=0.8, ls='--',
                    label=f'{n} anchor margin [m]',
                )  # fmt: skip
        ax2.set_ylim(-20, 25)
        ax2.axhline(ep.config.alarm.anchor_margin_warn, color='tab:orange', ls='--', lw=0.8)
        ax2.set_ylabel('anchor margin [m]')
        ax2.legend(loc='upper right', fontsize=8)
    ax.set_ylabel('uplift force [kN]')
    ax.legend(loc='upper left', fontsize=8)
    if data.size:
        _mark_uplift_warning(axes, t, data, idx, ep.config.alarm.uplift_time_warn, first)


def _draw_levels(ax: Any, ep: _Episode) -> None:
    """Every line's alarm level as steps (offset a little per line so they do not overlap)."""
    for k, n in enumerate(ep.names):
        tt, dd = ep.outs[n]
        if dd.size:
            ax.step(
                tt,
                dd[:, ep.idx['level']] + 0.04 * k,
                where='post',
                lw=1.2 if n in ep.focus else 0.6,
                color=ep.colours.get(n, 'grey'),
                label=n if n in ep.focus else None,
            )
    ax.set_yticks([0, 1, 2, 3], ['OK', 'WARN', 'ERROR', 'STALE'])
    ax.set_ylabel('alarm level')
    ax.set_xlabel('time since the episode began [s]')
    ax.legend(loc='upper right', fontsize=8)


def plot_episode(
    files: list[Path], png: Path, params: str, origin_ns: Optional[int] = None
) -> Path:
    """Chart of the episode from the MCAP log: depth, hook tensions, line 11, alarm levels;
    line 11's first time-to-uplift WARN and its uplift marked on every panel. Time in s since
    ``origin_ns`` (log time, ns; None: the first logged sample)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    ep = _read_episode(files, params, origin_ns)
    fig, axes = plt.subplots(4, 1, figsize=(11, 11), sharex=True)
    t, v = ep.cols[ep.config.depth_topic]
    axes[0].plot(t, v, color='tab:blue')
    axes[0].set_ylabel('depth at hook [m]')
    axes[0].set_title('catenary_monitor demo: floating dock (Hu & Tang 2004), storm on line_11')
    _draw_tensions(axes[1], ep)
    _draw_uplift(axes, ep)
    _draw_levels(axes[3], ep)
    for a in axes:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png
