"""Import weight: plain modal analysis and the Taylor arithmetic load only what they need."""

import subprocess
import sys

from conftest import ROOT, TWO_LINK

HEAVY = ("scipy", "matplotlib", "meshcat", "dask", "proxsuite", "numba", "llvmlite")


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


def test_the_pinflex_command_imports_only_the_subcommand_it_runs():
    """``python -m pinflex modes`` imports only its own subcommand module.

    No other subcommand, no Taylor, assignment, PRBDM or jet layer, no ``numpy.polynomial``;
    ``pinflex --help`` still lists every subcommand.
    """
    from pinflex.cli import SUBCOMMANDS

    code = ("import runpy, sys\n"
            f"sys.argv = ['pinflex', 'modes', {str(TWO_LINK)!r}, '--planar']\n"
            "try:\n    runpy.run_module('pinflex', run_name='__main__')\n"
            "except SystemExit as exc:\n    assert exc.code == 0, exc.code\n")
    loaded = _loaded(code)
    assert "pinflex.cli.modes" in loaded
    others = {f"pinflex.cli.{name}" for name in SUBCOMMANDS if name != "modes"}
    layers = {"pinflex.parametric", "pinflex.assignment", "pinflex.prbdm", "pinflex.jets",
              "pinflex.batch", "pinflex.visualization", "pinflex.native", "numpy.polynomial",
              "scipy.optimize", "scipy.sparse"}
    assert not loaded & (others | layers)
    helped = subprocess.run([sys.executable, "-m", "pinflex", "--help"], capture_output=True,
                            text=True, cwd=ROOT)
    assert helped.returncode == 0
    listed = helped.stdout.split("{", 1)[1].split("}", 1)[0].split(",")
    assert listed == SUBCOMMANDS
