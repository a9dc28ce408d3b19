"""A simulation saved as data, and read back: what ``pinflex simulate --out DIR`` writes.

The data of a run costs little to write next to the physics (on benchmark A a few
milliseconds against about a second), so ``--out`` always writes it; the charts (matplotlib)
and the meshcat playback pages cost about as much as the physics of a short run and are
written only when asked (``--charts``, ``--preview``), or later from this data by
``pinflex report DIR``. Per design ``NAME`` (``baseline``/``assigned`` or ``design``):

* ``NAME_series.json``: :meth:`VibrationReport.to_json` with the time series (the metrics,
  ``times_s`` and the frame's deflection ``deflection_m`` (nt, 3) [m]);
* ``NAME_run.npz``: the :class:`~pinflex.dynamics.Simulation`'s arrays (``times_s``,
  ``x``, ``xd``, ``q``, ``qd``, ``q_physical``, ``torque_times_s``, ``torques``), its scalars,
  and the validity indicator's arrays (``validity_*``) when it has one;
* ``NAME_validity.csv``: the validity indicator per sample (when there is one).

``run.json`` says what was simulated: the robot file (absolute path and the SHA-256 of its
text), ``planar``, the joint conditions, the parameter values, gravity, the drive, and per
design its values ``y`` and file names. :func:`load_run` reads all of it back;
:func:`run_dynamics` rebuilds a design's :class:`~pinflex.dynamics.ErlsDynamics` from it and
refuses when the robot file has changed since the run (an overlay's base URDF and meshes are
not hashed).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from pinflex.dynamics.response import VibrationReport
from pinflex.dynamics.result import Simulation
from pinflex.exceptions import ConfigurationError, OutputError

#: Format name and version written in ``run.json``.
RUN_FORMAT = "pinflex-simulation"
RUN_VERSION = 1

_ARRAYS = ("times_s", "x", "xd", "q", "qd", "q_physical", "torque_times_s", "torques")
_VALIDITY = ("times_s", "link_speed_rad_s", "link_accel_rad_s2", "omega_rad_s",
             "speed_ratio", "accel_ratio")


@dataclass(frozen=True)
class SavedRun:
    """A run read back by :func:`load_run`.

    Attributes:
        folder: The folder it was read from.
        source: ``run.json``'s ``model`` table (robot, sha256, planar, joints, values).
        drive: ``"prescribed"`` or ``"torque"``.
        gravity: Gravity (3,) in world axes [m/s²].
        reports: One :class:`VibrationReport` per design, in the run's order.
        sims: One :class:`Simulation` per design.
    """

    folder: Path
    source: dict
    drive: str
    gravity: tuple[float, float, float]
    reports: list
    sims: list


def file_sha256(path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def model_source(robot, *, planar: bool, joints, values: dict | None) -> dict:
    """The ``model`` table of ``run.json``: what rebuilds the simulated model."""
    robot = Path(robot).resolve()
    return {"robot": str(robot), "sha256": file_sha256(robot), "planar": bool(planar),
            "joints": joints if isinstance(joints, str) or joints is None else dict(joints),
            "values": {k: float(v) for k, v in (values or {}).items()}}


def _save_npz(path: Path, arrays: dict) -> Path:
    from pinflex.outputs import atomic_path

    with atomic_path(path, "simulation data") as tmp:
        with open(tmp, "wb") as stream:
            np.savez(stream, **arrays)
    return path


def simulation_arrays(sim: Simulation) -> dict:
    """The arrays and scalars of a :class:`Simulation` (and its validity) for ``np.savez``."""
    out: dict = {k: np.asarray(getattr(sim, k)) for k in _ARRAYS}
    for f in fields(sim):
        if f.name not in _ARRAYS and f.name != "validity":
            out[f.name] = np.asarray(getattr(sim, f.name))
    v = sim.validity
    if v is not None:
        for k in _VALIDITY:
            out[f"validity_{k}"] = np.asarray(getattr(v, k))
        out["validity_threshold"] = np.asarray(v.threshold)
        out["validity_basis"] = np.asarray(v.basis)
    return out


def simulation_from_arrays(data) -> Simulation:
    """The :class:`Simulation` of :func:`simulation_arrays` (an ``np.load`` mapping)."""
    kw: dict = {}
    for f in fields(Simulation):
        if f.name == "validity":
            continue
        a = np.asarray(data[f.name])
        if f.name in _ARRAYS:
            kw[f.name] = a
        elif a.dtype.kind in "US":
            kw[f.name] = str(a)
        elif a.dtype.kind in "iu":
            kw[f.name] = int(a)
        else:
            kw[f.name] = float(a)
    if "validity_times_s" in data:
        from pinflex.erls.validity import Validity

        kw["validity"] = Validity(
            **{k: np.asarray(data[f"validity_{k}"]) for k in _VALIDITY},
            threshold=float(data["validity_threshold"]), basis=str(data["validity_basis"]))
    return Simulation(**kw)


def report_from_json(text: str) -> VibrationReport:
    """The :class:`VibrationReport` of ``to_json(series=True)``'s text."""
    d = json.loads(text)
    if "times_s" not in d or "deflection_m" not in d:
        raise ConfigurationError("the series JSON has no time series (times_s, deflection_m)")
    kw = {}
    for f in fields(VibrationReport):
        if f.name not in d:
            continue
        v = d[f.name]
        if f.name in ("times_s", "static_m"):
            v = np.asarray(v, dtype=float)
        elif f.name == "deflection_m":
            v = np.asarray(v, dtype=float).reshape(-1, 3)
        elif f.name in ("reference_hz", "final_q"):
            v = tuple(float(a) for a in v)
        elif f.name in ("dominant_frequency_hz", "error_estimate", "linearisation_error"):
            v = float("nan") if v is None else float(v)
        kw[f.name] = v
    return VibrationReport(**kw)


def save_run(folder, reports, sims, *, source: dict, drive: str, gravity) -> list[Path]:
    """Write a run's data into ``folder`` (module doc); returns the files written.

    Args:
        folder: Output folder (created if needed).
        reports: One :class:`VibrationReport` per design.
        sims: One :class:`Simulation` per design, in the same order.
        source: :func:`model_source` of the simulated model.
        drive: The drive simulated.
        gravity: Gravity (3,) [m/s²].
    """
    from pinflex.outputs import json_text, output_dir, write_text

    out = output_dir(folder)
    files: list[Path] = []
    designs = []
    for rep, sim in zip(reports, sims):
        series = write_text(out / f"{rep.name}_series.json", rep.to_json(series=True),
                            "simulation JSON")
        data = _save_npz(out / f"{rep.name}_run.npz", simulation_arrays(sim))
        files += [series, data]
        entry = {"name": rep.name, "y": dict(rep.y), "series": series.name, "run": data.name,
                 "validity": None}
        if sim.validity is not None:
            csv = sim.validity.write_csv(out / f"{rep.name}_validity.csv")
            files.append(csv)
            entry["validity"] = csv.name
        designs.append(entry)
    run = {"format": RUN_FORMAT, "version": RUN_VERSION, "model": source, "drive": drive,
           "gravity": [float(g) for g in gravity], "designs": designs}
    files.append(write_text(out / "run.json", json_text(run, indent=1), "run JSON"))
    return files


def load_run(folder) -> SavedRun:
    """Read a run written by :func:`save_run` (``pinflex simulate --out DIR``).

    Raises:
        OutputError: ``folder`` holds no readable ``run.json`` or misses one of its files.
    """
    folder = Path(folder)
    path = folder / "run.json"
    try:
        run = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise OutputError(f"'{folder}' holds no readable run.json of 'pinflex simulate --out' "
                          f"({exc})") from None
    if run.get("format") != RUN_FORMAT or run.get("version") != RUN_VERSION:
        raise OutputError(f"'{path}' is not a {RUN_FORMAT} run of version {RUN_VERSION}")
    reports, sims = [], []
    for d in run["designs"]:
        try:
            reports.append(report_from_json((folder / d["series"]).read_text(encoding="utf-8")))
            with np.load(folder / d["run"], allow_pickle=False) as data:
                sims.append(simulation_from_arrays(data))
        except (OSError, ValueError, KeyError) as exc:
            raise OutputError(f"'{folder}': design '{d.get('name')}' cannot be read back "
                              f"({type(exc).__name__}: {exc}); rerun pinflex simulate --out"
                              ) from None
    g = tuple(float(v) for v in run["gravity"])
    return SavedRun(folder=folder, source=run["model"], drive=run["drive"],
                    gravity=(g[0], g[1], g[2]), reports=reports, sims=sims)


def run_dynamics(saved: SavedRun, index: int):
    """The :class:`~pinflex.dynamics.ErlsDynamics` design ``index`` of a saved run ran on.

    Raises:
        ConfigurationError: The robot file is gone or its text changed since the run.
    """
    from pinflex.dynamics.terms import ErlsDynamics
    from pinflex.erls import FlexibleModel

    src = saved.source
    robot = Path(src["robot"])
    if not robot.is_file():
        raise ConfigurationError(f"the run's robot file '{robot}' is gone; the playback needs "
                                 "the model (the data files do not)")
    if file_sha256(robot) != src["sha256"]:
        raise ConfigurationError(f"the robot file '{robot}' changed since the run (SHA-256 "
                                 "differs); rerun pinflex simulate")
    model = FlexibleModel(robot, planar=src["planar"], joints=src["joints"],
                          values=src["values"] or None)
    return ErlsDynamics(model, y=saved.reports[index].y, gravity=list(saved.gravity))
