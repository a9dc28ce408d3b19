"""The study files shown in the documentation are valid studies, and the shipped ones load."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "howto" / "study-files.md"


def _blocks() -> list[str]:
    return re.findall(r"```toml\n(.*?)```", PAGE.read_text(), flags=re.S)


def test_the_page_shows_studies():
    """The study-file page holds the examples the checks below read."""
    assert len(_blocks()) >= 5


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_every_study_on_the_page_passes_the_schema(index):
    """Each TOML block has no unknown key, wrong type or value out of range."""
    from pinflex.assignment.study_schema import check_study
    from pinflex.dynamics.study import parse_simulation_table

    data = tomllib.loads(_blocks()[index])
    assert check_study(data) == []
    parse_simulation_table(data.get("simulation"))


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_studies_on_shipped_robots_load_against_the_model(index, tmp_path):
    """A block naming a shipped robot and motion loads: modes and design names exist."""
    from pinflex.assignment.study import load_config

    text = _blocks()[index]
    data = tomllib.loads(text)
    if not str(data["robot"]).startswith("builtin:") or "builtin" not in data["trajectory"]:
        pytest.skip("needs files of its own (a robot or a CSV beside the study)")
    path = tmp_path / "study.toml"
    path.write_text(text)
    load_config(path)
