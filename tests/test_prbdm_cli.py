"""Tests of pinflex.cli.prbdm: the ``prbdm`` subcommand."""

import argparse
import json

import pytest

from pinflex.cli import main
from pinflex.cli import prbdm as cli


def test_add_parser_registers_prbdm_subcommand():
    """add_parser() registers 'prbdm' with its options on a foreign subparsers object."""
    parser = argparse.ArgumentParser(prog="pinflex")
    sub = parser.add_subparsers(dest="command")
    cli.add_parser(sub)
    args = parser.parse_args(["prbdm", "--beam", "random", "--seed", "3", "--links", "4",
                              "--modes", "3", "--objective", "pareto", "--json"])
    assert (args.beam, args.seed, args.links, args.modes, args.objective, args.json) == (
        "random", 3, 4, 3, "pareto", True)
    assert args.func is cli.run


def test_prbdm_json_output_reports_errors(capsys):
    """`pinflex prbdm --json` prints one JSON object whose 2R eigen fit matches both modes."""
    status = main(["prbdm", "--beam", "uniform", "--links", "2", "--objective", "eigen",
                       "--starts", "1", "--json", "--no-progress"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["eigen_error"] < 1e-8
    assert len(data["truth_hz"]) == len(data["model_hz"]) == 2
    assert data["model_hz"] == pytest.approx(data["truth_hz"], rel=1e-8)
    assert 0.0 < data["deflection_error"] < 1.0


def test_prbdm_reports_bad_input_with_exit_status(capsys):
    """More modes than joints is a user error: status 2 and one line on stderr."""
    status = main(["prbdm", "--links", "2", "--modes", "3", "--json", "--no-progress"])
    assert status == 2
    assert "modes" in capsys.readouterr().err


def test_prbdm_html_writes_an_offline_preview(tmp_path, capsys):
    """`pinflex prbdm --html FILE` writes one self-contained page and names it in the JSON."""
    import json

    page = tmp_path / "chain.html"
    code = main(["prbdm", "--beam", "random", "--seed", "2", "--links", "2", "--modes", "2",
                 "--starts", "1", "--no-progress", "--json", "--html", str(page)])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["html"] == str(page)
    text = page.read_text()
    assert len(text) > 100_000 and "<script" in text
    assert "http://" not in text.split("<script")[0]  # nothing fetched before the inlined viewer
