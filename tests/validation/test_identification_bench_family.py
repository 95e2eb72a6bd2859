"""Identification on the wide family, through a drawn bench (issue 38, item 6).

Twenty actuators of ``ActuatorFamily.wide()`` (diaphragms of 30-250 mm, strokes of
8-50 mm, 0.05-6 kg, Fc 0.3-300 N scaled with the size, Fs/Fc up to 2.2, vs 0.05-20
mm/s), each campaign designed from a prior up to ±50 % off and logged by a bench drawn
for it (``BenchFamily``: a pressure offset of up to ±2 kPa, a position lag of 0.5-20 ms,
a resolution of 2-50 µm and a logging rate of 100 Hz-1 kHz, each present in a half to
two thirds of the campaigns), identified from that prior. Asserted: no identified
estimate out of its tolerance, the reported 95 % intervals' coverage, and the share
identified, each against what it measured (``reference.BENCH_FAMILY_*``). Every drawn
pressure offset above 0.5 kPa is named.

Its own tier (``family``, with the default family's test, left out of the default run:
its twenty identifications take about 14 minutes of CPU); CI runs it with ``-m family -n 0``
(one process, the actuators on every core). The same draw and setting is
``python benchmarks/bench_identify_family.py --family wide --bench --validation
--actuators 20``, whose table is in ``docs/identification.md``.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from test_identification_family import family_table, identify_drawn

import reference as ref
from pneumact.identification import BenchFamily, Noise, synthetic_campaign
from pneumact.identification.campaign import add_noise
from pneumact.parameters.family import ActuatorFamily

pytestmark = [pytest.mark.family, pytest.mark.long]


def bench_of(index: int) -> Noise:
    """The bench of actuator ``index``'s campaign, as the benchmark draws it."""
    return BenchFamily().sample(np.random.default_rng([ref.FAMILY_SEED, index, index]))


def bench_records(truth, tests, index: int):
    """The ``tests`` run on ``truth`` as actuator ``index``'s bench logs them (each
    record's noise seeded on its own, as in the benchmark)."""
    exact = synthetic_campaign(truth, tests, noise=Noise(0.0, 0.0, 0.0))
    return [add_noise([record], bench_of(index), seed=index * 1000 + i)[0]
            for i, record in enumerate(exact)]


def identify_one(args):
    index, truth = args
    return truth, bench_of(index), identify_drawn(index, truth, bench_records)


@pytest.fixture(scope="module")
def bench_family_results():
    family = ActuatorFamily.wide().draw(ref.FAMILY_SIZE, seed=ref.FAMILY_SEED)
    threads = 1 if os.environ.get("PYTEST_XDIST_WORKER") else os.cpu_count() or 1
    with ThreadPoolExecutor(max_workers=threads) as pool:
        return list(pool.map(identify_one, enumerate(family)))


def test_nothing_identified_is_wrong_on_the_wide_family_through_a_bench(
        bench_family_results):
    table = family_table([(truth, result) for truth, _, result in bench_family_results])
    identified = table[table["verdict"] == "identified"]
    tolerance = identified["parameter"].map(ref.FAMILY_TOLERANCE_PERCENT)
    assert (identified["error_%"].abs() <= tolerance).all(), identified
    assert (table.loc[table["verdict"] != "identified", "reason"].str.len() > 0).all()
    share = len(identified) / len(table)
    assert share >= ref.BENCH_FAMILY_MIN_IDENTIFIED, (share, table.groupby("verdict").size())
    reported = table[table["reported"]]
    assert len(reported) >= ref.BENCH_FAMILY_MIN_INTERVALS
    coverage = reported["covered"].astype(float).mean()
    assert coverage >= ref.BENCH_FAMILY_COVERAGE, reported[~reported["covered"].astype(bool)]


def test_every_pressure_offset_of_the_drawn_benches_is_named(bench_family_results):
    for truth, bench, result in bench_family_results:
        said = " ".join(d.message for d in result.diagnostics if d.stage == "bench")
        if abs(bench.pressure_offset) > ref.BENCH_FAMILY_NAMED_OFFSET:
            assert "pressure sensor reads" in said, (truth.name, bench, said)
