"""A fit on a record whose drive steps (issue 41, item 5): the cylinder's spool stepped
between two samples, logged as commanded. A straight line across the sampling interval
moved the step by half an interval, and the fitted Fc came out 20.83 N, its 95 %
interval [20.73, 20.94] N, for a truth of 20 N. The rebuilt input now jumps at the first
sample that shows the new value, with and without ``smooth_input``."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from pneumact.experiments import SpoolStep
from pneumact.identification import Noise
from pneumact.identification.uncertainty import input_replicates

#: the spool from -1 to 0.5 at 0.1 s, a sample time: the piston leaves its stop and
#: crosses most of the stroke; logged at 1 kHz
EXPERIMENT = SpoolStep(-1.0, 0.5, t_step=0.1, t_end=0.3, n_points=301)


@pytest.fixture(scope="module")
def cylinder():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the shipped set's passivity note
        return pa.Cylinder(pa.load_params("iso15552-32"))


@pytest.fixture(scope="module")
def run(cylinder):
    """The truth: the step response at a tight tolerance (a record carries no integration
    error)."""
    return pa.simulate(cylinder, EXPERIMENT, pa.Rodas4(rtol=ref.STEP_FIT_TRUTH_RTOL))


def _record(run, seed: int, spool_noise: float = 0.0) -> pa.Record:
    """The run as a bench logs it: the position with the sensor's noise and resolution,
    the spool as commanded (right-continuous: the new value from the step's sample on);
    with ``spool_noise`` [-], a spool measured with that noise, scaled by 0.9 to stay
    within [-1, 1]."""
    rng = np.random.default_rng(seed)
    _, position = Noise().apply(rng, run["position"], run["position"])
    spool = EXPERIMENT.drive(run.time)
    if spool_noise:
        spool = 0.9 * spool + rng.normal(0.0, spool_noise, run.time.size)
    return pa.Record.from_arrays(run.time, {"position": position, "spool": spool},
                                 {"position": "m", "spool": "1"}, f"spool step {seed}")


@pytest.mark.parametrize("smooth", [True, False], ids=["smooth", "sampled"])
def test_fc_fitted_on_a_spool_step_holds_the_truth_in_its_interval(cylinder, run, smooth):
    """Over several noise seeds, Fc (started 30 % off) lands on the truth and its 95 %
    interval holds it."""
    truth = float(cylinder.params["Fc"])
    for seed in range(ref.STEP_FIT_SEEDS):
        result = pa.fit(cylinder, [_record(run, seed)], ["Fc"], start={"Fc": 1.3 * truth},
                        smooth_input=smooth)
        row = result.to_pandas().loc["Fc"]
        assert row["value"] == pytest.approx(truth, rel=ref.STEP_FIT_RTOL), (seed, row)
        # the interval, widened by the seeds' share of misses a 95 % interval allows
        half = 0.5 * (row["ci95_high"] - row["ci95_low"]) * ref.STEP_FIT_CI_SLACK
        assert abs(row["value"] - truth) <= half, (seed, row.to_dict())


def test_noise_on_a_stepping_input_moves_its_rebuilt_input(cylinder, run):
    """The input-noise bootstrap (``input_replicates``) on a noisy logged spool step: the
    jump keeps its time, the replicates run and move the position by a finite amount."""
    record = _record(run, 0, spool_noise=ref.STEP_FIT_SPOOL_NOISE)
    masks = [np.ones(record.time.size, dtype=bool)]
    moves = input_replicates([cylinder], [record], {"Fc": float(cylinder.params["Fc"])},
                             masks, replicates=4, workers=1)
    assert moves[0].shape == (4, record.time.size)
    assert np.all(np.isfinite(moves[0])) and np.abs(moves[0]).max() > 0.0
