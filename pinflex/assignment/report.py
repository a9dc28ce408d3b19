"""An assignment's answer as data: per sample and mode, and which constraints are active.

:func:`assignment_data` gathers, for every trajectory sample and every reported mode, the
target, the exact frequency before, the frequency the partially linear Taylor model predicts
for the chosen design, and the exact frequency after; and for every constraint (mass budget,
frequency floors, forbidden bands, design bounds, extra inequality rows) its value, its limit,
its slack and whether it is active at the answer. The result writes itself as CSV (long format:
one row per sample and mode), JSON, or Parquet when pyarrow is installed.

Activity: a constraint is *active* when its slack at the answer is below ``1e-6`` of its scale
(the budget in kg, the floor or band edge in Hz, the bound range in the variable's unit). Floors and bands are
imposed on the prediction; their exact slack (exact frequencies after) is reported too, and a
negative exact slack means that the exact model crosses a floor or enters a band that the
prediction kept clear.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pinflex.checks import check_q
from pinflex.exceptions import MissingDependency


@dataclass(frozen=True)
class AssignmentData:
    """Frequencies and constraints of an assignment, ready to write.

    Attributes:
        times_s: Sample times (ns,) [s].
        q: Joint samples (ns, nv).
        joint_names: Column names of ``q``.
        modes: Reported modes (targets first).
        roles: Per mode, ``"target"``, ``"floor"``, ``"band"`` or ``"report"`` (joined by
            ``+`` when several apply).
        target_hz: (ns, nm) targets [Hz], NaN for modes without one.
        before_hz: (ns, nm) exact frequencies of the design before [Hz].
        predicted_hz: (ns, nm) Taylor prediction at the design after [Hz], NaN for modes the
            Taylor model does not carry.
        after_hz: (ns, nm) exact frequencies of the design after [Hz].
        design_before: ``{name: value}`` before, each in its variable's unit.
        design_after: ``{name: value}`` after.
        constraints: One dictionary per constraint: ``name``, ``kind`` (``budget``, ``floor``,
            ``band``, ``lower_bound``, ``upper_bound``, ``inequality``), ``value``, ``limit``,
            ``slack`` (>= 0 when satisfied), ``active``, ``exact_slack`` (floors and bands),
            ``unit`` (a bound's is its variable's).
        design_units: ``{name: unit}`` of the design variables.
        validity: The validity indicator of eq. (1) along the trajectory at the design after
            (:class:`pinflex.erls.validity.Validity`), or None; its per-sample ratios of
            mode 1 are the ``speed_ratio`` and ``accel_ratio`` columns.
    """

    times_s: np.ndarray
    q: np.ndarray
    joint_names: tuple[str, ...]
    modes: tuple[int, ...]
    roles: tuple[str, ...]
    target_hz: np.ndarray
    before_hz: np.ndarray
    predicted_hz: np.ndarray
    after_hz: np.ndarray
    design_before: dict
    design_after: dict
    constraints: tuple[dict, ...]
    design_units: dict = field(default_factory=dict)
    validity: Any = None

    @property
    def active(self) -> list[str]:
        """Names of the active constraints."""
        return [c["name"] for c in self.constraints if c["active"]]

    def rows(self) -> list[dict]:
        """Long format: one row per sample and mode."""
        out = []
        for k in range(self.times_s.size):
            base: dict[str, Any] = {"sample": k, "t": float(self.times_s[k])}
            base.update({n: float(v) for n, v in zip(self.joint_names, self.q[k])})
            for c, m in enumerate(self.modes):
                tgt = self.target_hz[k, c]
                row = dict(base)
                row.update(
                    mode=m,
                    role=self.roles[c],
                    target_hz=float(tgt),
                    before_hz=float(self.before_hz[k, c]),
                    predicted_hz=float(self.predicted_hz[k, c]),
                    after_hz=float(self.after_hz[k, c]),
                    error_before=float(self.before_hz[k, c] / tgt - 1.0),
                    error_after=float(self.after_hz[k, c] / tgt - 1.0),
                )
                if self.validity is not None:
                    row.update(speed_ratio=float(self.validity.speed_ratio[k, 0]),
                               accel_ratio=float(self.validity.accel_ratio[k, 0]))
                out.append(row)
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` (empty cells for NaN: no target or no prediction)."""
        from pinflex.outputs import atomic_path

        path = Path(path)
        rows = self.rows()
        with atomic_path(path, "assignment CSV") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            for r in rows:
                w.writerow({k: ("" if isinstance(v, float) and not np.isfinite(v) else
                                repr(v) if isinstance(v, float) else v) for k, v in r.items()})
        return path

    def to_parquet(self, path: str | Path) -> Path:
        """Write :meth:`rows` as Parquet (needs pyarrow)."""
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError as exc:
            raise MissingDependency("pyarrow", "Parquet output") from exc
        rows = self.rows()
        from pinflex.outputs import atomic_path

        table = pa.table({k: [r[k] for r in rows] for k in rows[0]})
        with atomic_path(path, "assignment Parquet") as tmp:
            pq.write_table(table, str(tmp))
        return Path(path)

    def to_dict(self) -> dict:
        """JSON-ready: per mode arrays over the samples, constraints, active names."""
        def clean(a):
            return [None if not np.isfinite(v) else float(v) for v in a]

        return {
            "times_s": self.times_s.tolist(),
            "joint_names": list(self.joint_names),
            "q": self.q.tolist(),
            "design_before": self.design_before,
            "design_after": self.design_after,
            "design_units": self.design_units,
            "modes": [
                {
                    "mode": m,
                    "role": self.roles[c],
                    "target_hz": clean(self.target_hz[:, c]),
                    "before_hz": clean(self.before_hz[:, c]),
                    "predicted_hz": clean(self.predicted_hz[:, c]),
                    "after_hz": clean(self.after_hz[:, c]),
                }
                for c, m in enumerate(self.modes)
            ],
            "constraints": [dict(c) for c in self.constraints],
            "active_constraints": self.active,
            "validity": None if self.validity is None else self.validity.to_dict(),
        }

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as a JSON file."""
        from pinflex.outputs import json_text, write_text

        return write_text(path, json_text(self.to_dict(), indent=1), "assignment JSON")

    def constraint_lines(self) -> list[str]:
        """Readable lines, one per constraint, active ones marked."""
        lines = []
        for c in self.constraints:
            mark = "ACTIVE" if c["active"] else "      "
            text = f"{mark} {c['name']}: {c['value']:.6g} vs {c['limit']:.6g} {c['unit']} " \
                   f"(slack {c['slack']:.3g})"
            if c.get("exact_slack") is not None:
                text += f", exact slack {c['exact_slack']:.3g}"
                if c["exact_slack"] < -1e-9 * max(1.0, abs(c["limit"])):
                    text += " VIOLATED by the exact model"
            lines.append(text)
        return lines


def _is_active(slack: float, scale: float) -> bool:
    return bool(slack <= 1e-6 * max(abs(scale), 1e-12))


def assignment_data(model, trajectory, result) -> AssignmentData:
    """Per-sample, per-mode frequencies and the constraint report of an assignment.

    Args:
        model: The :class:`~pinflex.FlexibleModel` the assignment ran on.
        trajectory: Its trajectory (user coordinates).
        result: The :class:`~pinflex.assignment.AssignmentResult`.

    Returns:
        :class:`AssignmentData`.
    """
    settings = dict(result.settings or {})
    floors = list(settings.get("floors", []))
    bands = list(settings.get("bands", []))
    budget = settings.get("mass_budget_kg")
    quantity = settings.get("quantity", "freq_hz")
    Q = check_q(model, trajectory.in_order(model.joint_names))
    ns = Q.shape[0]
    modes = list(result.modes)
    for m in [f[0] for f in floors] + [b[0] for b in bands]:
        if m not in modes:
            modes.append(int(m))
    n_targets = result.targets_hz.shape[0]
    target_modes = list(result.modes[:n_targets])
    extra = [m for m in modes if m not in result.modes]
    before, after = result.freq_before_hz, result.freq_after_hz
    if extra:
        nmax = max(extra)
        fb = model.frequencies(Q, result.y_before, n_modes=nmax)
        fa = model.frequencies(Q, result.y, n_modes=nmax)
        before = np.hstack([before, fb[:, [m - 1 for m in extra]]])
        after = np.hstack([after, fa[:, [m - 1 for m in extra]]])
    target = np.full((ns, len(modes)), np.nan)
    for k, m in enumerate(target_modes):
        target[:, modes.index(m)] = result.targets_hz[k]
    # the Taylor model's prediction at the answer: the array the result carries (the same
    # function gives predicted_max_error_after and the confirmation gap)
    from pinflex.assignment.build import budget_mass, predicted_hz

    tm = result.taylor
    didx = list(tm.design_idx)
    dy = np.asarray(result.y)[didx] - tm.y0[didx]
    predicted = predicted_hz(tm, Q, result.y, modes, quantity)
    if result.predicted_hz is not None:
        given = list(result.modes)
        for c, m in enumerate(modes):
            if m in given:
                predicted[:, c] = result.predicted_hz[:, given.index(m)]
    roles = []
    for m in modes:
        r = [name for name, ms in (("target", target_modes), ("floor", [f[0] for f in floors]),
                                   ("band", [b[0] for b in bands])) if m in ms]
        roles.append("+".join(r) or "report")
    constraints: list[dict] = []
    names = [d.name for d in model.design]
    y = np.asarray(result.y)
    if budget is not None:
        total = float(budget_mass(model, y, didx))
        slack = float(budget) - total
        constraints.append(dict(name="mass budget", kind="budget", value=total,
                                limit=float(budget), slack=slack,
                                active=_is_active(slack, budget), exact_slack=None, unit="kg"))
    for m, f in floors:
        c = modes.index(m)
        slack = float(np.min(predicted[:, c] - f))
        constraints.append(dict(
            name=f"floor mode {m} >= {f:g} Hz", kind="floor",
            value=float(np.min(predicted[:, c])), limit=float(f), slack=slack,
            active=_is_active(slack, f), exact_slack=float(np.min(after[:, c] - f)), unit="Hz",
        ))
    for m, a, b in bands:
        c = modes.index(m)

        def outside(f):
            return np.maximum(a - f, f - b)  # > 0 outside the band

        slack = float(np.min(outside(predicted[:, c])))
        closest = float(predicted[int(np.argmin(outside(predicted[:, c]))), c])
        constraints.append(dict(
            name=f"band mode {m} not in ({a:g}, {b:g}) Hz", kind="band",
            value=closest, limit=float(a if closest <= 0.5 * (a + b) else b), slack=slack,
            active=_is_active(slack, b), exact_slack=float(np.min(outside(after[:, c]))),
            unit="Hz",
        ))
    for j in didx:
        d = model.design[j]
        scale = (d.upper - d.lower) if np.isfinite(d.upper) else max(1.0, abs(d.lower))
        unit = d.unit
        constraints.append(dict(name=f"{names[j]} >= {d.lower:g} {unit}".rstrip(),
                                kind="lower_bound",
                                value=float(y[j]), limit=float(d.lower),
                                slack=float(y[j] - d.lower),
                                active=_is_active(float(y[j] - d.lower), scale),
                                exact_slack=None, unit=unit))
        if np.isfinite(d.upper):
            constraints.append(dict(name=f"{names[j]} <= {d.upper:g} {unit}".rstrip(),
                                    kind="upper_bound",
                                    value=float(y[j]), limit=float(d.upper),
                                    slack=float(d.upper - y[j]),
                                    active=_is_active(float(d.upper - y[j]), scale),
                                    exact_slack=None, unit=unit))
    prob = result.problem
    first_user = 1 if budget is not None else 0
    groups = list(prob.constraint_groups)
    ineq = [i for i, g in enumerate(groups) if g == "inequality"][first_user:]
    for n_row, i in enumerate(ineq):
        value = float(prob.C[i] @ dy)
        slack = float(prob.u[i] - value)
        constraints.append(dict(name=f"inequality[{n_row}]", kind="inequality", value=value,
                                limit=float(prob.u[i]), slack=slack,
                                active=_is_active(slack, max(abs(prob.u[i]), 1.0)),
                                exact_slack=None, unit=""))
    return AssignmentData(
        times_s=np.asarray(trajectory.times_s, dtype=float),
        q=np.asarray(Q),
        joint_names=tuple(model.joint_names),
        modes=tuple(modes),
        roles=tuple(roles),
        target_hz=target,
        before_hz=np.asarray(before),
        predicted_hz=predicted,
        after_hz=np.asarray(after),
        design_before={n: float(v) for n, v in zip(names, result.y_before)},
        design_after=dict(result.design),
        constraints=tuple(constraints),
        design_units={d.name: d.unit for d in model.design},
        validity=getattr(result, "validity", None),
    )
