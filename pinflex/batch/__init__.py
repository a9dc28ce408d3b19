"""Batch studies at scale on Dask ``distributed``, resumable through an SQLite store.

* :mod:`pinflex.batch.tasks`: random-beam PRBDM studies (paper 001, Sec. 2.1), one task per beam;
* :mod:`pinflex.batch.sweep`: sweeps of assignment studies (``--sweep KEY=V1,V2``);
* :mod:`pinflex.batch.runner`: the Dask client loop (local cluster or existing scheduler);
* :mod:`pinflex.batch.store`: the result store, one row per (seed, item, config hash);
* :mod:`pinflex.batch.report`: error distributions, failures and histograms;
* the ``pinflex batch`` command is :mod:`pinflex.cli.batch`.

Dask is imported only when a batch runs.
"""

from pinflex.batch.store import ResultStore, Row
from pinflex.batch.tasks import PrbdmStudy

__all__ = ["PrbdmStudy", "ResultStore", "Row"]
