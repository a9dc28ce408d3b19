"""Tests of pinflex/batch/runner.py and cli.py on real Dask clusters bound to 127.0.0.1.

Studies are tiny (2R models, p = 3 planforms, two multistarts, one load level) so that a beam
takes about a second; each test starts its own cluster.
"""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from pinflex.batch.runner import run_assign, run_prbdm  # noqa: E402
from pinflex.batch.store import ResultStore  # noqa: E402
from pinflex.batch.sweep import parse_sweeps  # noqa: E402
from pinflex.batch.tasks import PrbdmStudy, config_hash  # noqa: E402

STUDY_A = Path(__file__).resolve().parents[1] / "examples" / "benchmark_a.toml"
TINY_ARGS = ["--links", "2", "--sections", "3", "--truth-modes", "2", "--alphas", "1",
             "--starts", "2", "--no-progress"]
TINY = dict(links=(2,), n_starts=2, n_sections=3, truth_modes=2, alphas=(1.0,))
#: Columns that depend on when and where a row was computed, not on its key.
VOLATILE = ("timings", "worker", "finished_at")


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pinflex", "batch", *args]


def _content(path: Path) -> dict:
    """Stored rows by key, without the volatile columns."""
    with ResultStore(path) as store:
        return {r.key: {k: v for k, v in vars(r).items() if k not in VOLATILE}
                for r in store.rows()}


def _count(path: Path) -> int:
    try:
        with sqlite3.connect(path, timeout=5) as db:
            return int(db.execute("SELECT COUNT(*) FROM results").fetchone()[0])
    except sqlite3.Error:
        return 0  # not created yet


def _stop(proc: subprocess.Popen) -> None:
    """Kill a process group this test started, if still alive."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=30)


def _reference_rows(study: PrbdmStudy, item: int) -> list[dict]:
    """Rows of one beam computed outside Dask, with single-threaded BLAS as on Dask workers.

    Threaded BLAS sums in another order and changes the last bits.
    """
    configs = [(config_hash(c), c) for c in study.configs()]
    shared = {"beam": study.beam_settings(), "truth": study.truth_settings()}
    script = ("import json, sys\n"
              "from pinflex.batch.store import canonical_json\n"
              "from pinflex.batch.tasks import run_prbdm_beam\n"
              "args = json.loads(sys.stdin.read())\n"
              "print(canonical_json(run_prbdm_beam(*args)))\n")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-c", script], input=json.dumps(
        [shared, study.seed, item, configs]), capture_output=True, text=True, env=env,
        timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_local_run_equals_direct_tasks_and_resumes(tmp_path):
    """A local-cluster run stores the rows the task gives in-process; a rerun computes nothing."""
    study = PrbdmStudy(seed=4, n_beams=3, **dict(TINY, links=(1, 2), modes=(1, 2)))
    store = tmp_path / "s.db"
    first = run_prbdm(study, store, workers=2, progress=False)
    assert (first.planned, first.skipped, first.tasks, first.written) == (6, 0, 3, 6)
    assert first.ok == 6 and first.failed == 0
    assert first.stage_s["truth_s"] > 0 and first.stage_s["fit_s"] > 0
    content = _content(store)
    assert sorted(k[1] for k in content) == [0, 0, 1, 1, 2, 2]
    for row in _reference_rows(study, 1):
        stored = content[(4, 1, row["config_hash"])]
        for column in ("status", "params", "truth", "result", "metrics"):
            assert stored[column] == row[column], column
    with ResultStore(store) as s:
        raw = s.raw_rows()
    again = run_prbdm(study, store, workers=2, progress=False)
    assert (again.planned, again.skipped, again.tasks, again.written) == (6, 6, 0, 0)
    more = run_prbdm(PrbdmStudy(seed=4, n_beams=4, **dict(TINY, links=(1, 2), modes=(1, 2))),
                     store, workers=1, progress=False)
    assert (more.skipped, more.tasks, more.written) == (6, 1, 2)
    with ResultStore(store) as s:
        assert set(raw) <= set(s.raw_rows())


def test_failures_are_recorded_once_and_retried_on_request(tmp_path):
    """Failed beams are stored with their error; only --retry-failed runs them again."""
    study = PrbdmStudy(seed=2, n_beams=2, thickness_m=-1.0, **TINY)
    store = tmp_path / "s.db"
    first = run_prbdm(study, store, workers=1, progress=False)
    assert (first.tasks, first.failed, first.ok) == (2, 2, 0)
    with ResultStore(store) as s:
        errors = [r.error for r in s.rows()]
    assert all(e.startswith("beam: InvalidBeam: thickness_m = -1.0") for e in errors)
    assert run_prbdm(study, store, workers=1, progress=False).tasks == 0
    retried = run_prbdm(study, store, workers=1, retry_failed=True, progress=False)
    assert (retried.skipped, retried.tasks, retried.written, retried.failed) == (0, 2, 2, 2)


def test_assignment_sweep_runs_new_cases_only(tmp_path):
    """A sweep stores one row per case; adding a value runs only the new cases.

    Cases that differ only in targets and budgets share one expansion: one task.
    """
    store = tmp_path / "a.db"
    sweeps = parse_sweeps(["targets.0.freq_hz=185,190", "constraints.mass_budget_kg=0.3,-0.1"])
    first = run_assign(STUDY_A, sweeps, store, workers=2, progress=False)
    assert (first.planned, first.tasks, first.ok, first.failed) == (4, 1, 2, 2)
    with ResultStore(store) as s:
        rows = {json.dumps(r.params["overrides"], sort_keys=True): r for r in s.rows()}
    ok = rows[json.dumps({"constraints.mass_budget_kg": 0.3, "targets.0.freq_hz": 190},
                         sort_keys=True)]
    assert ok.metrics["error_before"] == pytest.approx(0.0831, abs=5e-4)
    assert ok.metrics["error_after"] < 0.02
    assert all(r.error.startswith("assign: AssignmentInfeasible") for r in rows.values()
               if r.status == "failed")
    sweeps = parse_sweeps(["targets.0.freq_hz=185,190,195",
                           "constraints.mass_budget_kg=0.3,-0.1"])
    second = run_assign(STUDY_A, sweeps, store, workers=2, progress=False)
    assert (second.planned, second.skipped, second.tasks, second.ok) == (6, 4, 1, 1)


def test_killed_client_loses_nothing_and_rerun_completes(tmp_path):
    """SIGKILL mid-run keeps every stored row; the rerun ends with exactly N unique rows."""
    n = 8
    store = tmp_path / "s.db"
    cmd = _cli("prbdm", "--beams", str(n), "--seed", "21", *TINY_ARGS, "--store", str(store),
               "--workers", "2")
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 240
        while _count(store) < 3:
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() < deadline, "no rows within 240 s"
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait(timeout=30) == -signal.SIGKILL
    finally:
        _stop(proc)
    with ResultStore(store) as s:
        before = s.raw_rows()
    assert 3 <= len(before) < n, "the client must be killed mid-run"
    rerun = subprocess.run([*cmd, "--json"], capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stderr
    summary = json.loads(rerun.stdout)
    assert summary["skipped"] == len(before)
    assert summary["tasks"] == n - len(before)
    with ResultStore(store) as s:
        after = s.raw_rows()
        assert s.count() == n
    assert len({(r[0], r[1], r[2]) for r in after}) == n
    assert sorted(r[1] for r in after) == list(range(n))
    assert set(before) <= set(after)  # byte-identical rows
    assert all(r[4] == "ok" for r in after)


def _wait_for_file(path: Path, proc: subprocess.Popen, timeout_s: float = 60) -> None:
    deadline = time.monotonic() + timeout_s
    while not path.exists():
        assert proc.poll() is None, "the scheduler exited"
        assert time.monotonic() < deadline, f"{path.name} not written"
        time.sleep(0.1)


def test_external_scheduler_gives_the_local_rows(tmp_path):
    """A scheduler and two worker processes on 127.0.0.1 store the same rows as a local run."""
    from distributed import Client

    n = 4
    args = ["prbdm", "--beams", str(n), "--seed", "5", *TINY_ARGS]
    local = tmp_path / "local.db"
    run = subprocess.run(_cli(*args, "--store", str(local), "--workers", "2"),
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr

    scheduler_file = tmp_path / "scheduler.json"
    logs = open(tmp_path / "dask.log", "w")
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1",
                               "--port", "0", "--no-dashboard", "--scheduler-file",
                               str(scheduler_file)], start_new_session=True, stdout=logs,
                              stderr=logs)]
    try:
        _wait_for_file(scheduler_file, procs[0])
        time.sleep(0.2)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for _ in range(2):
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "dask", "worker", address, "--nthreads", "1",
                 "--host", "127.0.0.1", "--no-dashboard"], start_new_session=True,
                stdout=logs, stderr=logs))
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=120)
            workers = set(client.scheduler_info()["workers"])
        remote = tmp_path / "remote.db"
        run = subprocess.run(_cli(*args, "--store", str(remote), "--scheduler", address),
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stderr
        assert "on 2 worker(s)" in run.stdout
    finally:
        for proc in reversed(procs):
            _stop(proc)
        logs.close()
    remote_rows, local_rows = _content(remote), _content(local)
    assert len(remote_rows) == n and all(r["status"] == "ok" for r in remote_rows.values())
    assert remote_rows == local_rows
    with ResultStore(remote) as s:
        assert {r.worker for r in s.rows()} <= workers


def test_a_task_that_kills_its_workers_is_recorded_once(tmp_path):
    """A task that keeps killing workers is stored as failed; the other beams still finish."""
    from pinflex.batch.runner import Task, run_tasks
    from pinflex.batch.tasks import run_prbdm_beam

    study = PrbdmStudy(seed=8, n_beams=2, **TINY)
    configs = [(config_hash(c), c) for c in study.configs()]
    shared = {"beam": study.beam_settings(), "truth": study.truth_settings()}
    killer = Task("killer", ((8, 0, configs[0][0]),), os._exit, (3,), "prbdm", {"beam_seed": 0})
    beam = Task("beam", ((8, 1, configs[0][0]),), run_prbdm_beam, (shared, 8, 1, configs),
                "prbdm")
    store = tmp_path / "s.db"
    with ResultStore(store) as s:
        summary = run_tasks(s, [killer, beam], planned=2, skipped=0, workers=2,
                            progress=False)
        rows = {r.item: r for r in s.rows()}
    assert (summary.tasks, summary.ok, summary.failed) == (2, 1, 1)
    assert rows[0].status == "failed" and rows[0].error.startswith("worker: KilledWorker")
    assert rows[1].status == "ok"


def test_a_run_with_no_live_worker_stops_with_a_named_error(tmp_path):
    """Pending tasks and no worker for the timeout: BatchError, not a silent hang."""
    from distributed import LocalCluster

    from pinflex.batch.runner import Task, run_tasks
    from pinflex.exceptions import BatchError

    task = Task("t", ((1, 0, "h"),), os.getpid, (), "prbdm")
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        with ResultStore(tmp_path / "s.db") as store:
            t0 = time.perf_counter()
            with pytest.raises(BatchError, match="no Dask worker has been alive for 2 s"):
                run_tasks(store, [task], planned=1, skipped=0,
                          scheduler=cluster.scheduler_address, progress=False,
                          no_workers_timeout_s=2.0)
            assert time.perf_counter() - t0 < 30.0
            assert list(store.rows()) == []


def test_progress_bar_reports_rate_and_eta():
    """The bar shows done/total, percent, a rate and an ETA that reaches zero at the end."""
    import io

    from pinflex.progress import ProgressBar

    stream = io.StringIO()
    bar = ProgressBar(4, "beams", stream=stream, log_interval_s=0.0)
    bar.start -= 8.0  # as if the run had started 8 s ago
    bar.update()
    first = stream.getvalue().splitlines()[-1]
    assert "1/4" in first and " 25%" in first and "/s ETA 00:2" in first  # about 24 s left
    for _ in range(3):
        bar.update(failed=1)
    last = stream.getvalue().splitlines()[-1]
    assert "4/4 100%" in last and "ETA 00:00" in last and "3 failed" in last
    lines = len(stream.getvalue().splitlines())
    bar.close()
    assert len(stream.getvalue().splitlines()) == lines  # the final line is drawn once


def test_bad_command_lines_fail_before_any_cluster_starts(tmp_path, capsys):
    """Inconsistent options exit with code 2 and a message naming the fix."""
    from pinflex.batch.runner import connect
    from pinflex.cli import main
    from pinflex.exceptions import BatchError

    store = str(tmp_path / "s.db")
    assert main(["batch", "prbdm", "--beams", "2", "--links", "4", "--modes", "5",
                 "--store", store]) == 2
    assert "the 4R model has 4 modes" in capsys.readouterr().err
    assert main(["batch", "assign", str(STUDY_A), "--sweep", "nope=1", "--store", store]) == 2
    assert "not sweepable" in capsys.readouterr().err
    with pytest.raises(BatchError, match="--workers sizes the local cluster"):
        connect("tcp://127.0.0.1:9", workers=2)
