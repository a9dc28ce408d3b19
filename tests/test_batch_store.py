"""Tests of pinflex/batch/store.py: the SQLite result store."""

from __future__ import annotations

import json
import math
import sqlite3
import subprocess
import sys
import textwrap

import pytest

from pinflex.batch.store import ResultStore, canonical_json
from pinflex.exceptions import StoreError


def _row(item: int, status: str = "ok", value: float = 0.5, chash: str = "c1") -> dict:
    return {"seed": 7, "item": item, "config_hash": chash, "kind": "prbdm", "status": status,
            "error": None if status == "ok" else "fit: MappingFailed: all starts failed",
            "params": {"x_m": [0.0, 0.3, 1.0]}, "truth": {"freq_hz": [1.5, 9.25]},
            "result": {"value": value}, "metrics": {"eigen_error": value},
            "timings": {"fit_s": 0.1}, "worker": "tcp://127.0.0.1:1"}


def test_rows_round_trip(tmp_path):
    """A written row reads back with the same fields and parsed JSON."""
    with ResultStore(tmp_path / "s.db") as store:
        assert store.write([_row(0), _row(1, "failed")]) == 2
        rows = list(store.rows())
    assert [r.key for r in rows] == [(7, 0, "c1"), (7, 1, "c1")]
    assert rows[0].truth == {"freq_hz": [1.5, 9.25]}
    assert rows[1].status == "failed" and rows[1].error.startswith("fit: MappingFailed")
    assert rows[0].finished_at.endswith("+00:00")


def test_rewriting_a_key_keeps_the_first_row(tmp_path):
    """Writing an existing key again is a no-op, so reruns are idempotent."""
    with ResultStore(tmp_path / "s.db") as store:
        store.write([_row(0, value=0.5)])
        before = store.raw_rows()
        assert store.write([_row(0, value=0.9)]) == 0
        assert store.raw_rows() == before
        assert store.count() == 1


def test_failed_rows_are_replaced_only_on_request(tmp_path):
    """A stored failure is replaced only with replace_failed; an ok row never is."""
    with ResultStore(tmp_path / "s.db") as store:
        store.write([_row(0, "failed"), _row(1, "ok", 0.5)])
        assert store.write([_row(0, "ok", 0.25)]) == 0
        assert store.finished_keys() == {(7, 0, "c1"), (7, 1, "c1")}
        assert store.finished_keys(include_failed=False) == {(7, 1, "c1")}
        assert store.write([_row(0, "ok", 0.25), _row(1, "failed")], replace_failed=True) == 1
        rows = {r.item: r for r in store.rows()}
    assert rows[0].status == "ok" and rows[0].metrics["eigen_error"] == 0.25
    assert rows[1].status == "ok" and rows[1].metrics["eigen_error"] == 0.5


def test_canonical_json_is_exact_and_finite():
    """Floats round-trip exactly, keys are sorted and non-finite numbers become null."""
    import numpy as np

    value = {"b": [0.1 + 0.2, float("nan")], "a": np.float64(1 / 3), "c": np.arange(2)}
    text = canonical_json(value)
    assert text == '{"a":0.3333333333333333,"b":[0.30000000000000004,null],"c":[0,1]}'
    assert json.loads(text)["b"][0] == 0.1 + 0.2
    assert math.isfinite(json.loads(text)["a"])


def test_invalid_rows_are_rejected(tmp_path):
    """A row with an unknown status or a missing field raises StoreError."""
    with ResultStore(tmp_path / "s.db") as store:
        with pytest.raises(StoreError, match="status"):
            store.write([_row(0, "done")])
        bad = _row(1)
        del bad["metrics"]
        with pytest.raises(StoreError, match="metrics"):
            store.write([bad])
        assert store.count() == 0


def test_foreign_files_are_refused(tmp_path):
    """A non-SQLite file or a store of another schema version raises StoreError."""
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"not a database at all" * 100)
    with pytest.raises(StoreError, match="not a usable SQLite store"):
        ResultStore(junk)
    other = tmp_path / "other.db"
    ResultStore(other).close()
    with sqlite3.connect(other) as db:
        db.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    with pytest.raises(StoreError, match="schema version 99"):
        ResultStore(other)


def test_a_process_killed_mid_write_leaves_no_partial_row(tmp_path):
    """A writer killed inside a transaction leaves the store with only committed rows."""
    path = tmp_path / "s.db"
    with ResultStore(path) as store:
        store.write([_row(0)])
    script = textwrap.dedent(f"""
        import os, signal
        from pinflex.batch.store import ResultStore
        store = ResultStore({str(path)!r})
        store._db.execute("BEGIN")
        values = store._values({_row(1)!r})
        store._db.execute("INSERT INTO results VALUES (" + ",".join("?" * len(values)) + ")",
                          values)
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=60)
    assert proc.returncode == -9
    with ResultStore(path) as store:
        assert [r.item for r in store.rows()] == [0]
