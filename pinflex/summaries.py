"""Short text summaries of models and results, for their ``repr`` (no array dumps).

A result printed at the prompt should say what it holds in a few lines, as Pinocchio's models
do: counts, shapes, ranges and the few numbers that matter, never a whole array.
:func:`dataclass_summary` does so for any dataclass (a class opts in with
``__repr__ = dataclass_summary``); :func:`taylor_summary` and :func:`model_summary` name what
matters for a Taylor model and a flexible model.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

#: Arrays with at most this many entries are shown in full (rounded).
SMALL_ARRAY = 6
#: Width beyond which a summary is split into one field per line.
LINE = 100


def value_summary(value: Any) -> str:
    """One short piece of text for a field's value.

    Small arrays and sequences of numbers are shown rounded to 4 significant digits, larger
    ones as shape, dtype and range; nested dataclasses by their class name; mappings by
    their keys.
    """
    if isinstance(value, np.ndarray):
        return array_summary(value)
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, str):
        return repr(value) if len(value) <= 60 else repr(value[:57] + "...")
    if dataclasses.is_dataclass(value):
        return f"{type(value).__name__}(...)"
    if isinstance(value, Mapping):
        keys = list(value)
        if len(keys) <= 6 and all(isinstance(v, int | float | str | np.number) for v in
                                  value.values()):
            return "{" + ", ".join(f"{k}: {value_summary(v)}" for k, v in value.items()) + "}"
        shown = ", ".join(str(k) for k in keys[:6])
        more = f", ... ({len(keys)} keys)" if len(keys) > 6 else ""
        return "{" + shown + more + "}"
    if isinstance(value, Sequence) and not isinstance(value, bytes | bytearray):
        if all(isinstance(v, int | float | np.number) and not isinstance(v, bool)
               for v in value):
            return array_summary(np.asarray(value), sequence=type(value).__name__)
        if len(value) <= 3:
            return "[" + ", ".join(value_summary(v) for v in value) + "]"
        return f"<{len(value)} {type(value[0]).__name__}>"
    if isinstance(value, bytes | bytearray):
        return f"<{len(value)} bytes>"
    text = repr(value)
    return text if len(text) <= 60 else f"<{type(value).__name__}>"


def array_summary(a: np.ndarray, sequence: str | None = None) -> str:
    """An array in a few characters: its values if small, else shape, dtype and range."""
    a = np.asarray(a)
    if a.size <= SMALL_ARRAY and a.ndim <= 1:
        body = ", ".join(_number(v) for v in a.ravel())
        return f"({body}{',' if a.size == 1 else ''})" if sequence == "tuple" else f"[{body}]"
    shape = "×".join(str(n) for n in a.shape)
    if a.size == 0 or a.dtype.kind not in "biuf":
        return f"<{shape} {a.dtype}>"
    finite = a[np.isfinite(a)] if a.dtype.kind == "f" else a
    if finite.size == 0:
        return f"<{shape} {a.dtype}, no finite value>"
    rng = f"{_number(finite.min())} .. {_number(finite.max())}"
    nonfinite = a.size - finite.size
    return f"<{shape} {a.dtype}, {rng}{f', {nonfinite} not finite' if nonfinite else ''}>"


def _number(v) -> str:
    if isinstance(v, bool | np.bool_):
        return str(bool(v))
    if isinstance(v, int | np.integer):
        return str(int(v))
    return f"{float(v):.4g}"


def lines_summary(name: str, items: Sequence[tuple[str, str]]) -> str:
    """``Name(a=..., b=...)`` on one line, or one item per line when that is too wide."""
    one = f"{name}(" + ", ".join(f"{k}={v}" for k, v in items) + ")"
    if len(one) <= LINE:
        return one
    return f"{name}(\n" + "".join(f"  {k}={v},\n" for k, v in items) + ")"


def dataclass_summary(obj: Any) -> str:
    """The ``repr`` of a result dataclass, with arrays summarised (fields with ``repr=False``
    are left out, as the generated ``repr`` would)."""
    items = [(f.name, value_summary(getattr(obj, f.name)))
             for f in dataclasses.fields(obj) if f.repr]
    return lines_summary(type(obj).__name__, items)


def taylor_summary(model: Any) -> str:
    """A Taylor model: order, variables, modes, expansion point and radius.

    Args:
        model: A :class:`~pinflex.parametric.TaylorModel`.
    """
    nq, ny = len(model.joint_idx), len(model.design_idx)
    variables = []
    if nq:
        variables.append("joints " + ", ".join(f"q[{i}]" for i in model.joint_idx))
    if ny:
        variables.append("design " + ", ".join(f"y[{i}]" for i in model.design_idx))
    radius = np.asarray(model.radius)
    rad = "; ".join(
        f"mode {m}: {array_summary(radius[:, c])}" for c, m in enumerate(model.modes)
    ) if radius.size else "none"
    items = [
        ("order", str(model.order)),
        ("variables", f"{nq + ny} ({'; '.join(variables) or 'none'})"),
        ("modes", str(tuple(model.modes))),
        ("q0", array_summary(model.q0)),
        ("y0", array_summary(model.y0)),
        ("radius", rad),
    ]
    if model.joints:
        items.append(("joints", ", ".join(f"{k} {v}" for k, v in model.joints.items())))
    return lines_summary(type(model).__name__, items)


def model_summary(model: Any) -> str:
    """A flexible model: robot, dof, flexible links, joint conditions and design.

    Args:
        model: A :class:`~pinflex.FlexibleModel`.
    """
    name = model.description.name
    beams = model.plan.beams
    links = ", ".join(
        f"{link} ({b.spec.elements} elements, {b.spec.length_m:.4g} m)" for link, b in beams.items()
    )
    labels = model.joint_labels()
    kinds: dict[str, list[str]] = {}
    for joint, label in labels.items():
        kinds.setdefault(label, []).append(joint)
    if len(kinds) == 1:
        joints = f"all {next(iter(kinds))} ({len(labels)})"
    else:
        joints = "; ".join(f"{label}: {', '.join(js)}" for label, js in kinds.items())
    design = ", ".join(f"{n}: {float(v):.4g}" for n, v in zip(model.design_names, model.y0))
    items = [
        ("robot", repr(name)),
        ("dof", f"{model.ndof} ({model.nx} elastic + {model.nv} joints"
                f"{', planar' if model.planar else ''})"),
        ("flexible", links or "none"),
        ("joints", joints),
        ("design", "{" + design + "}" if design else "none"),
    ]
    if model.coordinates != "relative":
        items.append(("coordinates", model.coordinates))
    return lines_summary(type(model).__name__, items)
