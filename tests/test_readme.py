"""The README's "your own arm in five minutes": its files, commands and Python, as written."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def _section() -> str:
    text = README.read_text()
    start = text.index("## Your own arm in five minutes")
    return text[start: text.index("\n## ", start + 5)]


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
