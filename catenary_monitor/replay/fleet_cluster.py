"""The fleet replay on Dask distributed: every dock's chain of pieces
(:mod:`.fleet_tasks`) submitted at once, the docks side by side, on a local cluster of one-core
workers or on an existing scheduler.

Dask retries a task whose worker died (and redoes a lost result a later task needs: the piece
finds its checkpoint and returns it); a dock whose log cannot be replayed in pieces is
replayed again as one task; a dock that fails is named in one line and the others go on.
"""

from __future__ import annotations

import logging
import sys
import time
import uuid
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

from catenary_monitor.replay.fleet_dataset import clear_tmp, dataset_columns, remove_parts
from catenary_monitor.replay.fleet_tasks import (
    Carry,
    DockPlan,
    FleetError,
    PieceRestart,
    dock_name,
    finish_dock,
    finished_summary,
    forget_from,
    plan_dock,
    resume_point,
    run_piece,
)

__all__ = [
    'FleetRun',
    'Progress',
    'chain_priorities',
    'local_cluster',
    'run_fleet',
    'start_method',
]


@dataclass
class Progress:
    """What the run has done so far (for a progress line)."""

    tasks_done: int = 0
    tasks_total: int = 0
    messages: int = 0
    elapsed: float = 0.0
    notes: list[str] = field(default_factory=list)  # lines to print once (a worker lost, ...)


@dataclass
class FleetRun:
    """The run's outcome: each finished dock's summary, each failed dock's one line."""

    docks: dict[str, dict[str, Any]] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)
    tasks_run: int = 0
    tasks_reused: int = 0  # pieces a previous run finished (resumed after them)
    docks_up_to_date: list[str] = field(default_factory=list)
    workers: int = 0
    startup_seconds: float = 0.0  # the cluster ready, the workers' imports done
    seconds: float = 0.0  # the replay after it
    worker_cpu_seconds: float = 0.0  # CPU time the workers spent in it
    messages: int = 0
    workers_lost: int = 0


def _messages(carry: Carry) -> tuple[int, str]:
    """A finished piece's input messages (a small result for the progress line), and the
    worker that ran it (run on it: its carry is there), now free."""
    from distributed import get_worker

    try:
        where = str(get_worker().address)
    except ValueError:  # not on a worker
        where = ''
    return int(carry.piece_messages), where


class _Dock:
    """One dock's futures in the run (``generation`` counts its fresh starts) and its chain's
    next piece to submit."""

    def __init__(self, plan: DockPlan) -> None:
        self.plan = plan
        self.generation = 0
        self.futures: list[Any] = []
        self.failed = False
        self.next = 0  # the next piece to submit
        self.before: Any = None  # what it starts from (the piece before's future, ...)
        self.left: list[int] = []  # per piece, its priority (chain_priorities)
        self.busy = ''  # the count key of its piece on the cluster ('' when none is)
        self.tag = ''
        self.freed = ''  # the worker its last piece ran on (free since)

    def ready(self) -> bool:
        """Whether its next piece can be submitted now."""
        return not (self.busy or self.failed) and self.next < len(self.plan.pieces)


def run_fleet(
    folders: Sequence[Path],
    out: Path,
    *,
    workers: Optional[int] = None,
    scheduler: Optional[str] = None,
    progress: Optional[Callable[[Progress], None]] = None,
    columns: Optional[Sequence[str]] = None,
) -> FleetRun:
    """Replay every dock folder into the datasets under ``out`` on Dask: a local cluster of
    ``workers`` one-core worker processes (default: the usable CPUs), or the cluster whose
    scheduler is at ``scheduler`` (its workers must see ``out`` and the folders at the same
    paths). ``columns``: the messages dataset's (with ``time`` and ``line``; default: every
    column). Raises ValueError for an unknown column."""
    from distributed import Client

    names = dataset_columns(columns)
    run = FleetRun()
    root = Path(out).resolve()
    root.mkdir(parents=True, exist_ok=True)
    docks = _plans(folders, run, names)
    t0 = time.monotonic()
    cluster = None
    if scheduler:
        client = Client(scheduler, timeout='30s')
    else:
        cluster = local_cluster(workers)
        client = Client(cluster)
    try:
        run.workers = len(workers_now(client))
        client.run(_warm)  # each worker imports the replay once, before the clock of the replay
        run.startup_seconds = time.monotonic() - t0
        cpu = client.run(time.process_time)
        _drive(client, docks, root, run, progress, time.monotonic())
        after = client.run(time.process_time)  # a restarted worker's clock starts again
        run.worker_cpu_seconds = sum(
            after[w] - cpu.get(w, 0.0) for w in after if after[w] >= cpu.get(w, 0.0)
        )
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    clear_tmp(root)  # what killed tasks left, and nothing else
    run.seconds = time.monotonic() - t0 - run.startup_seconds
    return run


#: Dask's periodic work in the local cluster, spaced out: its event-loop tick (20 ms), system
#: monitor (0.5 s), memory monitor (0.1 s), work stealing (0.1 s) and the workers' statistical
#: profiler (a stack sample every 10 ms) kept an idle cluster of 2 workers at 0.085 of a core
#: (its client 0.03, each worker 0.027); thus 0.011. A fleet's tasks are few and long.
QUIET = {
    'distributed.admin.tick.interval': '1s',
    'distributed.admin.system-monitor.interval': '10s',
    'distributed.worker.memory.monitor-interval': '1s',
    'distributed.worker.profile.enabled': False,
    'distributed.scheduler.work-stealing-interval': '1s',
}


def start_method() -> str:
    """How the local cluster starts its worker processes: ``fork`` on Linux (each worker a
    copy of this process, which has imported the replay already: the start, the workers'
    imports and the stop 0.5 s together, where with ``spawn``, Dask's default, they took
    0.8-1.4 s on a quiet machine and 7-13 s at a load of 12), else Dask's setting (macOS
    forks unsafely in a process with threads; Windows cannot)."""
    import dask

    if sys.platform.startswith('linux'):
        return 'fork'
    return str(dask.config.get('distributed.worker.multiprocessing-method'))


def local_cluster(workers: Optional[int] = None) -> Any:
    """A local cluster of ``workers`` one-core worker processes (default: the usable CPUs),
    started by :func:`start_method` (this module imported the replay's tasks: a forked worker
    has them)."""
    import dask
    from distributed import LocalCluster

    with warnings.catch_warnings(), dask.config.set(
        {**QUIET, 'distributed.worker.multiprocessing-method': start_method()}
    ):
        warnings.simplefilter('ignore', UserWarning)  # "port 8787 in use" of its HTTP server
        return LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        )


def _warm() -> None:
    """Import what the tasks need, and one core per worker (:func:`.fleet_tasks.one_core`)."""
    from catenary_monitor.replay import fleet_tasks

    fleet_tasks.one_core()


def _plans(folders: Sequence[Path], run: FleetRun, columns: tuple[str, ...]) -> list[_Dock]:
    docks: list[_Dock] = []
    seen: dict[str, str] = {}
    for folder in folders:
        try:
            name = dock_name(Path(folder))
        except FleetError as err:  # this folder alone: the other docks go on
            run.failed[Path(folder).name or str(folder)] = str(err)
            continue
        if name in seen:
            run.failed[f'{name} ({folder})'] = (
                f'{folder}: a dock named {name} is given twice ({seen[name]}); the dock is '
                'the folder\'s name'
            )
            continue
        seen[name] = str(folder)
        try:
            docks.append(_Dock(plan_dock(Path(folder), columns=columns)))
        except FleetError as err:
            run.failed[name] = str(err)
    return docks


#: The priority of the small tasks (a piece's message count for the progress line, a dock's
#: end): run as soon as they can, before any piece.
AT_ONCE = 1 << 62


def chain_priorities(plan: DockPlan) -> list[int]:
    """Each piece's priority on the scheduler: the bytes of the dock's log from that piece
    on (the chain's work still ahead of it, its own included). A free worker takes the piece
    with the most work behind it: the longest chain is never left for the end (the largest
    dock first, then the others as their chains grow as long as its rest)."""
    sizes = [sum(plan.identity[i][1] for i in piece) for piece in plan.pieces]
    left = [0] * len(sizes)
    total = 0
    for k in range(len(sizes) - 1, -1, -1):
        total += sizes[k]
        left[k] = total
    return left


def _start(client: Any, dock: _Dock, root: Path, token: str, run: FleetRun) -> list[Any]:
    """Make the dock's chain start where a previous run stopped (nothing submitted, unless
    every piece is done: then its end); returns the futures to watch."""
    plan = dock.plan
    start = resume_point(root, plan)
    run.tasks_reused += start
    remove_parts(root, plan.name, start)
    forget_from(root, plan, start)
    dock.next, dock.busy, dock.futures = start, '', []
    dock.before = ('checkpoint', start - 1) if start else None
    dock.left = chain_priorities(plan)
    dock.tag = f'{token}-{dock.generation}-{plan.name}'
    return _submit_next(client, dock, root) if start == len(plan.pieces) else []


def _submit_next(client: Any, dock: _Dock, root: Path, worker: str = '') -> list[Any]:
    """Submit the dock's next piece (and its end after the last); returns the futures to
    watch (the piece's message count, the end). ``worker``: a free worker to run it on (the
    scheduler would put it where the piece before it ran, busy with another, with the free
    one idle until its work stealing moved it: up to a second)."""
    plan, task, watch = dock.plan, dock.next, []
    if task < len(plan.pieces):
        where = {'workers': [worker], 'allow_other_workers': True} if worker else {}
        dock.before = client.submit(
            run_piece, plan, task, dock.before, str(root),
            key=f'fleet-piece-{dock.tag}-{task}', priority=dock.left[task], **where,
        )  # fmt: skip
        count = client.submit(
            _messages, dock.before, key=f'fleet-count-{dock.tag}-{task}', priority=AT_ONCE
        )
        dock.futures += [dock.before, count]
        dock.busy, dock.next = count.key, task + 1
        watch.append(count)
    if dock.next == len(plan.pieces):
        end = client.submit(
            finish_dock, plan, dock.before, str(root), key=f'fleet-dock-{dock.tag}',
            priority=AT_ONCE,
        )  # fmt: skip
        dock.futures.append(end)
        watch.append(end)
    return watch


def _submit(client: Any, dock: _Dock, root: Path, token: str, run: FleetRun) -> list[Any]:
    """Start the dock's chain again (:func:`_start`) and submit its first piece."""
    watch = _start(client, dock, root, token, run)
    return watch if watch else _submit_next(client, dock, root)


def _drive(
    client: Any,
    docks: list[_Dock],
    root: Path,
    run: FleetRun,
    progress: Optional[Callable[[Progress], None]],
    t0: float,
) -> None:
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]
    state = Progress()
    owner: dict[str, tuple[_Dock, int]] = {}
    pending = as_completed()
    chains: list[_Dock] = []
    for dock in docks:
        summary = finished_summary(root, dock.plan)
        if summary is not None:
            run.docks[dock.plan.name] = summary
            run.docks_up_to_date.append(dock.plan.name)
            continue
        chains.append(dock)
        for future in _start(client, dock, root, token, run):
            owner[future.key] = (dock, dock.generation)
            pending.add(future)
        state.tasks_total += len(dock.plan.pieces)
    state.tasks_total -= run.tasks_reused
    addresses = workers_now(client)
    slots = _slots(client)
    free = [w for w, n in sorted(client.nthreads().items()) for _ in range(n)]

    def dispatch() -> None:  # each free thread: the ready piece with the most work behind it
        ready = [d for d in chains if d.ready()]
        busy = sum(1 for d in chains if d.busy and not d.failed)
        ready.sort(key=lambda d: -d.left[d.next])
        for dock in ready[: max(0, slots - busy)]:
            for future in _submit_next(client, dock, root, free.pop(0) if free else ''):
                owner[future.key] = (dock, dock.generation)
                pending.add(future)

    dispatch()
    next_look = 0.0
    while not pending.is_empty():
        for future in pending.next_batch(block=False) if pending.has_ready() else []:
            dock, generation = owner.pop(future.key)
            if generation != dock.generation or dock.failed:
                continue  # an abandoned start of this dock, or a failed dock's rest
            _collect(client, future, dock, root, token, run, state, owner, pending)
            if future.key == dock.busy and future.status == 'finished':
                dock.busy = ''  # its piece is done: the next may go, on the worker it freed
                if dock.freed in addresses:
                    free.append(dock.freed)
        dispatch()
        if time.monotonic() >= next_look or pending.is_empty():  # twice a second, and last
            next_look = time.monotonic() + 0.5
            addresses = _look_for_lost(client, addresses, run, state)
            slots = _slots(client)
        state.elapsed = time.monotonic() - t0
        if progress is not None:
            progress(state)
            state.notes = []
        _wait_for_one(pending)
    run.messages = state.messages


def _wait_for_one(pending: Any, timeout: float = 0.1) -> None:
    """Until a future is done (woken by it, as ``as_completed``'s own iterator is) or
    ``timeout`` s: a fixed sleep of 50 ms here cost a small run up to a second."""
    condition = getattr(pending, 'thread_condition', None)
    if condition is None:
        if not pending.has_ready():
            time.sleep(0.01)
        return
    with condition:
        if not pending.has_ready():
            condition.wait(timeout=timeout)


def _slots(client: Any) -> int:
    """The pieces the cluster runs at once: its worker threads (at least one)."""
    return max(1, sum(client.nthreads().values()))


def workers_now(client: Any) -> set[str]:
    """The addresses of the cluster's workers, asked of the scheduler now. Not
    ``client.scheduler_info()['workers']``: the client's periodic update of that cache asks
    for totals only (no workers), and when it lands between the call's own update and its
    return, every worker looks gone (a loaded machine reported two workers lost of a run that
    lost none)."""
    return set(client.nthreads())


def _look_for_lost(client: Any, addresses: set[str], run: FleetRun, state: Progress) -> set[str]:
    """The workers now; those gone since the last look are counted and named."""
    now = workers_now(client)
    lost = addresses - now
    if lost:
        run.workers_lost += len(lost)
        state.notes += [f'worker {a} lost: its tasks are done again' for a in sorted(lost)]
    return now


def _collect(
    client: Any,
    future: Any,
    dock: _Dock,
    root: Path,
    token: str,
    run: FleetRun,
    state: Progress,
    owner: dict[str, tuple[_Dock, int]],
    pending: Any,
) -> None:
    """Take one finished future of ``dock``: count it, or restart or fail the dock."""
    if future.status == 'finished':
        result = future.result()
        if isinstance(result, dict):  # the dock's end
            run.docks[dock.plan.name] = result
        else:
            messages, dock.freed = result
            state.tasks_done += 1
            run.tasks_run += 1
            state.messages += int(messages)
        return
    if future.status in ('pending', 'lost'):  # done, then its result lost with its worker:
        owner[future.key] = (dock, dock.generation)  # Dask computes it again; wait for that
        pending.add(future)
        return
    error = future.exception() if future.status == 'error' else None
    client.cancel(dock.futures)
    if isinstance(error, PieceRestart) and len(dock.plan.pieces) > 1:
        state.notes.append(f'{dock.plan.name}: {error}; replaying it as one task')
        state.tasks_total -= len(dock.plan.pieces) - 1
        dock.plan = plan_dock(Path(dock.plan.folder), serial=True, columns=dock.plan.columns)
        dock.generation += 1
        for fut in _submit(client, dock, root, token, run):
            owner[fut.key] = (dock, dock.generation)
            pending.add(fut)
        return
    dock.failed = True
    if error is None:
        text = f'task {future.key} {future.status} (not by this run)'
    elif isinstance(error, (FleetError, PieceRestart)):
        text = str(error)
    else:
        text = f'{type(error).__name__}: {error}'
    run.failed[dock.plan.name] = text.splitlines()[0] if text else type(error).__name__
