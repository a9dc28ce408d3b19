"""The walk-throughs of the README and the docs: their files, commands and Python, as written.

"Your own arm" (docs/howto/own-arm.md) and the short tour (docs/getting-started.md) are run
line by line and the numbers their prose quotes are compared with the output.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
OWN_ARM = ROOT / "docs" / "howto" / "own-arm.md"
TOUR = ROOT / "docs" / "getting-started.md"


def _section() -> str:
    return OWN_ARM.read_text()


def _readme_section(title: str) -> str | None:
    text = README.read_text()
    if title not in text:
        return None
    start = text.index(title)
    end = text.find("\n## ", start + 5)
    return text[start: end if end > 0 else None]


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", _section(), flags=re.S)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The overlay and the study, saved from the README."""
    out = tmp_path_factory.mktemp("five_minutes")
    (xml,), (toml,) = _blocks("xml"), _blocks("toml")
    (out / re.match(r"<!-- (\S+):", xml).group(1)).write_text(xml)
    (out / re.match(r"# (\S+):", toml).group(1)).write_text(toml)
    return out


def test_readme_commands_run_and_print_what_the_readme_says(folder, monkeypatch, capsys):
    """Every `pinflex ...` line exits 0; the numbers quoted in the prose are the outputs."""
    import warnings

    from pinflex.cli import main

    monkeypatch.chdir(folder)
    (bash,) = _blocks("bash")
    outputs = []
    for line in bash.strip().splitlines():
        argv = shlex.split(line)
        assert argv[0] == "pinflex"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main(argv[1:])
        out = capsys.readouterr()
        assert code == 0, (line, out.err)
        outputs.append(out.out)
    prose = _section()
    f1 = float(re.search(r"^\s+1\s+([0-9.]+)", outputs[0], flags=re.M).group(1))
    assert f"mode 1 at {f1:.2f} Hz" in prose
    before, after = map(float, re.search(r"([0-9.]+) % -> ([0-9.]+) %", outputs[3]).groups())
    assert f"({before:.1f} % -> {after:.1f} % largest error" in prose
    margin = float(re.search(r"exact slack ([0-9.]+)", outputs[3]).group(1))
    assert f"inactive with {margin:.0f} Hz to spare" in prose
    for name in ("traj.csv", "modes_along.csv", "modes_along.png", "ur10_modes.html",
                 "ur10_motion.html", "ur10_linear.npz", "ur10_assign/assignment.csv",
                 "ur10_assign/assignment.json", "ur10_assign/mode1_assignment.png"):
        assert (folder / name).is_file(), name
    data = np.load(folder / "ur10_linear.npz")
    assert data["A"].shape == (2 * 54, 2 * 54)


def test_readme_python_runs(folder, monkeypatch, capsys):
    """The Python block runs; the masses it quotes are the model's."""
    monkeypatch.chdir(folder)
    (code,) = _blocks("python")
    env: dict = {}
    exec(compile(code, "README five minutes", "exec"), env)
    arm = env["arm"]
    m = arm.effective_inertias()["upper_arm_link"].mass
    assert f"{m:.2f} kg of tube" in code
    jid = arm.model.getJointId("shoulder_lift_joint")
    assert f"URDF's {arm.model.inertias[jid].mass:.2f} kg" in code
    assert "ModalResult(4 modes" in capsys.readouterr().out


def test_readme_copy_of_the_walk_through_is_the_docs_one():
    """Where the README repeats the walk-through, its files and commands are the tested ones."""
    copy = _readme_section("## Your own arm in five minutes")
    if copy is None:
        return
    for lang in ("xml", "toml", "bash", "python"):
        assert re.findall(rf"```{lang}\n(.*?)```", copy, flags=re.S) == _blocks(lang), lang


def _tour(path: Path) -> tuple[list[str], str]:
    text = path.read_text()
    start = text.index("<!-- tour")
    block = re.search(r"```bash\n(.*?)```", text[start:], flags=re.S).group(1)
    lines = [ln.split("  #")[0].strip() for ln in block.strip().splitlines()]
    return lines, text[start:]


def _tour_python(path: Path) -> str:
    text = path.read_text()
    return re.search(r"```python\n(.*?)```", text[text.index("<!-- tour"):], flags=re.S).group(1)


def test_readme_is_short_and_opens_with_the_two_commands():
    """At most 12 KB; its first two commands install and run the demo, then the tests, and the
    second is the very line `.ci/run` runs."""
    text = README.read_text()
    assert len(text.encode()) <= 12 * 1024
    first, second = re.findall(r"```bash\n(.*?)```", text, flags=re.S)[:2]
    assert first.strip() == 'pip install -e ".[test]" && pinflex demo'
    assert second.strip() == 'pip install -e ".[test]" && pytest -q'
    ci = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert second.strip() in ci
    for phrase in ("paper 000", "paper 001", "issue ", "was ", "TODO"):
        assert phrase not in text, phrase


def test_readme_tour_is_the_tested_one():
    """The README's tour is the getting-started tour that the test above runs, line for line,
    and its Python is the getting-started Python (run below)."""
    assert _tour(README)[0] == _tour(TOUR)[0]
    assert _tour_python(README) == _tour_python(TOUR)


def test_tour_python_runs(tmp_path, monkeypatch, capsys):
    """The tour's Python block runs from the repository folder and prints the modes table."""
    monkeypatch.chdir(ROOT)
    env: dict = {}
    exec(compile(_tour_python(TOUR), "tour", "exec"), env)
    res = env["result"]
    assert res.freq_hz.shape == (4,) and np.all(np.diff(res.freq_hz) > 0)
    assert f"{res.freq_hz[0]:.2f}" in capsys.readouterr().out
    f = env["taylor"].evaluate([[1.9, 5.2]], [0.1, 0.0], quantity="freq_hz")
    exact = env["arm"].modes([1.9, 5.2], y=[0.1, 0.0], n_modes=1).freq_hz[0]
    assert abs(float(np.ravel(f)[0]) - exact) < 1e-3 * exact


def _figures_table() -> list[list[str]]:
    section = _readme_section("## How fast, how exact")
    assert section is not None
    rows = [r.strip().strip("|").split("|") for r in section.splitlines() if r.startswith("| ")]
    return [[c.strip() for c in r] for r in rows[1:]]  # without the header


def test_readme_figures_name_their_commands_and_match_the_docs():
    """Five rows; every command names a file that exists and options its script accepts; every
    figure is the one the performance, validation or examples page states with its conditions."""
    rows = _figures_table()
    assert len(rows) == 5
    pages = "".join((ROOT / "docs" / p).read_text()
                    for p in ("performance.md", "validation.md", "examples.md"))
    for _, result, command in rows:
        for figure in re.findall(r"[0-9][0-9.e-]*(?: %|×| ms)?", result):
            if figure.rstrip(".").isdigit() and len(figure) < 3:
                continue  # counts such as '24 random poses'
            assert figure in pages, (figure, result)
        for cmd in re.findall(r"`([^`]+)`", command):
            argv = shlex.split(cmd)
            assert argv[0] in ("python", "pytest", "pinflex"), cmd
            files = [a for a in argv[1:] if "/" in a]
            assert files and all((ROOT / f).is_file() for f in files), cmd
            if argv[0] == "python":
                source = (ROOT / argv[1]).read_text()
                for opt in (a for a in argv[2:] if a.startswith("--")):
                    assert f'"{opt}"' in source, (cmd, opt)


def test_readme_links_and_citation():
    """Relative links point at files of the repository; CITATION.cff carries pyproject's
    version and both papers' DOIs, as the README's references do."""
    import tomllib

    text = README.read_text()
    for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text):
        if not target.startswith("http"):
            assert (ROOT / target).exists(), target
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    cff = (ROOT / "CITATION.cff").read_text()
    assert f'version: "{version}"' in cff
    for doi in ("10.3390/app112311558", "10.1115/1.4045602"):
        assert f"doi: {doi}" in cff and f"doi.org/{doi}" in text
    assert "BSD 3-Clause License" in (ROOT / "LICENSE").read_text()


def test_tour_commands_run_and_print_what_the_prose_says(tmp_path, monkeypatch, capsys):
    """The short tour's commands exit 0 from the repository folder; its numbers are theirs."""
    import warnings

    from pinflex.cli import main

    lines, prose = _tour(TOUR)
    out_dir = tmp_path / "tour"
    out_dir.mkdir()
    monkeypatch.chdir(out_dir)
    outputs = []
    for line in lines:
        argv = shlex.split(line)
        assert argv[0] == "pinflex"
        argv = [str(ROOT / a) if (ROOT / a).is_file() and "/" in a else a for a in argv]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main(argv[1:])
        out = capsys.readouterr()
        assert code == 0, (line, out.err)
        outputs.append(out.out)
    f1 = float(re.search(r"^\s+1\s+([0-9.]+)", outputs[0], flags=re.M).group(1))
    assert f"mode 1 at {f1:.2f} Hz" in prose
    before, after = re.search(r"([0-9.]+ %) -> ([0-9.]+ %)", outputs[3]).groups()
    assert f"{before} → {after}" in prose
    peaks = re.findall(r"residual ([0-9.]+) mm", outputs[4])
    assert f"{float(peaks[0]):.3f} → {float(peaks[1]):.3f} mm" in prose
    for name in ("traj.csv", "modes_along.png", "assign/assignment.csv", "sim/assigned_series.json",
                 "modes.html"):
        assert (out_dir / name).is_file(), name
