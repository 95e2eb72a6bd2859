"""Shared fixtures and the test tiers.

Every test gets the marker of its directory (``unit``, ``integration``, ``validation``),
so ``pytest -m unit`` runs the fast tier; markers are strict and warnings are errors
(pyproject.toml), so a test that expects a warning says so.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import pytest

from pneumact.errors import PassivityWarning
from pneumact.parameters import load_params

TIERS = ("unit", "integration", "validation")


#: in a parallel run each test process has one core: one BLAS thread per process (and per
#: process it starts), or numpy's BLAS threads compete with the other processes
_ONE_CORE_EACH: object = None


def pytest_configure(config):
    global _ONE_CORE_EACH
    if os.environ.get("PYTEST_XDIST_WORKER"):
        from threadpoolctl import threadpool_limits

        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(name, "1")
        _ONE_CORE_EACH = threadpool_limits(limits=1, user_api="blas")


def pytest_collection_modifyitems(config, items):
    for item in items:
        tier = Path(str(item.fspath)).parent.name
        if tier in TIERS:
            item.add_marker(getattr(pytest.mark, tier))
    # long tests first, the unit tier's small files last (a stable sort keeps the rest in
    # order): with one process per core and a file per process at a time, big files
    # first and small ones to fill the end leave no process waiting on another at the end
    items.sort(key=lambda item: (item.get_closest_marker("long") is None,
                                 item.get_closest_marker("unit") is not None))


def load_quietly(name: str):
    """A shipped set without its passivity warning: both shipped sets knowingly break the
    LuGre passivity bound (they are the published values); the warning is tested in
    test_parameters.py, not repeated in every test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        return load_params(name)


@pytest.fixture(scope="session")
def vgt():
    """The seed paper's diaphragm actuator (Table I, delta = 1)."""
    return load_quietly("vgt-paper")


@pytest.fixture(scope="session")
def canudas():
    """Canudas de Wit et al. (1995) friction + stick-slip rig."""
    return load_quietly("canudas1995")


@pytest.fixture(scope="session")
def _dask_cluster_client():
    """A two-process Dask cluster whose workers import the ``pneumact`` this process runs
    (started with that PYTHONPATH, which the rest of the session does not see); its
    dashboard on a free port, so that clusters of concurrent test processes (``pytest
    -n``) do not collide on the default one. One per test process: starting and stopping
    a cluster, and the workers' first imports, cost seconds per test that uses one."""
    distributed = pytest.importorskip("distributed")
    import pneumact

    src = str(Path(pneumact.__file__).resolve().parents[1])
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [
            src, os.environ.get("PYTHONPATH")])))
        cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                           dashboard_address=":0")
    with cluster, distributed.Client(cluster) as client:
        yield client


@pytest.fixture
def dask_client(_dask_cluster_client):
    """The test process's Dask cluster (a client of it), with both workers up."""
    _dask_cluster_client.wait_for_workers(2)
    return _dask_cluster_client


def small_rig_comparison(progress=None, executor=1):
    """Two laws compared on two short records of the Canudas rig (Coulomb-viscous)
    driven by a position: a cheap ``FrictionComparison`` (difference Jacobians)."""
    import numpy as np

    import pneumact as pa
    from pneumact.experiments import from_samples

    rig = pa.FrictionRig(load_quietly("canudas1995"), pa.CoulombViscous(), drive="position")
    records = []
    for k in range(2):
        t = np.linspace(0.0, 2.0, 201)
        x = 1e-3 * (k + 1) * np.sin(np.pi * t)
        run = pa.simulate(rig, from_samples(t, x, "position", name=f"r{k}"), t_eval=t)
        records.append(pa.Record.from_arrays(t, {"position": x, "friction": run["friction"]},
                                             {"position": "m", "friction": "N"}, f"r{k}"))
    return pa.compare_friction_models(rig, records, ["coulomb-viscous", "stribeck"],
                                      signals=["friction"], executor=executor,
                                      progress=progress,
                                      optimizer=pa.Optimizer(jacobian="2-point"))


@pytest.fixture
def estimates_log(monkeypatch) -> list[str]:
    """The messages ``pneumact.estimates`` logs during the test, whatever earlier tests
    in this process did to logging (a command line run sends them to the terminal only,
    ``cli.common.show_estimates``, and caplog then saw nothing in the full suite)."""
    import logging

    notes: list[str] = []

    class Collect(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            notes.append(record.getMessage())

    logger = logging.getLogger("pneumact.estimates")
    monkeypatch.setattr(logger, "handlers", [Collect()])
    monkeypatch.setattr(logger, "disabled", False)
    monkeypatch.setattr(logger, "propagate", False)
    monkeypatch.setattr(logging.root.manager, "disable", 0)
    logger.setLevel(logging.INFO)
    return notes
