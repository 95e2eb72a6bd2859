"""The bench in the model (issue 38, item 1): a fault a real bench adds is named, with its
size, not "the model does not fit"; where the records can tell, it is estimated and
taken out (a pressure-sensor offset from the set-point/pressure pairs, a position-sensor
offset from the records at rest on the stop, a position lag
fitted jointly: ``test_identification_mismatch.py``), else its effect goes into the
intervals (quantisation).

One actuator drawn from the family (not vgt-paper), its campaign designed from a prior
off by up to ``ref.SIGNATURE_PRIOR_ERROR``, each fault added to that campaign.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import reference as ref
from pneumact.identification import Noise, design_campaign, identify_paper, synthetic_campaign
from pneumact.identification.faults import pressure_side, regulator_check
from pneumact.io.records import Record
from pneumact.parameters.family import ActuatorFamily

pytestmark = pytest.mark.validation
SPRING_AND_FRICTION = ("F0", "k", "Fc", "Fs", "vs", "sigma0", "sigma1", "sigma2")


@pytest.fixture(scope="module")
def actuator():
    """(truth, prior, prior-designed plan) of one drawn actuator."""
    truth = ActuatorFamily().draw(ref.BENCH_ACTUATOR + 1, seed=ref.FAMILY_SEED)[-1]
    rng = np.random.default_rng(ref.BENCH_ACTUATOR)
    factors = {n: 1 + rng.uniform(-1, 1) * ref.SIGNATURE_PRIOR_ERROR
               for n in SPRING_AND_FRICTION}
    factors["Fs"] = max(factors["Fs"], factors["Fc"])
    prior = truth.replace({n: truth[n] * f for n, f in factors.items()})
    return truth, prior, design_campaign(prior, ramps=ref.FAMILY_RAMPS)


def _offset(records, offset, signal="pressure"):
    return [Record.from_arrays(r.time, {**r.signals, signal: r[signal] + offset},
                               r.units, r.source, r.meta) for r in records]


def _right_and_covered(result, truth, misses: int = 1):
    table = result.to_pandas(truth=truth)
    identified = table[(table["verdict"] == "identified") & table["truth"].notna()]
    tolerance = np.array([ref.FAMILY_TOLERANCE_PERCENT[n] for n in identified.index])
    assert (identified["error_%"].abs() <= tolerance).all(), identified
    shown = identified[identified["ci95_low"].notna()]
    # one run of eight 95 % intervals misses one or more in a third of the runs: one miss
    # is chance, two are what a coarse sensor did before its rounding was in the intervals
    assert (~shown["truth_in_ci95"].astype(bool)).sum() <= misses, shown
    return table


def _bench_lines(result) -> str:
    return "\n".join(d.message for d in result.diagnostics if d.stage == "bench")


@pytest.mark.parametrize("fault", ["pressure offset", "position offset", "quantisation"])
def test_a_bench_fault_is_named_with_its_size(fault, actuator):
    truth, prior, plan = actuator
    noise = Noise(resolution=ref.BENCH_RESOLUTION) if fault == "quantisation" else Noise()
    records = synthetic_campaign(truth, plan.tests, noise=noise, seed=ref.IDENT_SEED)
    if fault == "pressure offset":
        records = _offset(records, ref.BENCH_PRESSURE_OFFSET)
    if fault == "position offset":
        records = _offset(records, ref.BENCH_POSITION_OFFSET, "position")
    result = identify_paper(records, prior, replicates=ref.FAMILY_REPLICATES)
    lines = _bench_lines(result)
    table = _right_and_covered(result, truth, ref.BENCH_MAX_MISSES[fault])
    if fault == "pressure offset":
        found = float(re.search(r"reads ([+-][\d.]+) kPa", lines).group(1)) * 1e3
        assert found == pytest.approx(ref.BENCH_PRESSURE_OFFSET, rel=ref.BENCH_SIZE_RTOL)
        assert result.extra["pressure_side"].applied
        assert result.parameter_set(partial=True)["pressure_offset"] == pytest.approx(found,
                                                                                rel=1e-2)
        for name in ("F0", "k"):  # the spring rests on the corrected pressure
            assert table.loc[name, "verdict"] == "identified", table
    elif fault == "position offset":  # read at rest on the stop, taken off, F0 not moved
        found = float(re.search(r"position sensor reads ([+-][\d.]+) µm", lines).group(1))
        assert found * 1e-6 == pytest.approx(ref.BENCH_POSITION_OFFSET,
                                             rel=ref.BENCH_SIZE_RTOL)
        assert result.parameter_set(partial=True)["position_offset"] == pytest.approx(
            found * 1e-6, rel=1e-2)
        for name in ("F0", "k"):
            assert table.loc[name, "verdict"] == "identified", table
    else:
        assert f"quantised at {ref.BENCH_RESOLUTION * 1e6:.3g} µm" in lines, lines
        assert "position sensor reads" not in lines, lines  # no offset invented


def test_a_short_unstated_position_lag_is_named_and_the_friction_identified(actuator):
    """A 1 ms position-sensor lag the prior does not state: the grid of whole sample
    periods finds none that predicts the records at half the error, so the joint fit
    frees one itself; the lag is named with its size, and every spring and friction
    parameter is identified inside its tolerance, its interval holding the truth."""
    truth, prior, plan = actuator
    records = synthetic_campaign(truth, plan.tests, noise=Noise(lag=ref.BENCH_SHORT_LAG),
                                 seed=ref.IDENT_SEED)
    result = identify_paper(records, prior, replicates=ref.FAMILY_REPLICATES)
    lines = _bench_lines(result)
    found = float(re.search(r"a first-order lag of ([\d.]+) ms", lines).group(1)) * 1e-3
    assert found == pytest.approx(ref.BENCH_SHORT_LAG, rel=ref.BENCH_SIZE_RTOL)
    table = _right_and_covered(result, truth, ref.BENCH_MAX_MISSES["short lag"])
    assert (table.loc[list(SPRING_AND_FRICTION), "verdict"] == "identified").all(), table


def test_a_slow_regulator_is_named_with_how_much_later_it_follows(actuator):
    """A regulator four times slower than the model's: at the identified values (here the
    truth's) the regulator check names it and how much later the chamber follows; the
    same check on the right regulator names nothing, and the pressure side at the prior
    invents no sensor offset from the lag."""
    truth, prior, plan = actuator
    slow = truth.replace(reg_tau=truth["reg_tau"] * ref.BENCH_REGULATOR_SLOWER)
    records = synthetic_campaign(slow, plan.tests, seed=ref.IDENT_SEED)
    table, found = regulator_check(records, truth)
    lines = " ".join(d.message for d in found)
    assert "does not follow the measured one" in lines and "regulator" in lines, table
    assert re.search(r"follows [\d.]+ ms later", lines), lines
    assert not pressure_side(records, prior).applied
    clean = synthetic_campaign(truth, plan.tests, seed=ref.IDENT_SEED)
    table, found = regulator_check(clean, truth)
    assert not found, table
