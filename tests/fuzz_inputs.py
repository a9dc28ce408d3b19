"""Seeded fuzzing of the shipped input files: malformed URDFs, overlays and TOML studies.

Each variant is one mutation of a shipped file (``urdf/`` and ``examples/*.toml``): a
misspelt pinflex element or attribute, a wrong namespace, a deleted attribute, a non-numeric,
NaN, infinite, negative, zero, huge or tiny value, a duplicated element, a truncated file or
random bytes. A variant is *refused* when loading it raises a :class:`PinflexError`
subclass; anything else it raises is *foreign* (a defect). Misspellings, wrong namespaces,
non-numbers and non-finite values must always be refused (a silent acceptance is a defect).
Every 10th URDF variant that loads is also built into a :class:`FlexibleModel`, and every
50th has its frequencies computed at a zero pose; a study is loaded with its robot checks.

Further families (:func:`run_families`, each with its own rule of what must happen):

* ``trajectory_header``: the header of a trajectory CSV permuted (must load with the same
  samples per joint), or with an unknown, missing, duplicate, extra or misspelt column (must be
  refused); cells with Unicode digits, ``1_0``, NaN, empty or ragged rows (refused);
* ``unicode_digits``: one number of a shipped URDF (an annotation or a plain URDF value that
  Pinocchio reads) rewritten with Arabic-Indic or full-width digits, a no-break or thin space,
  or a digit separator: always refused;
* ``parameter_reference``: a numeric annotation replaced by ``{p}`` with a new parameter
  ``p`` holding the literal (a good or a bad one): the outcome must be the literal's
  (refused iff the literal is);
* ``simulation_bounds``: one key of a ``[simulation]`` table set to a value beyond its bound,
  NaN, a string or a boolean: refused; in range: accepted;
* ``api_types``: a public function called with an argument of a wrong type or value (None,
  strings, booleans, complex, masked and nested arrays, NaN): a ``PinflexError``;
* ``cli``: a command line with a bad number, path or option value, or a count or size beyond
  its bound (workers, beams, starts, sweep cases, modes, amplitudes, joint values): exit
  status 2 and exactly one line on stderr (never 1 or a traceback);
* ``study_files``: one change of the shipped study (dates, huge or float integers, nested
  arrays, wrong tables, devices and folders as files, duplicate keys, non-UTF-8): refused;
* ``urdf_structure``: structural URDF changes (indefinite inertias, text inside annotations,
  missing limits, parameter cycles, two robots, ...): refused, except the valid ones;
* ``output_targets``: writing to a pipe, a device, a folder, an empty or too long name, or
  under a file: OutputError (a device is never replaced).

Run ``python tests/fuzz_inputs.py [--variants N] [--seed S] [--json]`` for the counts;
``tests/test_fuzz_inputs.py`` runs it in the default suite.
"""

from __future__ import annotations

import argparse
import json
import random
import re
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from pinflex.description import load  # noqa: E402
from pinflex.description.schema import SCHEMA  # noqa: E402
from pinflex.exceptions import PinflexError  # noqa: E402

URDFS = sorted((ROOT / "urdf").iterdir())
STUDIES = sorted((ROOT / "examples").glob("*.toml"))
MUST_REFUSE = {"misspelt_element", "misspelt_attribute", "wrong_namespace", "non_numeric",
               "non_finite", "duplicate_element", "misspelt_toml_key", "toml_wrong_type",
               "deleted_required"}

_START = re.compile(r"<pinflex:(\w+)((?:\s+[\w:]+\s*=\s*\"[^\"]*\")*)\s*(/?)>")
_ATTR = re.compile(r"([\w:]+)\s*=\s*\"([^\"]*)\"")
_NUMERIC = {name: {k for k, a in spec.attrs.items() if a.kind in ("float", "int", "vec3")}
            for name, spec in SCHEMA.items()}
_BAD_NUMBERS = ["abc", "", "1,5", "0x10", "1_000", "--1", "1e", "one"]
_NON_FINITE = ["nan", "NaN", "inf", "-inf", "Infinity", "1e400", "-1e999"]
_ODD_NUMBERS = ["-1", "0", "-0.0", "1e300", "1e-300", "-1e-12", "1e12", "123456789"]


def misspell(name: str, rng: random.Random, valid: set[str]) -> str | None:
    """A one-edit misspelling of ``name`` that is not a valid name (None if none found)."""
    letters = "abcdefghijklmnopqrstuvwxyz_"
    for _ in range(20):
        i = rng.randrange(len(name))
        op = rng.choice(("swap", "drop", "double", "replace", "append", "case"))
        if op == "swap" and len(name) > 1:
            i = min(i, len(name) - 2)
            out = name[:i] + name[i + 1] + name[i] + name[i + 2:]
        elif op == "drop" and len(name) > 1:
            out = name[:i] + name[i + 1:]
        elif op == "double":
            out = name[:i] + name[i] + name[i:]
        elif op == "replace":
            out = name[:i] + rng.choice(letters) + name[i + 1:]
        elif op == "append":
            out = name + rng.choice(letters + "x")
        else:
            out = name.swapcase()
        if out != name and out not in valid and re.fullmatch(r"[A-Za-z_][\w]*", out):
            return out
    return None


def _tags(text: str):
    return list(_START.finditer(text))


def mutate_xml(text: str, rng: random.Random) -> tuple[str, str]:
    """One mutation of an annotated URDF or overlay: ``(kind, new_text)``."""
    tags = _tags(text)
    kind = rng.choice(["misspelt_element", "misspelt_attribute", "misspelt_attribute",
                       "wrong_namespace", "deleted_required", "deleted_optional",
                       "non_numeric", "non_finite", "odd_number", "odd_number",
                       "duplicate_element", "truncated", "random_bytes", "no_parent",
                       "inverted_limits"])
    tag = rng.choice(tags)
    name, attrs = tag.group(1), tag.group(2)
    spec = SCHEMA.get(name)
    if kind == "misspelt_element":
        bad = misspell(name, rng, set(SCHEMA))
        if bad is None:
            return "skip", text
        start, end = tag.span(1)
        out = text[:start] + bad + text[end:]
        close = f"</pinflex:{name}>"
        if not tag.group(3):
            j = out.find(close, end)
            if j >= 0:
                out = out[:j] + f"</pinflex:{bad}>" + out[j + len(close):]
        return kind, out
    if kind == "wrong_namespace":
        uri = rng.choice(["urn:pinflex:urdf:2", "urn:pinflex:urdf", "urn:pinflx:urdf:1",
                          "URN:PINFLEX:URDF:1", "urn:pinflex:urdf:1 ", "http://pinflex.org",
                          "urn:other:1"])
        return kind, text.replace('xmlns:pinflex="urn:pinflex:urdf:1"',
                                  f'xmlns:pinflex="{uri}"', 1)
    found = list(_ATTR.finditer(attrs))
    offset = tag.start(2)
    if kind in ("misspelt_attribute", "deleted_required", "deleted_optional", "non_numeric",
                "non_finite", "odd_number") and not found:
        return "skip", text
    if kind == "misspelt_attribute":
        a = rng.choice(found)
        bad = misspell(a.group(1), rng, set(spec.attrs) if spec else set())
        if bad is None or bad in {f.group(1) for f in found}:
            return "skip", text
        s, e = a.span(1)
        return kind, text[:offset + s] + bad + text[offset + e:]
    if kind in ("deleted_required", "deleted_optional"):
        want = kind == "deleted_required"
        pool = [a for a in found if spec and a.group(1) in spec.attrs
                and spec.attrs[a.group(1)].required == want]
        if not pool:
            return "skip", text
        a = rng.choice(pool)
        s, e = a.span(0)
        return kind, text[:offset + s] + text[offset + e:]
    if kind in ("non_numeric", "non_finite", "odd_number"):
        pool = [a for a in found if a.group(1) in _NUMERIC.get(name, ())]
        if not pool:
            return "skip", text
        a = rng.choice(pool)
        choices = {"non_numeric": _BAD_NUMBERS, "non_finite": _NON_FINITE,
                   "odd_number": _ODD_NUMBERS}[kind]
        value = rng.choice(choices)
        if spec.attrs[a.group(1)].kind == "vec3":
            parts = a.group(2).split() or ["0", "0", "0"]
            parts[rng.randrange(len(parts))] = value or "x"
            value = " ".join(parts)
        s, e = a.span(2)
        return kind, text[:offset + s] + value + text[offset + e:]
    if kind == "duplicate_element":
        if name in ("overlay",):
            return "skip", text
        if tag.group(3):  # self-closing: copy the tag
            return kind, text[:tag.end()] + "\n" + tag.group(0) + text[tag.end():]
        close = f"</pinflex:{name}>"
        j = text.find(close, tag.end())
        block = text[tag.start():j + len(close)]
        return kind, text[:j + len(close)] + "\n" + block + text[j + len(close):]
    if kind == "truncated":
        cut = rng.randrange(1, len(text))
        return kind, text[:cut]
    if kind == "random_bytes":
        data = bytearray(text.encode())
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        return kind, bytes(data)  # type: ignore[return-value]
    if kind == "no_parent":
        if "<parent" not in text:
            return "skip", text
        return kind, re.sub(r"<parent\s+link=\"[^\"]*\"\s*/>", "", text, count=1)
    if kind == "inverted_limits":
        m = re.search(r"lower=\"([^\"]*)\"\s+upper=\"([^\"]*)\"", text)
        if not m or "<limit" not in text[max(0, m.start() - 40):m.start()]:
            return "skip", text
        lo, hi = m.group(1), m.group(2)
        if float(lo) >= float(hi):
            return "skip", text
        return kind, text[:m.start()] + f'lower="{hi}" upper="{lo}"' + text[m.end():]
    return "skip", text


def mutate_toml(text: str, rng: random.Random) -> tuple[str, str]:
    """One mutation of a TOML study: ``(kind, new_text)``."""
    lines = text.splitlines()
    keyed = [i for i, line in enumerate(lines) if re.match(r"^\s*[A-Za-z_]\w*\s*=", line)]
    kind = rng.choice(["misspelt_toml_key", "misspelt_toml_key", "toml_wrong_type",
                       "toml_wrong_type", "toml_value", "deleted_key", "truncated",
                       "random_bytes", "misspelt_inline_key"])
    if kind == "misspelt_toml_key":
        i = rng.choice(keyed)
        key = re.match(r"^\s*([A-Za-z_]\w*)", lines[i]).group(1)
        from pinflex.assignment.study_schema import STUDY

        valid = set(STUDY)
        for k in STUDY.values():
            valid |= set(k.keys)
            for sub in k.keys.values():
                valid |= set(sub.keys)
        bad = misspell(key, rng, valid)
        if bad is None:
            return "skip", text
        lines[i] = lines[i].replace(key, bad, 1)
        return kind, "\n".join(lines) + "\n"
    if kind == "misspelt_inline_key":
        m = list(re.finditer(r"\{\s*(\w+)\s*=", text))
        if not m:
            return "skip", text
        a = rng.choice(m)
        # design names inside inline tables: a misspelt design name must be refused
        bad = misspell(a.group(1), rng, {"m1", "m2", "m3", "payload", "tool"})
        if bad is None:
            return "skip", text
        return "misspelt_toml_key", text[:a.start(1)] + bad + text[a.end(1):]
    if kind in ("toml_wrong_type", "toml_value"):
        i = rng.choice(keyed)
        key, value = lines[i].split("=", 1)
        value = value.strip()
        if kind == "toml_wrong_type":
            if value in ("true", "false"):
                new = rng.choice(['"no"', '"yes"', "1", "0", '"true"'])
            elif re.fullmatch(r"-?\d+", value):
                new = rng.choice(["1.7", '"4"', "true", "[4]"])
            elif re.fullmatch(r"-?[\d.]+(e-?\d+)?", value):
                new = rng.choice(['"190"', "true", "{ a = 1 }", '""'])
            elif value.startswith('"'):
                new = rng.choice(["1", "true", "[1]"])
            else:
                return "skip", text
        else:
            new = rng.choice(["nan", "inf", "-inf", "-1", "0", "1e300", "-1e-300", "1e12"])
        lines[i] = f"{key}= {new}"
        return kind, "\n".join(lines) + "\n"
    if kind == "deleted_key":
        del lines[rng.choice(keyed)]
        return kind, "\n".join(lines) + "\n"
    if kind == "truncated":
        return kind, text[: rng.randrange(1, len(text))]
    data = bytearray(text.encode())
    for _ in range(rng.randint(1, 8)):
        data[rng.randrange(len(data))] = rng.randrange(256)
    return "random_bytes", bytes(data)  # type: ignore[return-value]


def _load_xml(path: Path, index: int):
    from pinflex.erls import FlexibleModel

    desc = load(path)
    if index % 10:
        return
    model = FlexibleModel(desc)
    if index % 50 == 0 and model.nx:
        import numpy as np

        model.frequencies(np.zeros(model.nv), n_modes=min(3, model.nx))


def _load_toml(path: Path, index: int):
    from pinflex.assignment.study import load_config

    load_config(path)


def run(n_variants: int = 1000, seed: int = 20261201) -> dict:
    """Fuzz ``n_variants`` variants; return the counts (see the module docstring)."""
    rng = random.Random(seed)
    sources = [(p, p.read_text(), mutate_xml, _load_xml) for p in URDFS]
    sources += [(p, p.read_text(), mutate_toml, _load_toml) for p in STUDIES]
    counts: Counter = Counter()
    by_kind: dict[str, Counter] = {}
    foreign: list[str] = []
    silent: list[str] = []
    t0 = time.perf_counter()
    shm = Path("/dev/shm")
    with tempfile.TemporaryDirectory(dir=shm if shm.is_dir() else None) as tmp:
        made = 0
        attempts = 0
        while made < n_variants and attempts < 20 * n_variants:
            attempts += 1
            src, text, mutate, loader = sources[made % len(sources)]
            kind, new = mutate(text, rng)
            if kind == "skip" or new == text:
                continue
            made += 1
            path = Path(tmp) / f"v{made}{src.suffix}"
            if isinstance(new, bytes):
                path.write_bytes(new)
            else:
                path.write_text(new)
            stats = by_kind.setdefault(kind, Counter())
            stats["variants"] += 1
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    loader(path, made)
            except PinflexError:
                stats["refused"] += 1
                counts["refused"] += 1
            except Exception as exc:  # noqa: BLE001 - counting foreign exceptions is the point
                stats["foreign"] += 1
                counts["foreign"] += 1
                foreign.append(f"{src.name} {kind}: {type(exc).__name__}: {exc}"[:300])
            else:
                stats["accepted"] += 1
                counts["accepted"] += 1
                if kind in MUST_REFUSE:
                    silent.append(f"{src.name} {kind}")
            counts["variants"] += 1
    return {
        "seed": seed,
        "variants": counts["variants"],
        "refused": counts["refused"],
        "accepted": counts["accepted"],
        "foreign": counts["foreign"],
        "silent_acceptances": len(silent),
        "misspellings": sum(by_kind.get(k, Counter())["variants"]
                            for k in ("misspelt_element", "misspelt_attribute",
                                      "misspelt_toml_key")),
        "by_kind": {k: dict(v) for k, v in sorted(by_kind.items())},
        "foreign_examples": foreign[:10],
        "silent_examples": silent[:10],
        "seconds": round(time.perf_counter() - t0, 2),
    }


# ======================================================================== further families
_WEIRD_DIGITS = [("\u0660\u0661\u0662\u0663\u0664\u0665\u0666\u0667\u0668\u0669", "arabic"),
                 ("\uff10\uff11\uff12\uff13\uff14\uff15\uff16\uff17\uff18\uff19",
                  "fullwidth"),
                 ("\u0966\u0967\u0968\u0969\u096a\u096b\u096c\u096d\u096e\u096f",
                  "devanagari")]
_PLAIN_NUMBER = re.compile(r'(\b(?:value|ixx|ixy|ixz|iyy|iyz|izz|lower|upper|effort|velocity|'
                           r'mass|E|G|A|Iy|Iz|J|density|linear_density|diameter|'
                           r'outer_diameter|inner_diameter|width|height|elements|stiffness|'
                           r'xyz|rpy|tip|normal)=")([^"{}]*[0-9][^"{}]*)(")')


def _unicode_digits(text: str, rng: random.Random) -> tuple[str, str]:
    hits = list(_PLAIN_NUMBER.finditer(text))
    if not hits:
        return "skip", text
    m = rng.choice(hits)
    value = m.group(2)
    how = rng.choice(["digits", "digits", "nbsp", "thin", "separator"])
    if how == "digits":
        table, _ = rng.choice(_WEIRD_DIGITS)
        spots = [i for i, c in enumerate(value) if c.isdigit()]
        i = rng.choice(spots)
        value = value[:i] + table[int(value[i])] + value[i + 1:]
    elif how in ("nbsp", "thin"):
        value = ("\u00a0" if how == "nbsp" else "\u2009") + value
    else:
        spots = [i for i in range(1, len(value)) if value[i - 1].isdigit() and value[i].isdigit()]
        if not spots:
            return "skip", text
        i = rng.choice(spots)
        value = value[:i] + "_" + value[i:]
    return "unicode_digits", text[:m.start(2)] + value + text[m.end(2):]


_REF_VALUES = ["-1", "0", "1e300", "1e-300", "70", "5000", "0.5", "120", "1e12", "2.5", "3"]


def _parameter_reference(text: str, rng: random.Random) -> tuple[str, str, str] | None:
    """``(literal_text, reference_text, attribute)``: the same value as literal and as {p}."""
    tags = [t for t in _tags(text) if t.group(1) in _NUMERIC and t.group(1) != "parameter"]
    if not tags:
        return None
    tag = rng.choice(tags)
    attrs = [a for a in _ATTR.finditer(tag.group(2)) if a.group(1) in _NUMERIC[tag.group(1)]
             and SCHEMA[tag.group(1)].attrs[a.group(1)].kind != "vec3"
             and "{" not in a.group(2)]
    if not attrs:
        return None
    a = rng.choice(attrs)
    value = rng.choice(_REF_VALUES + [a.group(2)])
    s, e = tag.start(2) + a.start(2), tag.start(2) + a.end(2)
    literal = text[:s] + value + text[e:]
    ref = text[:s] + "{fuzz_p}" + text[e:]
    decl = f'<pinflex:parameter name="fuzz_p" value="{value}"/>'
    close = "</robot>" if "</robot>" in ref else "</pinflex:overlay>"
    j = ref.rfind(close)
    if j < 0:
        return None
    ref = ref[:j] + decl + "\n" + ref[j:]
    return literal, ref, f"{tag.group(1)}.{a.group(1)}={value}"


_SIM_BAD = {
    "sample_hz": [1e12, 0.0, -5.0, "nan", "true", '"5000"'], "after_s": [1e6, 0.0, "inf", "-1.0"],
    "tol": [1e-16, 0.0, 1.0, "nan"], "rtol": [0.0, 2.0], "atol": [0.0, 5.0],
    "rho_inf": [-0.1, 1.5], "step_s": [0.0, 10.0], "kp": [-1.0, 1e15], "kd": [-1.0],
    "gravity": ["[0, -1e300, 0]", "[0, 0]", "[0, nan, 0]", '"down"'],
    "point": ["[1e9, 0, 0]", "[0, 0]"], "drive": ['"fly"', "1"], "frame": ["1", '""'],
    "damping": ['"rayleigh"', "{ kind = \"modal\" }", "{ kind = \"rayleigh\", beta = -1.0 }",
                "{ kind = \"modal\", ratios = [1.5] }"],
    "sampel_hz": [10.0],
}
_SIM_GOOD = {"sample_hz": [1000.0, 20000.0], "after_s": [0.1, 2.0], "tol": [1e-3, 1e-6],
             "gravity": ["[0, -9.81, 0]"], "drive": ['"prescribed"'], "frame": ['"link2"'],
             "damping": ['"none"', "{ kind = \"rayleigh\", alpha = 0.1, beta = 1e-5 }"]}
_SIM_BASE = ('robot = "builtin:two_link.urdf"\nplanar = true\n[trajectory]\n'
             'builtin = "benchmark_a"\n[[targets]]\nmode = 1\nfreq_hz = 190.0\n[simulation]\n')


def _api_calls(rng: random.Random):
    """``(label, call)`` pairs: a public function with one argument of a wrong type/value."""
    import numpy as np

    from pinflex import Material
    from pinflex.erls import FlexibleModel

    bad = [None, "1.0", "\u0661", True, 1 + 2j, [1, "a"], [[1, 2], [3]], float("nan"),
           float("inf"), np.ma.array([1.0, 2.0], mask=[0, 1]), np.array([True, False]),
           np.array([1 + 1j, 2.0]), {"a": 1}, object()]
    model = _model()
    tm = _taylor()
    q = np.array([1.8, 5.3])
    calls = [
        ("FlexibleModel(path)", lambda v: FlexibleModel(v)),
        ("FlexibleModel(values)", lambda v: FlexibleModel(TWO_LINK, values={"m1": v})),
        ("FlexibleModel(joints)", lambda v: FlexibleModel(TWO_LINK, joints={"q1": v})),
        ("FlexibleModel(planar)", lambda v: FlexibleModel(TWO_LINK, planar=v)),
        ("frequencies(q)", lambda v: model.frequencies(v)),
        ("frequencies(y)", lambda v: model.frequencies(q, v)),
        ("frequencies(n_modes)", lambda v: model.frequencies(q, n_modes=v)),
        ("modes(q)", lambda v: model.modes(v)),
        ("evaluate(Q)", lambda v: tm.evaluate(v)),
        ("evaluate(linear_in_design)", lambda v: tm.evaluate(q, linear_in_design=v)),
        ("evaluate(tol)", lambda v: tm.evaluate(q, tol=v)),
        ("Material(E)", lambda v: Material(E=v, density=2700.0)),
        ("Material(density)", lambda v: Material(E=7e10, density=v)),
        ("Trajectory(q)", lambda v: _trajectory(v)),
        ("linear_model(zeta)", lambda v: _export(model, zeta=v)),
        ("linear_model(rayleigh)", lambda v: _export(model, rayleigh=(v, 0.0))),
        ("ErlsDynamics(gravity)", lambda v: _dynamics(model, gravity=[0.0, v, 0.0])),
        ("simulate_prescribed(damping)", lambda v: _simulate(model, damping=v)),
        ("Beam(elements)", lambda v: _beam(elements=v)),
        ("Beam(tip)", lambda v: _beam(tip=(v, 0.0, 0.0))),
        ("Mass(mass)", lambda v: _mass(v)),
        ("Mass(xyz)", lambda v: _mass(0.1, xyz=(0.0, v, 0.0))),
        ("Mass(design)", lambda v: _mass(0.1, design=v)),
        ("with_values(m1)", lambda v: model.with_values(m1=v)),
        ("expand(order)", lambda v: _expand(model, order=v)),
        ("expand(q0)", lambda v: _expand(model, q0=[v, 5.3])),
        ("Trajectory(times)", lambda v: _trajectory_times(v)),
        ("Trajectory(name)", lambda v: _trajectory_kw(name=v)),
        ("Trajectory(joint_names)", lambda v: _trajectory_kw(joint_names=v)),
        ("check_limits(on_violation)", lambda v: _trajectory_kw().check_limits(
            -1.0, 1.0, on_violation=v)),
        ("evaluate(quantity)", lambda v: tm.evaluate(q, quantity=v)),
        ("example_robot(name)", lambda v: _example_robot(v)),
        ("assign_frequencies(targets)", lambda v: _assign(model, v)),
        ("simulate_torque(kp)", lambda v: _torque(model, kp=v)),
        ("simulate_torque(duration_s)", lambda v: _torque(model, duration_s=v)),
        ("FlexibleModel(coordinates)", lambda v: FlexibleModel(TWO_LINK, coordinates=v)),
    ]
    legit = {"frequencies(y)": (None,), "evaluate(linear_in_design)": (True,),
             "Mass(design)": (True,), "evaluate(tol)": (float("inf"),),  # inf: no check
             "Trajectory(name)": (None, "1.0", "\u0661"), "FlexibleModel(coordinates)": (None,),
             "frequencies(n_modes)": (None,),
             "FlexibleModel(planar)": (True,), "simulate_prescribed(damping)": (None,)}
    for label, call in calls:
        v = rng.choice([b for b in bad if not any(
            b is ok or (type(b) is float and b == ok) for ok in legit.get(label, ()))])
        yield f"{label} <- {type(v).__name__} {str(v)[:20]!r}", (lambda c=call, x=v: c(x))


TWO_LINK = ROOT / "urdf" / "two_link.urdf"
_CACHE: dict = {}


def _model_of(path):
    from pinflex.erls import FlexibleModel

    model = FlexibleModel(path, planar=True)
    model.frequencies([1.8, 5.3], n_modes=2)
    return model


def _model():
    if "model" not in _CACHE:
        from pinflex.erls import FlexibleModel

        _CACHE["model"] = FlexibleModel(TWO_LINK, planar=True)
    return _CACHE["model"]


def _taylor():
    if "taylor" not in _CACHE:
        from pinflex.parametric import expand

        _CACHE["taylor"] = expand(_model(), [1.8, 5.3], order=2, modes=[1])
    return _CACHE["taylor"]


def _trajectory(v):
    from pinflex.trajectory import Trajectory

    return Trajectory([0.0, 1.0], [[0.0, v], [0.0, 0.0]])


def _beam(**kwargs):
    from pinflex import Beam, Material
    from pinflex.beam import solid_circle

    return Beam(solid_circle(0.03), Material(E=69e9, linear_density=1.9),
                **kwargs).element("link1")


def _mass(mass, **kwargs):
    from pinflex import Mass

    return Mass("link1", mass, **kwargs).element("m9")


def _expand(model, order=1, q0=(1.8, 5.3)):
    from pinflex.parametric import expand

    return expand(model, q0, order=order, modes=[1])


def _trajectory_kw(**kwargs):
    from pinflex.trajectory import Trajectory

    return Trajectory([0.0, 1.0], [[0.0, 0.0], [0.0, 0.0]], **kwargs)


def _example_robot(name):
    from pinflex.native.robots import example_robot_urdf

    return example_robot_urdf(name)


def _assign(model, targets):
    from pinflex.assignment.driver import assign_frequencies
    from pinflex.trajectory import Trajectory

    traj = Trajectory([0.0, 0.01], [[1.8, 5.3], [1.8, 5.3]], model.joint_names)
    return assign_frequencies(model, traj, targets)


def _torque(model, kp=0.0, duration_s=0.001):
    from pinflex.dynamics.simulate import simulate_torque

    return simulate_torque(_dynamics(model), q0=[1.8, 5.3], duration_s=duration_s, kp=kp,
                           sample_hz=1000.0)


def _trajectory_times(v):
    from pinflex.trajectory import Trajectory

    return Trajectory([0.0, v], [[0.0, 0.0], [0.0, 0.0]])


def _export(model, **kwargs):
    from pinflex.native.export import linear_model

    return linear_model(model, [1.8, 5.3], **kwargs)


def _dynamics(model, **kwargs):
    from pinflex.dynamics.terms import ErlsDynamics

    return ErlsDynamics(model, **kwargs)


def _simulate(model, **kwargs):
    from pinflex.dynamics.simulate import simulate_prescribed
    from pinflex.trajectory import Trajectory

    traj = Trajectory([0.0, 0.01], [[1.8, 5.3], [1.8, 5.3]], model.joint_names)
    return simulate_prescribed(_dynamics(model), traj, after_s=0.001, sample_hz=1000.0, **kwargs)


def _trajectory_csv(rng: random.Random, times, q) -> tuple[str, str, object]:
    """``(kind, csv_text, expected)``: expected is the (ns, 2) samples or None (refuse)."""
    names = ["q1", "q2"]
    kind = rng.choice(["permuted", "permuted", "unknown", "missing", "duplicate", "extra",
                       "misspelt", "cell_digits", "cell_separator", "cell_nan", "cell_empty",
                       "ragged", "no_header", "time_not_first", "cell_huge", "time_huge",
                       "time_back", "semicolons", "crlf"])
    header = ["t", *names]
    cols = [[repr(float(v)) for v in times], *[[repr(float(v)) for v in q[:, j]] for j in range(2)]]
    expected = q
    if kind == "permuted":
        order = [0, 2, 1] if rng.random() < 0.5 else [0, 1, 2]
        header = [header[k] for k in order]
        cols = [cols[k] for k in order]
    elif kind == "unknown":
        header[rng.choice([1, 2])] = rng.choice(["a", "joint", "q3", "Q1", "t2"])
        expected = None
    elif kind == "missing":
        k = rng.choice([1, 2])
        del header[k], cols[k]
        expected = None
    elif kind == "duplicate":
        header[2] = header[1]
        expected = None
    elif kind == "extra":
        header.append(rng.choice(["q3", "q1", "x"]))
        cols.append(["0.0"] * len(times))
        expected = None
    elif kind == "misspelt":
        header[1] = rng.choice(["q 1", "q1 ", "ｑ1", "q_1"])
        expected = None if header[1].strip(" \t") != "q1" else q
    elif kind.startswith("cell_"):
        i, j = rng.randrange(len(times)), rng.choice([1, 2])
        cell = cols[j][i]
        if kind == "cell_digits":
            table, _ = rng.choice(_WEIRD_DIGITS)
            k = next((n for n, c in enumerate(cell) if c.isdigit()), None)
            if k is None:
                return "skip", "", None
            cell = cell[:k] + table[int(cell[k])] + cell[k + 1:]
        elif kind == "cell_separator":
            cell = "1_0"
        elif kind == "cell_nan":
            cell = rng.choice(["nan", "inf", "-inf", "1e400"])
        elif kind == "cell_huge":
            cell = rng.choice(["1e300", "-2e6", "1e7"])
        else:
            cell = ""
        cols[j][i] = cell
        expected = None
    elif kind == "time_huge":
        cols[0][-1] = rng.choice(["1e300", "2e9"])
        expected = None
    elif kind == "time_back":
        i = rng.randrange(1, len(times))
        cols[0][i] = cols[0][i - 1]
        expected = None
    elif kind == "ragged":
        cols[1] = cols[1][:-1]
        expected = None
    elif kind == "no_header":
        header = []
        expected = None
    elif kind == "time_not_first":
        header = [header[1], header[0], header[2]]
        cols = [cols[1], cols[0], cols[2]]
        expected = None
    sep, end = ("\t" if kind == "semicolons" and rng.random() < 0.5 else
                ";" if kind == "semicolons" else ","), "\r\n" if kind == "crlf" else "\n"
    if kind == "semicolons":
        expected = None
    rows = [sep.join(header)] if header else []
    n = max(len(c) for c in cols)
    for i in range(n):
        rows.append(sep.join(c[i] for c in cols if i < len(c)))
    return "trajectory_" + kind, end.join(rows) + end, expected


_CLI_CASES = [
    ["modes", "{urdf}", "--planar", "--q", "{num}", "0"],
    ["modes", "{urdf}", "--planar", "--modes", "{num}"],
    ["modes", "{urdf}", "--planar", "--set", "m1={num}"],
    ["modes", "{urdf}", "--planar", "--tol", "{num}"],
    ["export", "{urdf}", "--planar", "--zeta", "{num}", "--out", "{tmp}/e.npz"],
    ["export", "{urdf}", "--planar", "--rayleigh", "{num}", "0", "--out", "{tmp}/e.npz"],
    ["view", "{urdf}", "--planar", "--amplitude", "{num}", "--html", "{tmp}/v.html"],
    ["view", "{urdf}", "--planar", "--mode", "{num}", "--html", "{tmp}/v.html"],
    ["modes", "{long}"],
    ["modes", "{urdf}", "--planar", "--trajectory", "{long}"],
    ["export", "{urdf}", "--planar", "--out", "{tmp}/file/e.npz"],
    ["assign", "{long}"],
    ["batch", "report", "{tmp}/file/s.db"],
]
_CLI_NUMBERS = ["nan", "inf", "1_0", "\u0661", "\uff12", "\u00a01", "0x10", "abc", "",
                "-1", "1e400", "2.5"]


def _cli_argv(rng: random.Random, tmp: Path) -> list[str]:
    fixed = rng.random() < 0.4
    case = rng.choice(_CLI_FIXED if fixed else _CLI_CASES)
    num = rng.choice(_CLI_NUMBERS)
    long = str(tmp / ("x" * 300))
    return [w.format(urdf=str(TWO_LINK), num=num, tmp=str(tmp), long=long,
                     csv=str(tmp / "t.csv"), study=str(ROOT / "examples" / "benchmark_a.toml"))
            for w in case]


_URDF_STRUCTURE = [
    ("duplicate link", lambda t: t.replace('<link name="tool"/>',
                                            '<link name="tool"/><link name="tool"/>', 1)),
    ("two parents", lambda t: t.replace('<child link="tool"/>', '<child link="link2"/>', 1)),
    ("floating joint", lambda t: t.replace('type="revolute"', 'type="floating"', 1)),
    ("planar joint", lambda t: t.replace('type="revolute"', 'type="planar"', 1)),
    ("continuous joint", lambda t: t.replace('type="revolute"', 'type="continuous"', 1)),
    ("zero axis", lambda t: t.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', 1)),
    ("nan axis", lambda t: t.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 nan 1"/>', 1)),
    ("long axis", lambda t: t.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1e300"/>', 1)),
    ("no root", lambda t: t.replace('<parent link="base"/>', '<parent link="tool"/>', 1)),
    ("flexible root", lambda t: t.replace('<pinflex:flexible link="link1"',
                                           '<pinflex:flexible link="base"', 1)),
    ("flexible twice", lambda t: t.replace('<pinflex:flexible link="link2"',
                                            '<pinflex:flexible link="link1"', 1)),
    ("point mass on no link", lambda t: t.replace('link="link1" xyz="0.6 0 0"',
                                                   'link="nolink" xyz="0.6 0 0"', 1)),
    ("mass 1e300", lambda t: t.replace('<mass value="0.855"/>', '<mass value="1e300"/>', 1)),
    ("inertia -1", lambda t: t.replace('izz="0.01443"', 'izz="-1"', 1)),
    ("rpy 1e300", lambda t: t.replace('<origin xyz="0.6 0 0"/>',
                                       '<origin xyz="0.6 0 0" rpy="0 0 1e300"/>', 1)),
    ("limit nan", lambda t: t.replace('lower="-6.2832"', 'lower="nan"', 1)),
    ("tip zero", lambda t: t.replace('elements="4" normal="0 0 1"',
                                      'elements="4" tip="0 0 0" normal="0 0 1"', 1)),
    ("normal along beam", lambda t: t.replace('elements="4" normal="0 0 1"',
                                               'elements="4" normal="1 0 0"', 1)),
    ("pinflex joint on fixed", lambda t: t.replace(
        '<pinflex:coordinates', '<pinflex:joint name="tool_joint" stiffness="10"/>\n'
        '<pinflex:coordinates', 1)),
    ("spring and lock", lambda t: t.replace(
        '<pinflex:coordinates', '<pinflex:joint name="q2" stiffness="10" locked="true"/>\n'
        '<pinflex:coordinates', 1)),
    ("spring 1e300", lambda t: t.replace(
        '<pinflex:coordinates', '<pinflex:joint name="q2" stiffness="1e300"/>\n'
        '<pinflex:coordinates', 1)),
    ("two coordinates", lambda t: t.replace(
        '<pinflex:coordinates convention="absolute"/>',
        '<pinflex:coordinates convention="absolute"/><pinflex:coordinates '
        'convention="relative"/>', 1)),
    ("empty robot", lambda t: '<robot name="x" xmlns:pinflex="urn:pinflex:urdf:1"/>'),
    ("entity", lambda t: '<!DOCTYPE r [<!ENTITY a "aaaa">]>' + t),
    ("deep nesting", lambda t: t.replace("<link name=\"tool\"/>",
                                          "<link name=\"tool\">" + "<visual>" * 500
                                          + "</visual>" * 500 + "</link>", 1)),
    ("indefinite inertia", lambda t: _tool_inertia(t, 'iyz="0.5"')),
    ("negative principal inertia", lambda t: _tool_inertia(t, 'iyz="0" ixx="-1e-3"')),
    ("text in annotation", lambda t: t.replace(
        '<pinflex:coordinates convention="absolute"/>',
        '<pinflex:coordinates convention="absolute">relative</pinflex:coordinates>', 1)),
    ("CDATA in annotation", lambda t: t.replace(
        '<pinflex:material E="69e9" linear_density="1.9"/>',
        '<pinflex:material E="69e9" linear_density="1.9"><![CDATA[2700]]></pinflex:material>',
        1)),
    ("prismatic joint", lambda t: t.replace('type="revolute"', 'type="prismatic"', 1)),
    ("no limit", lambda t: t.replace(
        '<limit lower="-6.2832" upper="6.2832" effort="100" velocity="10"/>', "", 1)),
    ("limit text", lambda t: t.replace('lower="-6.2832"', 'lower="-6.2832 rad"', 1)),
    ("origin tabs", lambda t: t.replace('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6\t0\t0"/>',
                                         1)),
    ("mass entity digit", lambda t: t.replace('<mass value="0.855"/>',
                                               '<mass value="0.&#1637;55"/>', 1)),
    ("empty joint name", lambda t: t.replace('name="q2"', 'name=""', 1)),
    ("parameter cycle", lambda t: t.replace(
        "</robot>", '<pinflex:parameter name="a" value="{b}"/>'
        '<pinflex:parameter name="b" value="{a}"/></robot>', 1)),
    ("parameter in plain URDF", lambda t: t.replace('<mass value="0.855"/>',
                                                     '<mass value="{mm}"/>', 1).replace(
        "</robot>", '<pinflex:parameter name="mm" value="0.855"/></robot>', 1)),
    ("namespace version 2", lambda t: t.replace("urn:pinflex:urdf:1", "urn:pinflex:urdf:2")),
    ("two robots", lambda t: t + t),
]

#: Structural variants that are valid (loaded, possibly with a warning).
_URDF_STRUCTURE_VALID = {"continuous joint", "long axis", "inertia triangle",
                         "namespace alias", "mass far beyond the beam"}

_URDF_STRUCTURE += [
    ("inertia triangle", lambda t: _tool_inertia(t, 'ixx="1"')),
    ("namespace alias", lambda t: t.replace(
        'xmlns:pinflex=', 'xmlns:pf="urn:pinflex:urdf:1" xmlns:pinflex=', 1).replace(
        "<pinflex:coordinates", "<pf:coordinates", 1)),
    ("mass far beyond the beam", lambda t: t.replace('link="link1" xyz="0.6 0 0"',
                                                      'link="link1" xyz="6 0 0"', 1)),
]


def _tool_inertia(text: str, change: str) -> str:
    """The two-link arm with an inertia on its (rigid, moving) tool link, one entry changed."""
    attrs = {"ixx": "1e-3", "ixy": "0", "ixz": "0", "iyy": "1e-3", "iyz": "0", "izz": "1e-3"}
    for key, value in re.findall(r'(\w+)="([^"]*)"', change):
        attrs[key] = value
    inertia = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return text.replace('<link name="tool"/>', '<link name="tool"><inertial><mass value="0.5"/>'
                        f'<inertia {inertia}/></inertial></link>', 1)

_BASES = ["../two_link.urdf", "/etc/hostname", "file:///etc/hostname", "", "sub",
          "example-robot-data:../../../../etc/hostname", "example-robot-data:nothing.urdf",
          "example-robot-data:ur_description/urdf/ur5_robot.urdf", "x" * 400, "two_link.urdf",
          "bin.urdf"]


def _overlay_base(rng: random.Random, folder: Path) -> tuple[str, Path, bool]:
    """``(label, overlay path, must_refuse)``: an overlay whose base tests confinement."""
    base = rng.choice(_BASES)
    inner = folder / "inner"
    (inner / "sub").mkdir(parents=True, exist_ok=True)
    (inner / "two_link.urdf").write_text(TWO_LINK.read_text())
    (folder / "two_link.urdf").write_text(TWO_LINK.read_text())
    (inner / "bin.urdf").write_bytes(b"\x00\x01" * 10)
    flex = ('<pinflex:flexible link="link1" elements="2" normal="0 0 1">'
            '<pinflex:material E="69e9" linear_density="1.9"/>'
            '<pinflex:section A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"/>'
            '</pinflex:flexible>')
    if "ur5" in base:
        flex = flex.replace("link1", "upper_arm_link").replace('normal="0 0 1"', "")
    path = inner / "o.xml"
    path.write_text(f'<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" base="{base}">'
                    f"{flex}</pinflex:overlay>")
    ok = base in ("two_link.urdf", "example-robot-data:ur_description/urdf/ur5_robot.urdf")
    return f"base={base[:40]!r}", path, not ok


_SWEEPS = ["targets.0.freq_hz=185,1_0", "targets.0.freq_hz=nan", "expansion.y0.m9=0.1",
           "expansion.y0.m1=0.3", "options.baseline.mx=0.0", "values.nope=1.0",
           "targets.0.mode=99", "targets.5.freq_hz=190", "expansion.order=40",
           "expansion.order=2.5", "planar=maybe", "joints=stiff", "expansion.q0=[1.0]",
           "constraints.mass_budget_kg=\u0661", "targets.0.freq_hz=190,190",
           "expansion.quantity=hz", "robot=builtin:nothing.urdf"]


#: One change of examples/benchmark_a.toml each: ``(label, old, new)``; all must be refused.
_STUDY_CHANGES = [
    ("order as date", "order = 4", "order = 1979-05-27"),
    ("order huge", "order = 4", "order = 99999999999999999999999"),
    ("order float", "order = 4", "order = 4.0"),
    ("nested arrays", "order = 4", "order = 4\nx = " + "[" * 3000 + "]" * 3000),
    ("targets as table", "[[targets]]", "[targets]"),
    ("mode as bool", "mode = 1", "mode = true"),
    ("mode huge", "mode = 1", "mode = 1000000000"),
    ("freq as string", "freq_hz = 190.0", 'freq_hz = "190"'),
    ("freq nested", "freq_hz = 190.0", "freq_hz = [[190.0]]"),
    ("freq empty list", "freq_hz = 190.0", "freq_hz = []"),
    ("freq 1e30", "freq_hz = 190.0", "freq_hz = 1e30"),
    ("weight inf", "freq_hz = 190.0", "freq_hz = 190.0\nweight = inf"),
    ("q0 three values", "q0 = [1.817, 5.312]", "q0 = [1.817, 5.312, 0.0]"),
    ("q0 1e300", "q0 = [1.817, 5.312]", "q0 = [1e300, 5.312]"),
    ("y0 unknown", "m2 = 0.125 }", "m3 = 0.125 }"),
    ("y0 above bound", "y0 = { m1 = 0.125", "y0 = { m1 = 5.0"),
    ("quantity", 'quantity = "freq_hz"', 'quantity = "hz"'),
    ("robot empty", 'robot = "builtin:two_link.urdf"', 'robot = ""'),
    ("robot folder", 'robot = "builtin:two_link.urdf"', 'robot = "."'),
    ("robot device", 'robot = "builtin:two_link.urdf"', 'robot = "/dev/zero"'),
    ("robot number", 'robot = "builtin:two_link.urdf"', "robot = 5"),
    ("trajectory device", 'builtin = "benchmark_a"', 'csv = "/dev/zero"'),
    ("trajectory two sources", 'builtin = "benchmark_a"', 'builtin = "benchmark_a"\ncsv = "t.csv"'),
    ("trajectory none", 'builtin = "benchmark_a"', ""),
    ("planar string", "planar = true", 'planar = "true"'),
    ("joints table", "planar = true", 'planar = true\njoints = { q1 = "locked" }'),
    ("values nan", "planar = true", "planar = true\nvalues = { m1 = nan }"),
    ("duplicate target", "[options]", "[[targets]]\nmode = 1\nfreq_hz = 200.0\n[options]"),
    ("report mode 0", "report_modes = [2, 3, 4]", "report_modes = [0]"),
    ("max refinements huge", "report_modes = [2, 3, 4]",
     "report_modes = [2, 3, 4]\nmax_refinements = 1000000"),
    ("confirm_tol negative", "report_modes = [2, 3, 4]",
     "report_modes = [2, 3, 4]\nconfirm_tol = -1.0"),
    ("non-UTF-8", "# Paper", "# \udcff Paper"),
    ("duplicate key", "planar = true", "planar = true\nplanar = false"),
    ("hex", "order = 4", "order = 0x4"),
]


def _study_case(text: str, folder: Path, label: str, old: str, new: str):
    """A study file with one change, loaded and checked against its robot."""
    from pinflex.assignment.study import check_config, load_config

    path = folder / "s.toml"
    changed = text.replace(old, new, 1)
    path.write_bytes(changed.encode("utf-8", "surrogateescape"))
    cfg = load_config(path)
    check_config(cfg)
    return cfg


_OUTPUT_TARGETS = ["fifo", "folder", "empty", "long", "under a file", "device"]


def _output_case(kind: str, folder: Path):
    """Write a small output to a target that cannot be written as a file: OutputError."""
    import os

    from pinflex.outputs import write_text

    if kind == "fifo":
        target = folder / "pipe"
        if not target.exists():
            os.mkfifo(target)
    elif kind == "folder":
        target = folder
    elif kind == "empty":
        target = Path("")
    elif kind == "long":
        target = folder / ("x" * 300)
    elif kind == "under a file":
        (folder / "file").write_text("x")
        target = folder / "file" / "out.csv"
    else:  # a device: /dev/null exists everywhere and must never be replaced
        target = Path(os.devnull)
    write_text(target, "t,q1\n0,0\n", "CSV")


#: Command lines that must be refused (exit 2, one line) before any work.
_CLI_FIXED = [
    ["modes", "{urdf}", "--planar", "--set", "m1=0.1", "--set", "m1=0.2"],
    ["modes", "{urdf}", "--planar", "--q", "1e300", "0"],
    ["modes", "{urdf}", "--planar", "--trajectory", "{csv}", "--csv", ""],
    ["modes", "{urdf}", "--planar", "--trajectory", "{csv}", "--csv", "{tmp}/pipe"],
    ["modes", "{urdf}", "--planar", "--trajectory", "/dev/zero"],
    ["modes", "/dev/zero"],
    ["export", "{urdf}", "--planar", "--rayleigh", "0", "1e300", "--out", "{tmp}/e.npz"],
    ["export", "{urdf}", "--planar", "--out", "{tmp}/e.xyz"],
    ["view", "{urdf}", "--planar", "--modes", "100000", "--html", "{tmp}/v.html"],
    ["view", "{urdf}", "--planar", "--amplitude", "1e300", "--html", "{tmp}/v.html"],
    ["view", "{urdf}", "--planar", "--serve-seconds", "1e300", "--html", "{tmp}/v.html"],
    ["view", "{urdf}", "--planar", "--bind", "no.such.host.invalid"],
    ["path", "{urdf}", "--frame", "tool", "--through", "0.5", "0.5", "0", "--q", "1e9", "0",
     "--out", "{tmp}/p.csv"],
    ["assign", "{study}", "--target-tol", "1e300"],
    ["assign", "{study}", "--confirm-tol", "2"],
    ["assign", "/dev/zero"],
    ["size", "{study}", "--order", "99"],
    ["simulate", "{study}", "--exaggeration", "-1"],
    ["prbdm", "--starts", "1000000000"],
    ["prbdm", "--sections", "1000000000"],
    ["prbdm", "--links", "1000000"],
    ["batch", "prbdm", "--beams", "0", "--store", "{tmp}/b.db"],
    ["batch", "prbdm", "--beams", "100000000000", "--store", "{tmp}/b.db"],
    ["batch", "prbdm", "--beams", "1", "--workers", "100000", "--store", "{tmp}/b.db"],
    ["batch", "assign", "{study}", "--store", "{tmp}/a.db", "--sweep",
     "targets.0.freq_hz=" + ",".join(["190"] * 20_000)],
    ["batch", "report", "/dev/zero"],
]


def _sweep_case(option: str):
    from pinflex.batch.sweep import parse_sweeps, plan_cases

    return plan_cases(ROOT / "examples" / "benchmark_a.toml", parse_sweeps([option]))


def run_families(n_variants: int = 600, seed: int = 20261202, cli: int = 40) -> dict:
    """Fuzz the further families (see the module docstring); return the counts per family.

    ``foreign``: a non-pinflex exception, or a CLI exit status other than 0/2 or a refusal on
    more than one line; ``silent``: a wrong or unknown input accepted (or a permuted header
    read into the wrong columns, or a reference accepted where its literal is refused).
    """
    import io
    from contextlib import redirect_stderr, redirect_stdout

    import numpy as np

    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics.study import load_simulation_study
    from pinflex.trajectory import Trajectory

    rng = random.Random(seed)
    counts: dict[str, Counter] = {}
    foreign: list[str] = []
    silent: list[str] = []
    t0 = time.perf_counter()

    def outcome(family: str, kind: str, call, must_refuse: bool | None):
        stats = counts.setdefault(family, Counter())
        stats["variants"] += 1
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                value = call()
        except PinflexError:
            stats["refused"] += 1
            return "refused", None
        except Exception as exc:  # noqa: BLE001 - counting foreign exceptions is the point
            stats["foreign"] += 1
            foreign.append(f"{family} {kind}: {type(exc).__name__}: {exc}"[:300])
            return "foreign", None
        stats["accepted"] += 1
        if must_refuse:
            stats["silent"] += 1
            silent.append(f"{family} {kind}")
        return "accepted", value

    model = _model()
    full = user_trajectory(model, "benchmark_a")
    times, q = full.times_s[::10], full.q[::10]
    urdfs = [p for p in URDFS if p.suffix == ".urdf"] + [p for p in URDFS if p.suffix == ".xml"]
    texts = {p: p.read_text() for p in urdfs}
    shm = Path("/dev/shm")
    with tempfile.TemporaryDirectory(dir=shm if shm.is_dir() else None) as tmpdir:
        tmp = Path(tmpdir)
        (tmp / "file").write_text("x")
        per = max(1, n_variants // 5)
        # trajectory headers and cells
        for k in range(per):
            kind, text, expected = _trajectory_csv(rng, times, q)
            if kind == "skip":
                continue
            path = tmp / f"t{k}.csv"
            path.write_text(text, encoding="utf-8")
            status, traj = outcome("trajectory_headers", kind, lambda p=path: Trajectory.from_csv(
                p, joint_names=model.joint_names), expected is None)
            if status == "accepted" and expected is not None and not np.array_equal(
                    traj.q, expected):
                counts["trajectory_headers"]["silent"] += 1
                silent.append(f"trajectory_headers {kind}: columns read in the wrong order")
        # Unicode digits in URDF numbers
        for k in range(per):
            src = urdfs[k % len(urdfs)]
            kind, text = _unicode_digits(texts[src], rng)
            if kind == "skip":
                continue
            path = tmp / f"u{k}{src.suffix}"
            path.write_text(text, encoding="utf-8")
            outcome("unicode_digits", src.name, lambda p=path: _load_xml(p, 1), True)
        # parameter references in every numeric annotation
        for k in range(per):
            src = urdfs[k % len(urdfs)]
            made = _parameter_reference(texts[src], rng)
            if made is None:
                continue
            literal, ref, label = made
            lit_path, ref_path = tmp / f"l{k}{src.suffix}", tmp / f"r{k}{src.suffix}"
            lit_path.write_text(literal)
            ref_path.write_text(ref)
            lit, _ = outcome("parameter_reference(literal)", label,
                             lambda p=lit_path: load(p), None)
            got, _ = outcome("parameter_reference", label, lambda p=ref_path: load(p),
                             lit == "refused")
            if lit == "accepted" and got == "refused":
                counts["parameter_reference"]["refused_only_as_reference"] += 1
        # [simulation] bounds
        for k in range(per):
            key = rng.choice(sorted(_SIM_BAD))
            good = rng.random() < 0.25 and key in _SIM_GOOD
            value = rng.choice((_SIM_GOOD if good else _SIM_BAD)[key])
            path = tmp / f"s{k}.toml"
            path.write_text(_SIM_BASE + f"{key} = {value}\n")
            outcome("simulation_bounds", f"{key} = {value}",
                    lambda p=path: load_simulation_study(p), not good)
        # API types
        made = 0
        while made < per:
            for label, call in _api_calls(rng):
                outcome("api_types", label, call, True)
                made += 1
        # URDF structure
        for k in range(per // 2):
            label, change = rng.choice(_URDF_STRUCTURE)
            path = tmp / f"st{k}.urdf"
            path.write_text(change(texts[TWO_LINK]))
            status, _ = outcome("urdf_structure", label,
                                lambda p=path: _model_of(p),
                                label not in _URDF_STRUCTURE_VALID)
        # overlay bases
        for k in range(per // 4):
            label, path, refuse = _overlay_base(rng, tmp / f"ob{k}")
            outcome("overlay_base", label, lambda p=path: load(p), refuse)
        # sweeps
        for k in range(per // 4):
            option = rng.choice(_SWEEPS)
            outcome("sweep", option, lambda o=option: _sweep_case(o),
                    option != "targets.0.freq_hz=190,190")
        # study files
        study_text = (ROOT / "examples" / "benchmark_a.toml").read_text()
        for k in range(per // 4):
            label, old, new = rng.choice(_STUDY_CHANGES)
            folder = tmp / f"st{k}"
            folder.mkdir()
            outcome("study_files", label, lambda f=folder, a=old, b=new, lab=label:
                    _study_case(study_text, f, lab, a, b), True)
        # output targets
        for k in range(per // 8):
            kind = rng.choice(_OUTPUT_TARGETS)
            folder = tmp / f"out{k}"
            folder.mkdir()
            outcome("output_targets", kind, lambda f=folder, kd=kind: _output_case(kd, f),
                    True)
        # command lines
        import os

        from pinflex.cli import main as cli_main

        (tmp / "t.csv").write_text("t,q1,q2\n0,1.8,5.3\n0.1,1.81,5.31\n")
        if not (tmp / "pipe").exists():
            os.mkfifo(tmp / "pipe")

        for _ in range(cli):
            argv = _cli_argv(rng, tmp)
            err, out = io.StringIO(), io.StringIO()
            stats = counts.setdefault("cli", Counter())
            stats["variants"] += 1
            with warnings.catch_warnings(), redirect_stderr(err), redirect_stdout(out):
                warnings.simplefilter("ignore")
                try:
                    code = cli_main(argv)
                except SystemExit as exc:
                    code = exc.code if isinstance(exc.code, int) else 1
                except Exception as exc:  # noqa: BLE001
                    code = f"{type(exc).__name__}: {exc}"
            lines = [line for line in err.getvalue().splitlines() if line.strip()]
            if code == 0:
                stats["accepted"] += 1
            elif code == 2 and len(lines) == 1:
                stats["refused"] += 1
            else:
                stats["foreign"] += 1
                foreign.append(f"cli {argv[:4]}...: exit {code}, stderr {lines[:3]}"[:300])
    total = Counter()
    for c in counts.values():
        total.update(c)
    return {
        "seed": seed,
        "variants": total["variants"],
        "foreign": total["foreign"],
        "silent_acceptances": total["silent"],
        "by_family": {k: dict(v) for k, v in sorted(counts.items())},
        "foreign_examples": foreign[:10],
        "silent_examples": silent[:10],
        "seconds": round(time.perf_counter() - t0, 2),
    }


def main(argv: list[str] | None = None) -> int:
    """Print the fuzz counts."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=20261201)
    parser.add_argument("--families", type=int, default=600,
                        help="variants of the further families (0: none)")
    parser.add_argument("--cli", type=int, default=40, help="command lines fuzzed")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    out = run(args.variants, args.seed)
    if args.families:
        out["families"] = run_families(args.families, args.seed + 1, args.cli)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{out['variants']} variants (seed {out['seed']}): {out['refused']} refused, "
          f"{out['accepted']} accepted, {out['foreign']} foreign exceptions, "
          f"{out['silent_acceptances']} silent acceptances, {out['seconds']} s")
    for kind, c in out["by_kind"].items():
        print(f"  {kind:20s} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))
    for line in out["foreign_examples"] + out["silent_examples"]:
        print("  !", line)
    fam = out.get("families")
    if fam:
        print(f"further families: {fam['variants']} variants, {fam['foreign']} foreign, "
              f"{fam['silent_acceptances']} silent, {fam['seconds']} s")
        for kind, c in fam["by_family"].items():
            print(f"  {kind:30s} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))
        for line in fam["foreign_examples"] + fam["silent_examples"]:
            print("  !", line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
