"""Reading description files: size and encoding checks, XML with line numbers, no entities.

:func:`read_text` refuses what cannot be a description (a missing file, a folder, binary or
non-UTF-8 bytes, more than :data:`MAX_FILE_BYTES`) with :class:`UnreadableFile`.
:func:`parse_xml` builds an ElementTree with expat and records the line of every element, so
schema errors can say where they are; it refuses DTD entity declarations (no entity
expansion, hence no "billion laughs"), and remembers which URI the prefix ``pinflex`` was
bound to so that a wrong namespace is caught even when its URI looks nothing like pinflex's.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from pinflex.description.types import NAMESPACE
from pinflex.exceptions import InvalidDescription, PinflexError, UnreadableFile

#: Largest description file read [bytes]; URDFs are a few hundred kB at most.
MAX_FILE_BYTES = 20_000_000


@dataclass
class XmlDocument:
    """An XML document with the line of each element.

    Attributes:
        root: The root element.
        source: File name (or ``"<string>"``) for messages.
        lines: Line number of each element, by ``id(element)``.
        prefixes: ``(prefix, uri, line)`` of every namespace declaration.
    """

    root: ET.Element
    source: str
    lines: dict[int, int] = field(default_factory=dict)
    prefixes: list[tuple[str, str, int]] = field(default_factory=list)

    def line(self, el: ET.Element) -> int | None:
        """Line of ``el`` in the file, if known."""
        return self.lines.get(id(el))


def input_path(path, what: str = "file", error: type[PinflexError] = UnreadableFile) -> Path:
    """``path`` as a :class:`Path`: a ``str`` or path-like without NUL; else ``error``."""
    if isinstance(path, Path):
        out = path
    elif isinstance(path, str) or isinstance(path, os.PathLike):
        out = Path(path)
    else:
        raise error(f"{what} must be a file path, got {type(path).__name__} {_short(path)}")
    if "\x00" in str(out):
        raise error(f"{what} {_short(str(out))} contains a NUL character")
    return out


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:60] + "..." + text[-15:]


def file_kind(path: Path, what: str, error: type[PinflexError]) -> os.stat_result:
    """``stat`` of an existing regular file, or ``error`` saying why it cannot be read."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise error(f"{what} {_short(str(path))} does not exist") from None
    except OSError as exc:  # name too long, not a directory, permission, loop
        raise error(f"{what} {_short(str(path))} cannot be read: "
                    f"{exc.strerror or type(exc).__name__}") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{what} '{path}' is not a regular file")
    return st


def confine(path: Path, roots, what: str, *, allow: bool = False) -> Path:
    """``path`` resolved (symbolic links followed), refused unless it lies inside a root.

    Args:
        path: The file a description names.
        roots: Folders it may lie in (the model's folder, package roots).
        what: What the file is, for the message.
        allow: Skip the check (``allow_paths=True``, ``--allow-paths``).

    Raises:
        UnsafePath: Outside every root.
    """
    from pinflex.exceptions import UnsafePath

    resolved = Path(path).resolve()
    if allow:
        return resolved
    real_roots = [Path(r).resolve() for r in roots if r is not None]
    if any(resolved == r or resolved.is_relative_to(r) for r in real_roots):
        return resolved
    raise UnsafePath(
        f"{what} {_short(str(path))} lies outside the model's folder and package roots "
        f"({', '.join(str(r) for r in real_roots) or 'none'}); copy it there, or allow it "
        "explicitly (allow_paths=True, --allow-paths)"
    )


def check_mesh_paths(urdf_xml: str, base_dir: Path | None, package_dirs, *,
                     allow: bool = False) -> None:
    """Refuse visual/collision meshes outside the model's folder and the package roots.

    ``package://pkg/rest`` must be found under a package root (``root/pkg/rest``), a relative
    file name under ``base_dir``; absolute names, ``file://`` URIs and ``..`` leaving those
    folders are refused (they would be read and embedded in a preview page), unless ``allow``.

    Raises:
        UnsafePath: Naming the first mesh outside.
    """
    import xml.etree.ElementTree as ET

    from pinflex.exceptions import UnsafePath

    if allow:
        return
    roots = [Path(d) for d in package_dirs if d]
    for el in ET.fromstring(urdf_xml).iter("mesh"):
        name = el.get("filename") or ""
        what = f"mesh '{_short(name)[1:-1]}'"
        if name.startswith("package://"):
            rest = name[len("package://"):]
            found = [r / rest for r in roots if (r / rest).exists()]
            for cand in found:
                confine(cand, roots, what)
            if not found and _elsewhere(rest):
                raise UnsafePath(f"{what} is in no package root ({', '.join(map(str, roots))}) "
                                 "but in a folder of ROS_PACKAGE_PATH/AMENT_PREFIX_PATH; allow "
                                 "it explicitly (allow_paths=True, --allow-paths)")
        elif name.startswith("file://") or Path(name).is_absolute():
            raise UnsafePath(f"{what} is an absolute path; meshes are read from the model's "
                             "folder and package roots only (allow others with "
                             "allow_paths=True, --allow-paths)")
        else:
            confine((base_dir or Path(".")) / name, [base_dir or Path(".")], what)


def _elsewhere(rest: str) -> bool:
    """Whether ``package://rest`` exists under a ROS package path (which Pinocchio searches)."""
    for var in ("ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH"):
        for folder in os.environ.get(var, "").split(os.pathsep):
            if folder and ((Path(folder) / rest).exists()
                           or (Path(folder) / "share" / rest).exists()):
                return True
    return False


def read_text(path: str | Path, what: str = "file",
              error: type[PinflexError] = UnreadableFile) -> str:
    """The UTF-8 text of an input file, or ``error`` (:class:`UnreadableFile`) saying why not."""
    path = input_path(path, what, error)
    size = file_kind(path, what, error).st_size
    if size > MAX_FILE_BYTES:
        raise error(
            f"{what} '{path}' has {size} bytes, more than the {MAX_FILE_BYTES} a description "
            "may have"
        )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise error(f"{what} '{path}' cannot be read: {exc.strerror}") from exc
    return decode(data, str(path), error, what)


def decode(data: bytes, source: str, error: type[PinflexError] = UnreadableFile,
           what: str = "URDF") -> str:
    """UTF-8 text of ``data`` (BOM allowed); binary or other encodings refused."""
    nul = data.find(b"\x00")
    if nul >= 0:
        raise error(
            f"'{source}' contains NUL bytes (first at offset {nul}): it is a binary file, "
            f"not a {what} (UTF-16 text is refused too: save it as UTF-8)"
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(
            f"'{source}' is not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the file as UTF-8"
        ) from None


def parse_xml(text: str, source: str = "<string>") -> XmlDocument:
    """Parse XML text into an :class:`XmlDocument`; malformed XML raises InvalidDescription."""
    if not isinstance(text, str):
        raise InvalidDescription(f"{source}: expected XML text, got {type(text).__name__}")
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate(namespace_separator="}")
    doc_lines: dict[int, int] = {}
    prefixes: list[tuple[str, str, int]] = []

    def name(raw: str) -> str:
        return "{" + raw if "}" in raw else raw

    def start(tag, attrs):
        el = builder.start(name(tag), {name(k): v for k, v in attrs.items()})
        doc_lines[id(el)] = parser.CurrentLineNumber

    def entity(*_args):
        raise InvalidDescription(
            f"{source}: line {parser.CurrentLineNumber}: DTD entity declarations are not "
            "allowed in a description"
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: builder.end(name(tag))
    parser.CharacterDataHandler = builder.data
    parser.StartNamespaceDeclHandler = lambda prefix, uri: prefixes.append(
        (prefix or "", uri, parser.CurrentLineNumber)
    )
    parser.EntityDeclHandler = entity
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        raise InvalidDescription(
            f"{source}: not well-formed XML at line {exc.lineno}, column {exc.offset}: "
            f"{expat.ErrorString(exc.code)}"
        ) from None
    root = builder.close()
    return XmlDocument(root=root, source=source, lines=doc_lines, prefixes=prefixes)


def local_name(tag: str) -> tuple[str, str]:
    """``(namespace URI, local name)`` of an ElementTree tag or attribute key."""
    if tag.startswith("{"):
        ns, _, local = tag[1:].partition("}")
        return ns, local
    return "", tag


def element_label(el) -> str:
    """An element as messages name it: ``<pinflex:flexible>`` or ``<joint>`` ("" for None)."""
    if el is None:
        return ""
    ns, local = local_name(el.tag)
    return f"<pinflex:{local}>" if ns == NAMESPACE else f"<{local}>"
