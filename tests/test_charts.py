"""Charts are drawn through matplotlib's object API and leave the process's backend alone."""

import subprocess
import sys
import textwrap


def test_assignment_charts_keep_the_backend_and_pyplot_unloaded(tmp_path):
    """assignment_charts writes PNGs without switching the backend or importing pyplot."""
    script = textwrap.dedent(f"""
        import sys
        from types import SimpleNamespace
        import matplotlib
        matplotlib.use("svg")
        import numpy as np
        from pinflex.assignment.charts import assignment_charts
        t = np.linspace(0.0, 1.0, 5)
        f = np.stack([190 + t, 400 + t, 700 + t], axis=1)
        result = SimpleNamespace(modes=(1, 2, 3), targets_hz=np.full((1, 5), 190.0),
                                 design={{"m1": 0.2}}, freq_before_hz=f, freq_after_hz=f + 1,
                                 max_error_before=0.05, max_error_after=0.01,
                                 settings=None)
        paths = assignment_charts(result, t, r"{tmp_path}")
        print(matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules,
              [p.name for p in paths], [p.read_bytes()[:4] for p in paths])
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout.split(" ", 2)
    assert out[0] == "svg" and out[1] == "False"
    assert "mode1_assignment.png" in out[2] and "other_modes.png" in out[2]
    assert out[2].count("PNG") == 2
