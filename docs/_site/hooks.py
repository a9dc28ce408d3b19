"""Build hooks of the documentation site (MkDocs): math as MathML, generated reference pages.

* Math: ``$...$`` (inline) and ``$$...$$`` (display) in the Markdown pages are converted to
  MathML at build time (latex2mathml), so the pages render in any current browser with no
  script and no network.
* Reference pages generated from the code, so that they cannot drift from it: the annotation
  schema (``reference/annotations.md``), the study and simulation TOML formats
  (``reference/study.md``) and the command line (``reference/cli.md``). The generators are in
  ``reference.py`` beside this file.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from latex2mathml.converter import convert
from mkdocs.structure.files import File

sys.path.insert(0, str(Path(__file__).resolve().parent))

import reference  # noqa: E402

_FENCE = re.compile(r"^( {0,3})(`{3,}|~{3,}).*?^\1\2[ \t]*$", re.M | re.S)
_CODE = re.compile(r"(`+)(?:.+?)(?<!`)\1(?!`)", re.S)
_DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.S)
_INLINE = re.compile(r"(?<![\\$\w])\$(?=\S)([^$\n]+?)(?<=\S)\$(?![\w$])")
_TOKEN = "PINFLEXMATH{:05d}END"
_TOKEN_RE = re.compile(r"PINFLEXMATH(\d{5})END")


def _math(text: str, store: list[str]) -> str:
    def display(m: re.Match) -> str:
        store.append(convert(m.group(1).strip(), display="block"))
        return "\n\n" + _TOKEN.format(len(store) - 1) + "\n\n"

    def inline(m: re.Match) -> str:
        store.append(convert(m.group(1)))
        return _TOKEN.format(len(store) - 1)

    out = []
    pos = 0
    for code in _CODE.finditer(text):
        out.append(_INLINE.sub(inline, _DISPLAY.sub(display, text[pos:code.start()])))
        out.append(code.group(0))
        pos = code.end()
    out.append(_INLINE.sub(inline, _DISPLAY.sub(display, text[pos:])))
    return "".join(out)


def on_page_markdown(markdown: str, page, **kwargs) -> str:
    """Replace math by tokens (MathML kept aside until the HTML is made)."""
    store: list[str] = []
    out = []
    pos = 0
    for fence in _FENCE.finditer(markdown):
        out.append(_math(markdown[pos:fence.start()], store))
        out.append(fence.group(0))
        pos = fence.end()
    out.append(_math(markdown[pos:], store))
    page.meta["_mathml"] = store
    return "".join(out)


def on_page_content(html: str, page, **kwargs) -> str:
    """Put the MathML in place of its tokens."""
    store = page.meta.get("_mathml", [])
    html = re.sub(r"<p>\s*(PINFLEXMATH\d{5}END)\s*</p>", r"\1", html)
    return _TOKEN_RE.sub(lambda m: store[int(m.group(1))], html)


def on_files(files, config, **kwargs):
    """Add the generated reference pages."""
    for uri, text in reference.pages().items():
        files.append(File.generated(config, uri, content=text))
    return files
