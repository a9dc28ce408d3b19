"""Lazy exports of package namespaces (PEP 562), so that importing a package stays cheap.

A package lists ``{public name: defining module}``; a name is imported from its module the first
time it is read. ``import pinflex`` then loads neither Pinocchio nor SciPy, and plain modal
analysis never loads the optimisers, sparse matrices, plotting or batch machinery.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, exports: Mapping[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` functions of a package with lazy exports.

    Args:
        package: The package's ``__name__``.
        exports: ``{name: module}``; the module is absolute or relative to ``package``.

    Returns:
        ``(__getattr__, __dir__)`` to assign in the package's ``__init__``.
    """

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        importlib.import_module(package).__dict__[name] = value  # later reads skip this
        return value

    def __dir__() -> list[str]:
        return sorted(set(importlib.import_module(package).__dict__) | set(exports))

    return __getattr__, __dir__
