"""A replay window's lines recomputed in two processes: :class:`LineSplit`.

The window-wide decisions (sensors, tide, blind inputs, dock) are made once, in the replay's
process; a worker process forked before the log is read runs some of the lines
(:func:`catenary_monitor.core.twin.engine.advance_lines`) while this process runs the others,
on the same core: the core after the decisions, the window and the decisions go over a socket
(pickled, the arrays' bytes out of band), each worker line's outputs and its state's four
parts (``LineState.read``) come back and are written through the twin's door
(``line.take``). Each line's pass reads the core and writes only its line's state, so the
results are those of one process, byte for byte.

What comes back is what a summary and the alarm journal read: a line's results with the
values ``value_keys`` names (None: every one), its level series without inputs, its steps'
times. Only without snapshots (``advance`` runs the lines itself with them).

The worker ignores SIGINT (the replay's process decides), exits on its socket's end of file
(the replay's process closed it, or died), and is killed and reaped by :meth:`LineSplit.close`
on an error or an interrupt: no process outlives the replay. A worker that goes away (killed,
out of memory) is said once (a RuntimeWarning) and its lines run in the replay's process from
then on, the window it had included: the same results.
"""

from __future__ import annotations

import dataclasses
import os
import pickle
import signal
import socket
import struct
import traceback
import warnings
from typing import Any, Collection, Optional

import numpy as np

from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.state import (
    LineAlarmPart,
    LineInputPart,
    LineRulesPart,
    LineSolvePart,
)
from catenary_monitor.core.physics import fused_kernel
from catenary_monitor.core.twin.engine import LineContext, LineOutput, advance_lines
from catenary_monitor.core.twin.schedule import LineSteps
from catenary_monitor.core.twin.window import Window

__all__ = ['LineSplit', 'LineSplitError', 'default_processes', 'usable_cpus', 'worker_lines']

_PARTS = (LineInputPart, LineSolvePart, LineRulesPart, LineAlarmPart)
_HEAD = struct.Struct('<QQ')
#: A peer gone is an error (EPIPE), not the end of the process: the command line restores
#: SIGPIPE's default action (``... | head``).
_FLAGS = getattr(socket, 'MSG_NOSIGNAL', 0)


class LineSplitError(RuntimeError):
    """The worker process failed (its traceback)."""


def usable_cpus() -> int:
    """The CPUs this process may run on (``os.sched_getaffinity``; else ``os.cpu_count``)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def worker_lines(lines: int) -> int:
    """How many of ``lines`` the worker takes: 7 of 12 (this process also makes the
    window-wide decisions and hands the results on; its read-ahead thread runs beside the
    worker: docs/benchmarks.md)."""
    return (7 * lines + 6) // 12 if lines > 1 else 0


def default_processes() -> int:
    """Replay's line processes by default: 2 where two CPUs are usable and the machine's
    load leaves one idle (the 1-minute load average at most the usable CPUs less one), else 1:
    on two busy cores the worker's share of the CPU is taken from the others and the split
    costs more than it saves (docs/benchmarks.md)."""
    cpus = usable_cpus()
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):  # not on this system: do not guess the machine is idle
        return 1
    return 2 if cpus >= 2 and load <= cpus - 1 else 1


def _send(sock: socket.socket, obj: Any) -> None:
    buffers: list[pickle.PickleBuffer] = []
    head = pickle.dumps(obj, 5, buffer_callback=buffers.append)
    raws = [b.raw() for b in buffers]
    sizes = [r.nbytes for r in raws]
    sizes_bytes = struct.pack(f'<{len(sizes)}Q', *sizes)
    sock.sendall(_HEAD.pack(len(head), len(sizes)) + sizes_bytes, _FLAGS)
    sock.sendall(head, _FLAGS)
    for raw in raws:
        sock.sendall(raw, _FLAGS)


def _exactly(sock: socket.socket, n: int) -> bytearray:
    out = bytearray(n)
    view = memoryview(out)
    got = 0
    while got < n:
        k = sock.recv_into(view[got:], n - got)
        if not k:
            raise EOFError
        got += k
    return out


def _recv(sock: socket.socket) -> Any:
    size, count = _HEAD.unpack(_exactly(sock, _HEAD.size))
    sizes = struct.unpack(f'<{count}Q', _exactly(sock, 8 * count))
    head = _exactly(sock, size)
    return pickle.loads(head, buffers=[_exactly(sock, n) for n in sizes])


def _lean(out: LineOutput) -> LineOutput:
    """What the replay's process reads of a line's outputs without snapshots."""
    r, s, st, a, d = out
    empty = np.zeros(0, np.int64)
    steps = LineSteps(st.times, *([empty] * 7))  # the journal reads the steps' times only
    return r, s, steps, a, np.zeros(0)


def _only(window: Window, ks: Collection[int]) -> Window:
    """The window with the columns of lines ``ks`` only (a line's pass reads its own columns,
    the depth's and the ticks): the others empty, as if they had no sample."""
    keep = set(ks)
    none = (np.zeros(0, np.int64), np.zeros(0))

    def mine(columns: Optional[list[Any]]) -> Optional[list[Any]]:
        if columns is None:
            return None
        return [c if k in keep else None for k, c in enumerate(columns)]

    return dataclasses.replace(
        window,
        tensions=[c if k in keep else none for k, c in enumerate(window.tensions)],
        tension_stamps=mine(window.tension_stamps),
        channels=mine(window.channels),
        channel_values={k: v for k, v in window.channel_values.items() if k in keep},
    )


def _serve(sock: socket.socket) -> None:
    """The worker's loop: a window's lines per request, until end of file."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    fused_kernel.set_threads(1)
    while True:
        try:
            core, window, context, ks, value_keys = _recv(sock)
        except EOFError:
            return
        try:
            outs = [  # one line's whole results at a time
                _lean(advance_lines(core, window, context, [k], False, value_keys)[0])
                for k in ks
            ]
            parts = [[core.state.lines[k].read(p) for p in _PARTS] for k in ks]
            reply: Any = ('ok', outs, parts)
        except Exception:
            reply = ('error', traceback.format_exc())
        _send(sock, reply)


class LineSplit:
    """The lines of each window in two processes (a :data:`~.engine.LineRunner`): the last
    ``remote`` of ``lines`` in a worker forked now (before any thread of the replay starts),
    the others here. :meth:`close` ends the worker (``with`` closes it too)."""

    def __init__(
        self, lines: int, remote: int, value_keys: Optional[Collection[str]] = None
    ) -> None:
        self.local = list(range(lines - remote))
        self.remote = list(range(lines - remote, lines))
        self.value_keys = None if value_keys is None else frozenset(value_keys)
        mine, theirs = socket.socketpair()
        pid = os.fork()
        if pid == 0:  # the worker: never returns into the caller's code
            code = 0
            try:
                mine.close()
                _serve(theirs)
            except BaseException:
                code = 1
            finally:
                os._exit(code)
        theirs.close()
        self.sock: Optional[socket.socket] = mine
        self.pid: Optional[int] = pid

    def __call__(self, core: MonitorCore, window: Window, context: LineContext) -> list[Any]:
        if self.sock is None:  # the worker went away: every line here
            return self._here(core, window, context, self.local + self.remote)
        job = (core, _only(window, self.remote), context, self.remote, self.value_keys)
        try:
            _send(self.sock, job)
        except OSError as err:
            return self._alone(err, core, window, context, self.local + self.remote)
        local = self._here(core, window, context, self.local)
        try:
            reply = _recv(self.sock)
        except (EOFError, OSError) as err:  # its lines' states were not taken: redone here
            return local + self._alone(err, core, window, context, self.remote)
        if reply[0] != 'ok':
            raise LineSplitError(f'the line worker failed:\n{reply[1]}')
        _, outs, parts = reply
        for k, line_parts in zip(self.remote, parts):
            for part in line_parts:
                core.state.lines[k].take(part)
        return local + outs

    def _here(
        self, core: MonitorCore, window: Window, context: LineContext, ks: list[int]
    ) -> list[Any]:
        return advance_lines(core, window, context, ks, False, self.value_keys)

    def _alone(
        self,
        err: BaseException,
        core: MonitorCore,
        window: Window,
        context: LineContext,
        ks: list[int],
    ) -> list[Any]:
        """The worker went away (killed, out of memory): said once, reaped, and lines ``ks``
        of this window and every line from now on run here (the results stay the same)."""
        warnings.warn(
            f'the replay\'s line worker went away ({err!r}); its lines run in one process '
            'from now on',
            RuntimeWarning,
            stacklevel=2,
        )
        self.close(kill=True)
        return self._here(core, window, context, ks)

    def close(self, kill: bool = False) -> None:
        """End the worker: its socket closed (it exits at end of file), killed first when
        ``kill`` (an error or an interrupt here: it may be mid-window), then reaped."""
        if self.sock is not None:
            self.sock.close()
            self.sock = None
        if self.pid is not None:
            pid, self.pid = self.pid, None
            if kill:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            os.waitpid(pid, 0)

    def __enter__(self) -> 'LineSplit':
        return self

    def __exit__(self, kind: Any, *rest: Any) -> None:
        self.close(kill=kind is not None)
