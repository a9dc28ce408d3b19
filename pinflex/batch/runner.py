"""Run batch tasks on Dask ``distributed`` and store every row as it completes.

The client plans the keys, skips those already in the store, submits one task per beam (or
assignment case) with a bounded number in flight, and writes each returned row in its own
SQLite transaction as soon as the task completes (``distributed.as_completed``). Workers never
touch the store. Consequences:

* a killed client loses only the tasks in flight; everything it reported is in the store;
* a killed worker's task is rescheduled by Dask; a task that kills workers repeatedly comes back
  as ``KilledWorker`` and is stored as a failed row, so it is not retried forever;
* rerunning the same command submits only the missing keys (``--retry-failed`` also reruns the
  stored failures).

The engine is a ``LocalCluster`` on 127.0.0.1 with one single-threaded worker process per core
by default, or an existing scheduler given by address. Dask's nanny sets
``OMP_NUM_THREADS = OPENBLAS_NUM_THREADS = MKL_NUM_THREADS = 1`` in worker processes, so one
task uses one core and results do not depend on how many workers run.
"""

from __future__ import annotations

import importlib
import logging
import os
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pinflex.batch.store import Key, ResultStore
from pinflex.exceptions import BatchError, MissingDependency
from pinflex.progress import ProgressBar


@dataclass(frozen=True)
class Task:
    """One unit of work: a function, its arguments and the keys its rows fill.

    Attributes:
        name: Readable task name (used in the Dask key).
        keys: Store keys the task's rows fill.
        func: Importable function run on a worker; returns a list of row dictionaries.
        args: Positional arguments (plain, picklable data).
        kind: ``"prbdm"`` or ``"assign"``.
        params: Row parameters to record if the task dies with its worker.
    """

    name: str
    keys: tuple[Key, ...]
    func: Callable
    args: tuple
    kind: str
    params: dict = field(default_factory=dict)


@dataclass
class BatchSummary:
    """Outcome of one batch run.

    Attributes:
        planned: Keys in the study.
        skipped: Keys already finished in the store before this run.
        tasks: Tasks submitted by this run.
        written: Rows written by this run.
        ok: Rows written with status ``ok``.
        failed: Rows written with status ``failed``.
        wall_s: Wall time from the first submission to the last row [s].
        workers: Worker processes (threads) that served the run.
        stage_s: Mean compute time per task of each timed stage [s].
        interrupted: True if the run stopped early (Ctrl-C).
    """

    planned: int = 0
    skipped: int = 0
    tasks: int = 0
    written: int = 0
    ok: int = 0
    failed: int = 0
    wall_s: float = 0.0
    workers: int = 0
    stage_s: dict[str, float] = field(default_factory=dict)
    interrupted: bool = False

    @property
    def rate_per_s(self) -> float:
        """Tasks completed per second of wall time [1/s]."""
        return self.tasks / self.wall_s if self.wall_s > 0 else float("nan")

    def text(self, unit: str = "task") -> str:
        """Multi-line human summary."""
        lines = [f"{self.planned} keys planned, {self.skipped} already in the store, "
                 f"{self.tasks} {unit}s run on {self.workers} worker(s)"
                 + (" (interrupted)" if self.interrupted else "")]
        if self.tasks:
            lines.append(f"{self.written} rows written: {self.ok} ok, {self.failed} failed; "
                         f"{self.wall_s:.1f} s wall, {self.rate_per_s:.3g} {unit}s/s")
        if self.stage_s:
            lines.append("mean compute per " + unit + ": " + ", ".join(
                f"{k.removesuffix('_s')} {v:.3g} s" for k, v in self.stage_s.items()))
        return "\n".join(lines)


def connect(scheduler: str | None = None, workers: int | None = None):
    """A Dask client: to ``scheduler`` if given, else to a new local cluster.

    Args:
        scheduler: Address of a running scheduler (e.g. ``tcp://10.0.0.5:8786``).
        workers: Worker processes of the local cluster (default: one per core); each has one
            thread.

    Returns:
        ``(client, cluster)``; ``cluster`` is None for an external scheduler.

    Raises:
        MissingDependency: If ``distributed`` is not installed.
        BatchError: If the scheduler does not answer, or both arguments are given.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise MissingDependency("dask[distributed]", "pinflex batch") from exc
    if scheduler:
        if workers is not None:
            raise BatchError("--workers sizes the local cluster; with --scheduler, start as "
                             "many `dask worker` processes as you want instead")
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise BatchError(f"no Dask scheduler answers at {scheduler} ({exc}); start one "
                             "with `dask scheduler` and pass the address it prints") from exc
    cores = os.cpu_count() or 1
    n = int(workers) if workers is not None else cores
    top = max(8, 4 * cores)  # each worker is a process; more only compete for the cores
    if not 1 <= n <= top:
        raise BatchError(f"--workers {n} must be between 1 and {top} (4 per core on this "
                         f"machine's {cores}); for more, start a Dask cluster and pass "
                         "--scheduler")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address="127.0.0.1:0",
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _import_modules(modules: tuple[str, ...]) -> None:
    """Import modules on a worker (run through ``Client.run``)."""
    for name in modules:
        importlib.import_module(name)


def _killed_rows(task: Task, exc: BaseException) -> list[dict]:
    text = f"worker: {type(exc).__name__}: {exc}"
    return [{"seed": s, "item": i, "config_hash": h, "kind": task.kind, "status": "failed",
             "error": text, "params": task.params, "truth": None, "result": None,
             "metrics": {}, "timings": {}, "worker": None} for s, i, h in task.keys]


def run_tasks(store: ResultStore, tasks: Sequence[Task], planned: int, skipped: int,
              scheduler: str | None = None, workers: int | None = None,
              retry_failed: bool = False, progress: bool = True, label: str = "batch",
              max_in_flight: int | None = None,
              preload: Sequence[str] = (),
              no_workers_timeout_s: float | None = -1.0) -> BatchSummary:
    """Run tasks on Dask and write their rows to the store as they complete.

    Args:
        store: The result store (written by this process only).
        tasks: Tasks to run (keys already finished must be filtered out by the caller).
        planned: Keys in the whole study (for the summary).
        skipped: Keys already finished (for the summary).
        scheduler: Address of an existing scheduler, or None for a local cluster.
        workers: Worker processes of the local cluster.
        retry_failed: Whether a new row may replace a stored failure.
        progress: Show the progress bar on stderr.
        label: Progress-bar label.
        max_in_flight: Most tasks submitted at once; default four per worker thread of the
            cluster (and at least 16), rechecked every 5 s as workers join or leave, which
            keeps workers busy and the client's memory bounded.
        preload: Modules every worker imports before the clock starts (so the first tasks'
            imports do not count in the rate).
        no_workers_timeout_s: How long the run may go on with tasks pending and no worker
            alive before it stops with a :class:`BatchError` (rows already written stay in
            the store; rerunning resumes). The default (-1) means 300 s for the local cluster,
            whose nanny restarts workers that die, and no limit for an external scheduler,
            to which workers may be added later; None means no limit.

    Returns:
        The run's summary.

    Raises:
        BatchError: If no worker is alive for ``no_workers_timeout_s`` while tasks are
            pending (for example when every worker keeps dying at start-up).
    """
    summary = BatchSummary(planned=planned, skipped=skipped)
    if no_workers_timeout_s is not None and no_workers_timeout_s < 0:
        no_workers_timeout_s = None if scheduler else 300.0
    if not tasks:
        return summary
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    client, cluster = connect(scheduler, workers)
    stage_sum: dict[str, float] = {}
    try:
        if preload:
            client.run(_import_modules, tuple(preload))
        token = uuid.uuid4().hex[:8]
        queue = list(tasks)[::-1]
        owner: dict = {}
        checked = -np.inf
        limit = 16

        def refresh_limit() -> None:
            """Follow the cluster's size (workers may join later), at most every 5 s."""
            nonlocal checked, limit
            if time.perf_counter() - checked < 5.0:
                return
            checked = time.perf_counter()
            threads = sum(client.nthreads().values())
            summary.workers = max(summary.workers, threads)
            limit = max_in_flight or max(16, 4 * threads)

        def top_up(pending) -> None:
            refresh_limit()
            while queue and len(owner) < limit:
                task = queue.pop()
                future = client.submit(task.func, *task.args, key=f"{task.name}-{token}",
                                       pure=False, retries=0)
                owner[future.key] = task
                pending.add(future)

        bar = ProgressBar(len(tasks), label, progress)
        start = time.perf_counter()
        pending = as_completed()
        top_up(pending)
        try:
            while not pending.is_empty():
                future = _next_completed(pending, client, no_workers_timeout_s)
                task = owner.pop(future.key)
                try:
                    rows = future.result()
                except KilledWorker as exc:
                    rows = _killed_rows(task, exc)
                finally:
                    future.release()
                written = store.write(rows, replace_failed=retry_failed)
                summary.tasks += 1
                summary.written += written
                n_failed = sum(r["status"] == "failed" for r in rows)
                summary.failed += n_failed
                summary.ok += len(rows) - n_failed
                _add_stages(stage_sum, rows)
                bar.update(1, int(n_failed > 0))
                top_up(pending)
        except KeyboardInterrupt:
            summary.interrupted = True
        finally:
            summary.wall_s = time.perf_counter() - start
            bar.close()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    if summary.tasks:
        summary.stage_s = {k: v / summary.tasks for k, v in stage_sum.items()}
    return summary


def _next_completed(pending, client, no_workers_timeout_s: float | None):
    """The next finished future; a BatchError if no worker lives for the timeout."""
    idle_since: float | None = None
    checked = time.perf_counter()
    while not pending.has_ready():
        time.sleep(0.02)
        now = time.perf_counter()
        if no_workers_timeout_s is None or now - checked < 1.0:
            continue
        checked = now
        if client.nthreads():
            idle_since = None
        elif idle_since is None:
            idle_since = now
        elif now - idle_since > no_workers_timeout_s:
            raise BatchError(
                f"no Dask worker has been alive for {no_workers_timeout_s:g} s while "
                f"{pending.count()} task(s) wait; the rows finished so far are in the store "
                "(rerun the same command to resume)")
    return pending.next()


def _add_stages(acc: dict[str, float], rows: list[dict]) -> None:
    """Accumulate per-task stage times: shared stages once, per-row stages summed."""
    if not rows:
        return
    if "shared_by" in rows[0]["timings"]:  # assignment cases sharing one expansion
        for name in ("task_s", "task_cpu_s", "shared_setup_s", "qp", "exact_verification"):
            values = [r["timings"][name] for r in rows if name in r["timings"]]
            if values:
                acc[name] = acc.get(name, 0.0) + float(sum(values))
        return
    for name in ("beam_s", "truth_s", "truth_cpu_s", "task_s", "task_cpu_s"):
        if name in rows[0]["timings"]:
            acc[name] = acc.get(name, 0.0) + float(rows[0]["timings"][name])
    for name in ("fit_s", "fit_cpu_s", "total"):
        values = [r["timings"][name] for r in rows if name in r["timings"]]
        if values:
            acc[name] = acc.get(name, 0.0) + float(sum(values))


def run_prbdm(study, store_path: str | Path, scheduler: str | None = None,
              workers: int | None = None, retry_failed: bool = False,
              progress: bool = True) -> BatchSummary:
    """Run (or resume) a random-beam PRBDM study.

    Args:
        study: The :class:`~pinflex.batch.tasks.PrbdmStudy`.
        store_path: SQLite store file.
        scheduler: Address of an existing Dask scheduler; default a local cluster.
        workers: Worker processes of the local cluster (default one per core).
        retry_failed: Rerun keys stored as failed.
        progress: Show the progress bar on stderr.

    Returns:
        The run's summary.
    """
    from pinflex.batch.tasks import KIND, beam_seed, config_hash, run_prbdm_beam

    configs = [(config_hash(c), c) for c in study.configs()]
    shared = {"beam": study.beam_settings(), "truth": study.truth_settings()}
    with ResultStore(store_path) as store:
        for chash, config in configs:
            store.add_config(chash, KIND, config)
        done = store.finished_keys(include_failed=not retry_failed)
        tasks, skipped = [], 0
        for item in range(study.n_beams):
            todo = [(h, c) for h, c in configs if (study.seed, item, h) not in done]
            skipped += len(configs) - len(todo)
            if todo:
                tasks.append(Task(name=f"prbdm-{study.seed}-{item}",
                                  keys=tuple((study.seed, item, h) for h, _ in todo),
                                  func=run_prbdm_beam, args=(shared, study.seed, item, todo),
                                  kind=KIND, params={"beam_seed": beam_seed(study.seed, item)}))
        return run_tasks(store, tasks, study.n_beams * len(configs), skipped, scheduler,
                         workers, retry_failed, progress, label="beams",
                         preload=("pinflex.prbdm.mapping", "pinflex.prbdm.problem"))


def run_assign(config_path: str | Path, sweeps: list[tuple[str, list]],
               store_path: str | Path, scheduler: str | None = None,
               workers: int | None = None, retry_failed: bool = False,
               progress: bool = True) -> BatchSummary:
    """Run (or resume) a sweep of assignment studies.

    Args:
        config_path: TOML study file (:mod:`pinflex.assignment.study`).
        sweeps: Parsed ``--sweep`` options (:func:`~pinflex.batch.sweep.parse_sweeps`).
        store_path: SQLite store file.
        scheduler: Address of an existing Dask scheduler; default a local cluster.
        workers: Worker processes of the local cluster (default one per core).
        retry_failed: Rerun keys stored as failed.
        progress: Show the progress bar on stderr.

    Returns:
        The run's summary.
    """
    from pinflex.batch.sweep import KIND, expansion_key, plan_cases, run_assign_group

    cases = plan_cases(config_path, sweeps)
    with ResultStore(store_path) as store:
        done = store.finished_keys(include_failed=not retry_failed)
        groups: dict[str, list] = {}
        skipped, seen = 0, set()
        for index, (chash, config, cfg, overrides) in enumerate(cases):
            store.add_config(chash, KIND, config)
            key = (0, 0, chash)
            if key in done or key in seen:
                skipped += key in done
                continue
            seen.add(key)
            # cases that differ only in targets, budgets, floors, bands or baseline share one
            # Taylor expansion: one task per group
            groups.setdefault(expansion_key(cfg), []).append((cfg, overrides, chash, index))
        tasks = [
            Task(name=f"assign-{items[0][3]}", keys=tuple((0, 0, it[2]) for it in items),
                 func=run_assign_group, args=(items,), kind=KIND,
                 params={"cases": [it[3] for it in items]})
            for items in groups.values()
        ]
        return run_tasks(store, tasks, len(cases), skipped, scheduler, workers, retry_failed,
                         progress, label="expansion groups",
                         preload=("pinflex.assignment.study", "pinflex.assignment"))
