"""``pinflex batch report``: error distributions, failures and histograms of a result store.

Rows are grouped by study: a PRBDM configuration (its config hash: nR, modes, objective, ...)
or an assignment study file (all the cases of its sweeps). For each group the report gives the
row counts, percentiles of every metric over the ``ok`` rows (errors as fractions; the text
shows percent), mean compute times, and the failures grouped by stage and exception type
with a few example keys. Histograms of log10 of each error are written as PNG.
"""

from __future__ import annotations

import re
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pinflex.batch.store import ResultStore, Row
from pinflex.exceptions import StoreError
from pinflex.outputs import output_dir, save_figure

PERCENTILES = (0, 5, 25, 50, 75, 95, 100)


@dataclass
class GroupReport:
    """Statistics of one group of rows.

    Attributes:
        name: Group label (e.g. ``prbdm 4R/4 modes eigen ...``).
        kind: ``"prbdm"`` or ``"assign"``.
        config_hashes: Configurations in the group.
        n_ok: Rows with status ``ok``.
        n_failed: Rows with status ``failed``.
        metrics: ``{metric: {"n", "mean", "p0", "p5", ..., "p100"}}`` over ok rows [-].
        timings_s: Mean compute time of each stage over the rows that report it [s].
        failures: ``[(stage_and_type, count, [example "seed/item/hash: message", ...])]``.
    """

    name: str
    kind: str
    config_hashes: list[str] = field(default_factory=list)
    n_ok: int = 0
    n_failed: int = 0
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)
    failures: list[tuple[str, int, list[str]]] = field(default_factory=list)


@dataclass
class Report:
    """Report of a whole store: one :class:`GroupReport` per study group."""

    path: str
    groups: list[GroupReport]

    def to_dict(self) -> dict:
        """Plain dictionary (JSON-ready)."""
        return {"store": self.path, "groups": [vars(g) for g in self.groups]}

    def text(self) -> str:
        """Human-readable report."""
        if not self.groups:
            return f"{self.path}: no rows"
        out = [f"store {self.path}"]
        for g in self.groups:
            total = g.n_ok + g.n_failed
            out.append("")
            out.append(f"== {g.name}: {total} rows, {g.n_ok} ok, {g.n_failed} failed")
            if g.metrics:
                head = "".join(f"{'p' + str(p):>10}" for p in PERCENTILES)
                out.append(f"  {'error [%]':<26}{'n':>6}{head}{'mean':>10}")
                for name, st in g.metrics.items():
                    vals = "".join(f"{100 * st['p' + str(p)]:>10.3g}" for p in PERCENTILES)
                    out.append(f"  {name:<26}{int(st['n']):>6}{vals}{100 * st['mean']:>10.3g}")
            if g.timings_s:
                out.append("  mean time: " + ", ".join(
                    f"{k.removesuffix('_s')} {v:.3g} s" for k, v in g.timings_s.items()))
            for label, count, examples in g.failures:
                out.append(f"  failed {count}x {label}")
                for example in examples:
                    out.append(f"      {example}")
        return "\n".join(out)


def _group_of(row: Row, configs: dict) -> tuple[str, str]:
    kind, config = configs.get(row.config_hash, (row.kind, {}))
    if row.kind == "assign":
        return f"assign:{config.get('study_sha256')}", (
            f"assign {config.get('study_file', '?')} (sweep)")
    fit, beam = config.get("fit", {}), config.get("beam", {})
    return row.config_hash, (
        f"prbdm {fit.get('n_joints')}R/{fit.get('n_modes')} modes, {fit.get('objective')}, "
        f"{fit.get('n_starts')} starts, p = {beam.get('n_sections')} "
        f"[{row.config_hash}]")


def _stats(values: list[float]) -> dict[str, float]:
    a = np.asarray(values, dtype=float)
    out = {"n": float(a.size), "mean": float(a.mean())}
    out.update({f"p{p}": float(v) for p, v in zip(PERCENTILES, np.percentile(a, PERCENTILES))})
    return out


def _metric_values(rows: list[Row]) -> dict[str, list[float]]:
    values: dict[str, list[float]] = defaultdict(list)
    for row in rows:
        if row.status != "ok":
            continue
        for name, v in row.metrics.items():
            if v is not None and np.isfinite(v):
                values[name].append(float(v))
    return values


def build_report(path: str | Path, n_examples: int = 3) -> Report:
    """Statistics of every study group in a store.

    Raises:
        StoreError: If the file does not exist or is not a store.
    """
    if not Path(path).is_file():
        raise StoreError(f"no store at '{path}'; pass the --store file of a batch run")
    with ResultStore(path) as store:
        configs = store.configs()
        grouped: dict[str, tuple[str, list[Row]]] = {}
        for row in store.rows():
            key, name = _group_of(row, configs)
            grouped.setdefault(key, (name, []))[1].append(row)
    groups = []
    for key, (name, rows) in grouped.items():
        g = GroupReport(name=name, kind=rows[0].kind,
                        config_hashes=sorted({r.config_hash for r in rows}))
        g.n_ok = sum(r.status == "ok" for r in rows)
        g.n_failed = len(rows) - g.n_ok
        g.metrics = {m: _stats(v) for m, v in sorted(_metric_values(rows).items()) if v}
        times: dict[str, list[float]] = defaultdict(list)
        for r in rows:
            for k, v in r.timings.items():
                times[k].append(float(v))
        g.timings_s = {k: float(np.mean(v)) for k, v in times.items()}
        kinds: Counter = Counter()
        examples: dict[str, list[str]] = defaultdict(list)
        for r in rows:
            if r.status != "failed":
                continue
            parts = (r.error or "unknown: unknown").split(": ", 2)
            label = ": ".join(parts[:2])
            kinds[label] += 1
            if len(examples[label]) < n_examples:
                message = parts[-1] if len(parts) == 3 else (r.error or "")
                short = message if len(message) <= 160 else message[:157] + "..."
                examples[label].append(f"{r.seed}/{r.item}/{r.config_hash}: {short}")
        g.failures = [(label, count, examples[label]) for label, count in kinds.most_common()]
        groups.append(g)
    return Report(str(path), groups)


def write_histograms(path: str | Path, out_dir: str | Path | None = None,
                     bins: int = 40) -> list[Path]:
    """Histograms of log10(error) for every group and metric, as PNG files.

    Args:
        path: The store.
        out_dir: Output folder; default the store's path without suffix + ``-report``.
        bins: Most histogram bins (fewer for few rows).

    Returns:
        The written files.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(path)
    out = Path(out_dir) if out_dir is not None else path.with_name(path.stem + "-report")
    out = output_dir(out, "report folder")
    with ResultStore(path) as store:
        configs = store.configs()
        grouped: dict[str, tuple[str, list[Row]]] = {}
        for row in store.rows(status="ok"):
            key, name = _group_of(row, configs)
            grouped.setdefault(key, (name, []))[1].append(row)
    written = []
    for index, (key, (name, rows)) in enumerate(sorted(grouped.items())):
        for metric, values in sorted(_metric_values(rows).items()):
            positive = np.asarray([v for v in values if v > 0.0])
            if positive.size == 0:
                continue
            fig = Figure(figsize=(6.0, 3.6))
            FigureCanvasAgg(fig)  # its own canvas: the process-wide backend is left alone
            ax = fig.add_subplot()
            n_bins = min(bins, max(5, 2 * int(np.sqrt(positive.size))))
            ax.hist(np.log10(positive), bins=n_bins, color="tab:blue", alpha=0.8)
            ax.axvline(np.log10(np.median(positive)), color="k", lw=1,
                       label=f"median {100 * np.median(positive):.3g} %")
            ax.set_xlabel(f"log10 {metric} [-]")
            ax.set_ylabel("rows")
            ax.set_title(f"{name}\n{positive.size} rows", fontsize=8)
            ax.legend(fontsize=8)
            fig.tight_layout()
            safe = re.sub(r"[^A-Za-z0-9._-]+", "-", name.split(" [")[0]).strip("-")
            file = out / f"{index:02d}_{safe}_{metric}.png"
            save_figure(fig, file, dpi=110)
            written.append(file)
    return written


@dataclass
class CaseTable:
    """One row per assignment case of a store, the case parameters as columns.

    Attributes:
        columns: Column names: ``case``, one per swept key (its dotted study key), ``status``,
            the design variables [kg], ``total_kg``, ``error_before_%``, ``error_after_%``,
            ``predicted_after_%``, ``qp_iterations``, ``time_s``, ``error``.
        rows: Values, one list per case, ordered by case index.
    """

    columns: list[str]
    rows: list[list]

    def to_csv(self, path: str | Path) -> Path:
        """Write the table as CSV (empty cells for missing values)."""
        import csv

        from pinflex.outputs import atomic_path

        path = Path(path)
        with atomic_path(path, "sweep table CSV") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(self.columns)
            for r in self.rows:
                w.writerow(["" if v is None else v for v in r])
        return path

    def text(self, max_error_chars: int = 40) -> str:
        """An aligned terminal table."""
        def fmt(v):
            if v is None:
                return "-"
            if isinstance(v, float):
                return f"{v:.4g}"
            s = str(v)
            return s if len(s) <= max_error_chars else s[: max_error_chars - 3] + "..."

        cells = [[fmt(v) for v in r] for r in self.rows]
        widths = [max([len(c)] + [len(r[i]) for r in cells]) for i, c in enumerate(self.columns)]
        line = "  ".join(c.rjust(w) for c, w in zip(self.columns, widths))
        out = [line, "  ".join("-" * w for w in widths)]
        out += ["  ".join(v.rjust(w) for v, w in zip(r, widths)) for r in cells]
        return "\n".join(out)


def case_table(path: str | Path) -> CaseTable:
    """The per-case table of the assignment rows of a store (empty without any).

    Raises:
        StoreError: If the file does not exist or is not a store.
    """
    if not Path(path).is_file():
        raise StoreError(f"no store at '{path}'; pass the --store file of a batch run")
    with ResultStore(path) as store:
        rows = list(store.rows(kind="assign"))
    rows.sort(key=lambda r: int((r.params or {}).get("case", r.item)))
    keys: list[str] = []
    design: list[str] = []
    for r in rows:
        for k in ((r.params or {}).get("overrides") or {}):
            if k not in keys:
                keys.append(k)
        for k in ((r.result or {}).get("design") or {}):
            if k not in design:
                design.append(k)
    columns = (["case"] + keys + ["status"] + [f"{d}_kg" for d in design]
               + ["total_kg", "error_before_%", "error_after_%", "predicted_after_%",
                  "qp_iterations", "time_s", "error"])
    table = []
    for r in rows:
        params = r.params or {}
        over = params.get("overrides") or {}
        res = r.result or {}
        des = res.get("design") or {}

        def pct(v):
            return None if v is None else 100.0 * float(v)

        table.append(
            [int(params.get("case", r.item))]
            + [over.get(k) for k in keys]
            + [r.status]
            + [des.get(d) for d in design]
            + [float(sum(des.values())) if des else None,
               pct(res.get("max_error_before")), pct(res.get("max_error_after")),
               pct(res.get("predicted_max_error_after")), res.get("iterations"),
               (r.timings or {}).get("task_s"), r.error]
        )
    return CaseTable(columns, table)
