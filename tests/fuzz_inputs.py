"""Seeded fuzzing of the shipped input files: malformed URDFs, overlays and TOML studies.

Each variant is one mutation of a shipped file (``urdf/`` and ``examples/*.toml``): a
misspelt pinflex element or attribute, a wrong namespace, a deleted attribute, a non-numeric,
NaN, infinite, negative, zero, huge or tiny value, a duplicated element, a truncated file or
random bytes. A variant is *refused* when loading it raises a :class:`PinflexError`
subclass; anything else it raises is *foreign* (a defect). Misspellings, wrong namespaces,
non-numbers and non-finite values must always be refused (a silent acceptance is a defect).
Every 10th URDF variant that loads is also built into a :class:`FlexibleModel`, and every
50th has its frequencies computed at a zero pose; a study is loaded with its robot checks.

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


def main(argv: list[str] | None = None) -> int:
    """Print the fuzz counts."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=20261201)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    out = run(args.variants, args.seed)
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
