"""SQLite store of batch results, one row per (seed, item, config_hash).

Why SQLite and not a Parquet dataset: a batch writes one small row at a time, as tasks finish,
and must survive a kill at any instant. SQLite gives exactly that with the standard library:
every row is written in its own transaction, so a row is either entirely in the file or not at
all (the write-ahead log rolls an interrupted transaction back on the next open), and the
``PRIMARY KEY (seed, item, config_hash)`` makes a rerun idempotent. Parquet files are immutable:
appending row by row means thousands of tiny files or rewriting a file, and a kill during a write
leaves a torn file that readers must learn to skip. The results are small (a few kB of JSON per
row; 50,000 beams fit in a few hundred MB), so columnar storage buys nothing here;
:meth:`ResultStore.rows` hands them to pandas or anything else in one query.

Only the client writes: workers return rows and the client stores each one as it completes.
There is no write contention, and no network file system sees concurrent SQLite writers.

Schema (``results``)::

    seed         INTEGER  study seed (0 for assignment sweeps)
    item         INTEGER  beam index (prbdm) or case index (assign)
    config_hash  TEXT     hash of the model configuration (see ``configs``)
    kind         TEXT     'prbdm' or 'assign'
    status       TEXT     'ok' or 'failed'
    error        TEXT     'ExceptionType: message' of a failed task, else NULL
    params       TEXT     JSON: beam parameters or case settings
    truth        TEXT     JSON: reference solution (beam frequencies, elastica tips), or NULL
    result       TEXT     JSON: fitted parameters or assignment answer, or NULL
    metrics      TEXT     JSON: headline errors, {name: fraction}
    timings      TEXT     JSON: compute time per stage [s]
    worker       TEXT     address of the worker that ran the task
    finished_at  TEXT     UTC time the client stored the row (ISO 8601)

``configs`` maps each ``config_hash`` to its configuration JSON, ``meta`` holds the schema
version.
"""

from __future__ import annotations

import json
import math
import sqlite3
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from pinflex.exceptions import StoreError

SCHEMA_VERSION = "1"
STATUSES = ("ok", "failed")
_JSON_FIELDS = ("params", "truth", "result", "metrics", "timings")
_COLUMNS = ("seed", "item", "config_hash", "kind", "status", "error", *_JSON_FIELDS,
            "worker", "finished_at")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS configs (
    config_hash TEXT PRIMARY KEY,
    kind        TEXT NOT NULL,
    config      TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS results (
    seed        INTEGER NOT NULL,
    item        INTEGER NOT NULL,
    config_hash TEXT    NOT NULL,
    kind        TEXT    NOT NULL,
    status      TEXT    NOT NULL CHECK (status IN ('ok', 'failed')),
    error       TEXT,
    params      TEXT    NOT NULL,
    truth       TEXT,
    result      TEXT,
    metrics     TEXT    NOT NULL,
    timings     TEXT    NOT NULL,
    worker      TEXT,
    finished_at TEXT    NOT NULL,
    PRIMARY KEY (seed, item, config_hash)
) WITHOUT ROWID;
"""


def canonical_json(value) -> str:
    """Deterministic JSON text: sorted keys, no spaces, non-finite floats as null.

    Python writes floats with the shortest repr that round-trips, so equal numbers give equal
    text on every machine.
    """
    return json.dumps(_finite(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


def _finite(value):
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if hasattr(value, "item") and callable(value.item) and getattr(value, "ndim", None) == 0:
        return _finite(value.item())  # numpy scalar
    if hasattr(value, "tolist"):
        return _finite(value.tolist())  # numpy array
    return value


Key = tuple[int, int, str]


@dataclass(frozen=True)
class Row:
    """One stored result.

    Attributes:
        seed: Study seed.
        item: Beam index (prbdm) or case index (assign).
        config_hash: Hash of the model configuration.
        kind: ``"prbdm"`` or ``"assign"``.
        status: ``"ok"`` or ``"failed"``.
        error: ``"ExceptionType: message"`` of a failed task, else None.
        params: Beam parameters or case settings.
        truth: Reference solution, or None.
        result: Fitted parameters or assignment answer, or None.
        metrics: Headline errors [-] (fractions, not percent).
        timings: Compute time per stage [s].
        worker: Address of the worker that ran the task.
        finished_at: UTC time the row was stored (ISO 8601).
    """

    seed: int
    item: int
    config_hash: str
    kind: str
    status: str
    error: str | None
    params: dict
    truth: dict | None
    result: dict | None
    metrics: dict
    timings: dict
    worker: str | None = None
    finished_at: str = ""

    @property
    def key(self) -> Key:
        """The primary key (seed, item, config_hash)."""
        return (self.seed, self.item, self.config_hash)


class ResultStore:
    """A batch result store in one SQLite file (see the module docstring).

    Args:
        path: File of the store; created with its parent folder if missing.
        timeout_s: How long a write waits for another connection's lock [s].

    Raises:
        StoreError: If the file is not a pinflex store or has another schema version.
    """

    def __init__(self, path: str | Path, timeout_s: float = 60.0):
        """Open (or create) the store and check its schema version.

        Args:
            path: File of the store; created with its parent folder if missing.
            timeout_s: How long a write waits for another connection's lock [s].

        Raises:
            StoreError: The file is not a usable SQLite store or has another schema version.
        """
        from pinflex.exceptions import OutputError
        from pinflex.outputs import check_file_target, output_dir

        try:
            self.path = check_file_target(path, "--store")
            output_dir(self.path.parent, "store folder")
        except OutputError as exc:
            raise StoreError(str(exc)) from None
        try:
            self._db = sqlite3.connect(self.path, timeout=timeout_s, isolation_level=None)
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.executescript(_SCHEMA)
            self._db.execute("INSERT OR IGNORE INTO meta VALUES ('schema_version', ?)",
                             (SCHEMA_VERSION,))
            (version,) = self._db.execute(
                "SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"'{self.path}' is not a usable SQLite store ({exc}); pass a new "
                             "file name to --store") from exc
        if version != SCHEMA_VERSION:
            raise StoreError(f"'{self.path}' has store schema version {version}; this pinflex "
                             f"writes version {SCHEMA_VERSION}: use a new --store file")

    def close(self) -> None:
        """Close the connection (rows are already durable)."""
        self._db.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def add_config(self, config_hash: str, kind: str, config: dict) -> None:
        """Record a configuration under its hash (no-op if already there).

        Args:
            config_hash: Hash identifying the configuration (the ``config_hash`` of rows).
            kind: Kind of study the configuration belongs to.
            config: The configuration, JSON-serialisable; stored as canonical JSON.
        """
        self._db.execute("INSERT OR IGNORE INTO configs VALUES (?, ?, ?)",
                         (config_hash, kind, canonical_json(config)))

    def configs(self) -> dict[str, tuple[str, dict]]:
        """All configurations: ``{config_hash: (kind, config)}``."""
        return {h: (k, json.loads(c))
                for h, k, c in self._db.execute("SELECT config_hash, kind, config FROM configs")}

    def finished_keys(self, include_failed: bool = True) -> set[Key]:
        """Keys that a rerun skips: every stored row, or only the ``ok`` ones.

        Args:
            include_failed: Also return the keys of ``failed`` rows (default True).

        Returns:
            ``{(seed, item, config_hash)}``.
        """
        sql = "SELECT seed, item, config_hash FROM results"
        if not include_failed:
            sql += " WHERE status = 'ok'"
        return {(int(s), int(i), str(h)) for s, i, h in self._db.execute(sql)}

    def write(self, rows: Iterable[dict], replace_failed: bool = False) -> int:
        """Store rows, each in its own transaction; return how many were written.

        A key already stored is left unchanged (reruns are idempotent), except that a stored
        ``failed`` row is replaced when ``replace_failed`` is set (``--retry-failed``). An
        ``ok`` row is never overwritten.

        Args:
            rows: Dictionaries with the fields of :class:`Row` (``finished_at`` is filled in).
            replace_failed: Whether a new row may replace a stored failure.

        Raises:
            StoreError: If a row has an unknown status or misses a field.
        """
        sql = (f"INSERT INTO results ({', '.join(_COLUMNS)}) "
               f"VALUES ({', '.join('?' * len(_COLUMNS))}) "
               "ON CONFLICT (seed, item, config_hash) DO ")
        sql += ("UPDATE SET " + ", ".join(f"{c} = excluded.{c}" for c in _COLUMNS[3:])
                + " WHERE results.status = 'failed'") if replace_failed else "NOTHING"
        written = 0
        for row in rows:
            values = self._values(row)
            for attempt in range(5):
                try:
                    cursor = self._db.execute(sql, values)  # autocommit: one transaction
                    break
                except sqlite3.OperationalError as exc:  # a reader holds a lock
                    if "locked" not in str(exc) or attempt == 4:
                        raise StoreError(f"cannot write to '{self.path}': {exc}") from exc
                    time.sleep(0.2 * (attempt + 1))
            written += cursor.rowcount
        return written

    @staticmethod
    def _values(row: dict) -> tuple:
        missing = [c for c in ("seed", "item", "config_hash", "kind", "status", "params",
                               "metrics", "timings") if c not in row]
        if missing:
            raise StoreError(f"a result row lacks the fields {missing}")
        if row["status"] not in STATUSES:
            raise StoreError(f"row status {row['status']!r} must be one of {STATUSES}")
        finished = row.get("finished_at") or datetime.now(timezone.utc).isoformat(
            timespec="seconds")
        out = []
        for column in _COLUMNS:
            value = row.get(column)
            if column == "finished_at":
                value = finished
            elif column in _JSON_FIELDS and value is not None:
                value = canonical_json(value)
            out.append(value)
        return tuple(out)

    def rows(self, kind: str | None = None, status: str | None = None) -> Iterator[Row]:
        """Stored rows ordered by key, optionally of one kind and status.

        Args:
            kind: Only rows of this kind (None: every kind).
            status: Only rows of this status (None: every status).

        Returns:
            An iterator of :class:`Row`, JSON fields decoded, ordered by
            ``(config_hash, seed, item)``.
        """
        where, args = [], []
        if kind is not None:
            where.append("kind = ?")
            args.append(kind)
        if status is not None:
            where.append("status = ?")
            args.append(status)
        sql = f"SELECT {', '.join(_COLUMNS)} FROM results"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += " ORDER BY config_hash, seed, item"
        for values in self._db.execute(sql, args):
            record = dict(zip(_COLUMNS, values))
            for column in _JSON_FIELDS:
                if record[column] is not None:
                    record[column] = json.loads(record[column])
            yield Row(**record)

    def raw_rows(self) -> list[tuple]:
        """Every row as stored (text columns unparsed), ordered by key; for exact comparisons."""
        return list(self._db.execute(
            f"SELECT {', '.join(_COLUMNS)} FROM results ORDER BY seed, item, config_hash"))

    def count(self, status: str | None = None) -> int:
        """Number of stored rows, optionally of one status.

        Args:
            status: Only count rows of this status (None: every row).

        Returns:
            The number of rows.
        """
        if status is None:
            return int(self._db.execute("SELECT COUNT(*) FROM results").fetchone()[0])
        return int(self._db.execute("SELECT COUNT(*) FROM results WHERE status = ?",
                                    (status,)).fetchone()[0])
