"""``compare_friction_models`` in an actuator (pressure-position loops, the loop measures)
and on a Dask cluster (the same table as on this machine's threads)."""

from __future__ import annotations

import numpy as np
import pandas as pd

import pneumact as pa
from conftest import small_rig_comparison
from pneumact.io.records import Record


def test_an_actuator_comparison_scores_the_loops(vgt):
    """A law in the actuator (a pressure source; the cheapest, a Coulomb-viscous map: the
    ranking of laws is test_friction_comparison's), on two pressure cycles made by LuGre
    with position noise: its loop width is scored against the held-out cycle's, and the
    report says how well it predicts that cycle."""
    model = pa.Actuator(vgt, valve=pa.PressureSource())
    rng = np.random.default_rng(5)
    records = []
    for k, (low, period) in enumerate([(30e3, 2.0), (45e3, 3.0)]):
        run = pa.simulate(model, pa.PressureCycle(high=90e3, low=low, period=period,
                                                  n_points=201))
        noisy = run["position"] + rng.normal(0.0, 2e-5, run.time.size)
        records.append(Record.from_arrays(run.time, {"pressure": run["pressure"],
                                                     "position": noisy},
                                          {"pressure": "Pa", "position": "m"}, f"cycle{k}"))
    result = pa.compare_friction_models(model, records, ["coulomb-viscous"], executor=1)
    row = result.to_pandas().set_index("law").loc["coulomb-viscous"]
    assert row["verdict"] == "recommended", row["error"]
    assert np.isfinite(row["loop_width_error_%"]), row
    assert row["held_out_fit_%"] > 90.0, row
    assert "only law fitted" in result.recommendation


def test_a_comparison_on_dask_equals_one_on_threads(dask_client):
    local = small_rig_comparison(executor=1)
    remote = small_rig_comparison(executor=pa.Executor(scheduler=dask_client))
    columns = [c for c in local.to_pandas() if c != "seconds"]
    pd.testing.assert_frame_equal(remote.to_pandas()[columns], local.to_pandas()[columns])
