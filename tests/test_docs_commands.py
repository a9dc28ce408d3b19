"""The command lines and Python names the docs and the README show exist in the code.

Every ``pinflex ...`` line of a ``bash`` block parses with pinflex's own parser (files need
not exist: only the arguments are checked); every ``--option`` of a ``pinflex SUBCOMMAND``
written anywhere else (synopsis blocks, inline code) is an option of that subcommand; every
dotted name ``pinflex.a.b`` the pages write resolves (a module, or an attribute of one).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import re
import shlex
from pathlib import Path

import pytest

from pinflex.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]


def _lines(text: str, lang_pattern: str) -> list[str]:
    out = []
    for block in re.findall(rf"```{lang_pattern}\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.strip().removeprefix("$ ")
            if line.startswith("pinflex "):
                out.append(re.split(r"\s+#|\s\|\s|\s>\s|\s&&\s", line)[0].strip())
    return out


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _command(argv: list[str]) -> argparse.ArgumentParser:
    """The (sub)parser a command line addresses: ``pinflex batch prbdm ...`` -> batch prbdm."""
    parser = build_parser()
    for word in argv[1:]:
        subs = _subparsers(parser)
        if word not in subs:
            break
        parser = subs[word]
    return parser


def _options(parser: argparse.ArgumentParser) -> set[str]:
    return {o for a in parser._actions for o in a.option_strings}


def test_bash_blocks_parse():
    """Every `pinflex` line in a bash block is accepted by the parser (status 0)."""
    checked = 0
    for page in PAGES:
        for line in _lines(page.read_text(), "bash"):
            if "..." in line:
                continue
            err = io.StringIO()
            try:
                with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                    build_parser().parse_args(shlex.split(line)[1:])
            except SystemExit as stop:
                assert not stop.code, (page.relative_to(ROOT), line, err.getvalue())
            checked += 1
    assert checked >= 20


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_options_named_in_the_docs_exist(page):
    """Every --option shown after `pinflex SUBCOMMAND` (inline or in any block) is one of its
    options."""
    text = page.read_text()
    spans = re.findall(r"`(pinflex [^`\n]+)`", text) + _lines(text, "[a-z]*")
    for span in spans:
        words = span.replace("[", " ").replace("]", " ").replace("|", " ").split()
        parser = _command(words)
        known = _options(parser)
        for opt in (w.split("=")[0] for w in words if w.startswith("--")):
            assert opt in known, (page.relative_to(ROOT), span, opt)


# written as examples of a rule or as package data, not importable names
NOT_NAMES = {"pinflex.other", "pinflex.urdf"}


def _resolves(name: str) -> bool:
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            if not hasattr(obj, part):
                return False
            obj = getattr(obj, part)
        return True
    return False


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_python_names_in_the_docs_resolve(page):
    """Every `pinflex.module.name` on the page is a module of pinflex or an attribute of one
    (a moved or renamed function fails here and in the site's --strict build)."""
    names = set(re.findall(r"\b(pinflex(?:\.[A-Za-z_][A-Za-z0-9_]*)+)", page.read_text()))
    for name in sorted(names - NOT_NAMES):
        if name.endswith((".py", ".md", ".toml", ".xml", ".html", ".yml", ".csv", ".json")):
            continue
        assert _resolves(name), (page.relative_to(ROOT), name)
