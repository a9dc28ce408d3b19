"""Import weight: plain modal analysis and the Taylor arithmetic load only what they need."""

import subprocess
import sys

from conftest import TWO_LINK

HEAVY = ("scipy", "matplotlib", "meshcat", "dask", "proxsuite")


def _loaded(code: str) -> set[str]:
    script = code + "\nimport sys\nprint(' '.join(sys.modules))"
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout
    return set(out.split())


def test_import_pinflex_jets_needs_neither_pinocchio_nor_scipy():
    """``import pinflex.jets`` (and ``import pinflex``) load NumPy only."""
    loaded = _loaded("import pinflex, pinflex.jets")
    assert "numpy" in loaded
    assert not {m for m in loaded if m.split(".")[0] in ("pinocchio", *HEAVY)}


def test_pinflex_modes_loads_no_optimiser_plotting_or_batch_module():
    """A plain ``pinflex modes`` run imports Pinocchio and NumPy, none of the heavy extras."""
    loaded = _loaded(
        "import sys\nfrom pinflex.cli import main\n"
        f"assert main(['modes', {str(TWO_LINK)!r}, '--planar']) == 0")
    assert "pinocchio" in loaded
    assert not {m for m in loaded if m.split(".")[0] in HEAVY}
