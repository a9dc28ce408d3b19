"""The documentation site, opened in headless Chromium: the API page of FlexibleModel is there.

`.ci/run` builds the site with warnings as errors (`mkdocs build --strict`) and passes its
folder in ``PINFLEX_DOCS_SITE``; without it the test builds the site itself when the `docs`
extra is installed (``pip install -e ".[docs]"``) and skips otherwise. The pages are loaded
from files with the network blocked, as a reader offline would see them.
"""

from __future__ import annotations

import inspect
import os
import re
import subprocess
import sys
from html import unescape
from pathlib import Path

import pytest
from chromium import find_browser

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "docs" / "_site" / "mkdocs.yml"


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """Folder of the built site."""
    given = os.environ.get("PINFLEX_DOCS_SITE")
    if given:
        path = Path(given)
        assert (path / "index.html").is_file(), f"PINFLEX_DOCS_SITE={given} holds no site"
        return path
    pytest.importorskip("mkdocs", reason="the docs extra is not installed "
                        "(pip install -e \".[docs]\")")
    pytest.importorskip("mkdocstrings", reason="the docs extra is not installed")
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
                           "-f", str(CONFIG), "-d", str(out)],
                          capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


@pytest.fixture(scope="module")
def browser() -> str:
    """Path of a Chromium executable, or skip."""
    return find_browser()


def dom(browser: str, page: Path, profile: Path) -> str:
    """The page's DOM after Chromium has run its scripts, offline."""
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--proxy-server=http://127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",
           f"--user-data-dir={profile}", "--virtual-time-budget=2000", "--dump-dom",
           page.as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def test_site_leads_from_its_front_page_to_the_api_of_flexible_model(site, browser, tmp_path):
    """From index.html the navigation reaches a page whose FlexibleModel entry is its docstring."""
    from pinflex import FlexibleModel

    front = dom(browser, site / "index.html", tmp_path / "p0")
    assert "<title>" in front and "pinflex" in front
    links = re.findall(r'href="([^"#]*api/[^"#]*\.html)"', front)
    assert links, "the front page links to no API page"
    first_line = inspect.getdoc(FlexibleModel).splitlines()[0]
    for link in dict.fromkeys(links):
        page = (site / link).resolve()
        html = dom(browser, page, tmp_path / "p1")
        entry = re.search(r'id="pinflex\.FlexibleModel"(.*?)</h2>(.*?)<h3', html, flags=re.S)
        if entry:
            break
    else:
        pytest.fail(f"no API page among {sorted(set(links))} documents pinflex.FlexibleModel")
    text = unescape(re.sub(r"<[^>]+>", " ", entry.group(2)))
    words = " ".join(text.split())
    assert " ".join(first_line.split()) in words
    # its public methods are documented on the same page, each under its own anchor
    for method in ("modes", "frequencies", "matrices"):
        assert f'id="pinflex.FlexibleModel.{method}"' in html


def test_generated_reference_lists_every_schema_entry(site):
    """The annotation and study references name every element, attribute and key of the code."""
    from pinflex.assignment.study_schema import STUDY
    from pinflex.description.schema import SCHEMA

    annotations = (site / "reference" / "annotations.html").read_text()
    for name, element in SCHEMA.items():
        assert f"&lt;pinflex:{name}&gt;" in annotations, name
        for attr in element.attrs:
            assert f"<code>{attr}</code>" in annotations, (name, attr)
    study = (site / "reference" / "study.html").read_text()

    def keys(table):
        for key, spec in table.items():
            yield key
            yield from keys(spec.keys)

    for key in keys(STUDY):
        assert f"<code>{key}</code>" in study, key


def test_math_is_mathml(site):
    """Equations are rendered at build time (MathML), so they show without scripts or network."""
    html = (site / "concepts" / "erls.html").read_text()
    assert "<math" in html and "$$" not in html
