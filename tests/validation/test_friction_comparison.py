"""Which friction law do the records support? Honest on its own data (issue 21).

Records made by each registered law on the Canudas rig driven by a measured position
(noise on the friction, one record held out): the comparison ranks the generating law
first or within the noise of it, and its held-out prediction is as good as the noise
allows. Records that do not tell two laws apart say so ("cannot tell") and recommend the
simpler law. A comparison on the threads of an executor equals one in this thread.
"""

from __future__ import annotations

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from pneumact.experiments import from_samples
from pneumact.io.records import Record
from pneumact.models import friction_law, friction_models
from pneumact.options import Optimizer

GENERATING = [*[name for name in friction_models() if name != "gms"], "gms:4"]
#: every law's fit here uses a difference Jacobian: the rig's plain kernels of the
#: friction registry serve, no sensitivity kernel is compiled for a law (20 s each)
DIFFERENCES = Optimizer(jacobian="2-point")


def _campaign(law: str, canudas, seed: int = 0) -> list[Record]:
    """Two records of the rig with ``law`` (its own parameters matched to Canudas')."""
    truth = friction_law(law)
    params = canudas.replace(truth.matched_values(canudas))
    rig = pa.FrictionRig(params, truth, drive="position")
    rng = np.random.default_rng(seed)
    records = []
    for k, (amplitude, frequency) in enumerate(zip(ref.COMPARE_AMPLITUDES,
                                                   ref.COMPARE_FREQUENCIES, strict=True)):
        t = np.linspace(0.0, 4.0 / frequency, ref.COMPARE_SAMPLES)
        x = amplitude * (np.sin(2 * np.pi * frequency * t)
                         + ref.COMPARE_HARMONIC * np.sin(2 * np.pi * 7 * frequency * t))
        run = pa.simulate(rig, from_samples(t, x, "position", name=f"{law}-{k}",
                                            n_points=t.size), t_eval=t)
        noisy = run["friction"] + rng.normal(0.0, ref.COMPARE_NOISE * canudas["Fc"], t.size)
        records.append(Record.from_arrays(t, {"position": x, "friction": noisy},
                                          {"position": "m", "friction": "N"},
                                          f"{law}-{k}.csv"))
    return records


def _start(canudas):
    """Where every comparison starts: the Canudas set, whatever law made the records."""
    return pa.FrictionRig(canudas, drive="position")


@pytest.mark.parametrize("law", GENERATING)
def test_the_generating_law_is_first_or_within_its_noise(law, canudas):
    laws = [*ref.COMPARE_LAWS, *([law] if law not in ref.COMPARE_LAWS else [])]
    result = pa.compare_friction_models(_start(canudas), _campaign(law, canudas), laws,
                                        signals=["friction"], optimizer=DIFFERENCES,
                                        executor=1)
    table = result.to_pandas().set_index("law")
    truth = friction_law(law).spec
    assert table.loc[truth, "verdict"] != "failed", table["error"]
    assert truth in [s.label for s in result.tied()], table[["held_out_fit_%", "z_vs_best"]]
    assert table.loc[truth, "held_out_fit_%"] >= ref.COMPARE_TRUTH_FIT_PERCENT
    if not result.cannot_tell:
        assert result.recommended.label == truth


def test_records_that_do_not_discriminate_say_cannot_tell(canudas):
    """Dahl's records fitted by LuGre as well (LuGre with a small σ1 and Fs near Fc is
    Dahl-like on sliding sines): no winner, and the simpler law is recommended."""
    result = pa.compare_friction_models(_start(canudas), _campaign("dahl", canudas),
                                        ["lugre", "dahl"], signals=["friction"],
                                        optimizer=DIFFERENCES, executor=1)
    assert result.cannot_tell
    assert result.recommended.label == "dahl"
    assert "Cannot tell" in result.recommendation
    assert "do not discriminate" in result.report_text()
