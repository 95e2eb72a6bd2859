"""The paper's statements as margins: known answers of the measures and of the summary."""

from __future__ import annotations

import pandas as pd

from pneumact.statements import EQ13_FC_RTOL, eq13_bias, summarise


def test_eq13_gives_fc_only_well_above_vs(vgt):
    """g(v) − Fc = (Fs − Fc)·exp(−v/vs) (δ = 1): from 20·vs on it is 1e-9·Fc, so the
    fitted Fc is exact to the σ2 term's conditioning; from 0.5·vs the Stribeck hump
    biases it well beyond 1 %."""
    bias = eq13_bias(vgt, [0.5, 20.0]).set_index("lowest_vs")
    assert abs(bias.loc[20.0, "Fc_error"]) < 1e-6
    assert abs(bias.loc[20.0, "sigma2_error"]) < 1e-4
    assert bias.loc[0.5, "Fc_error"] > EQ13_FC_RTOL  # Fs pulls the low-speed friction up


def test_summary_gives_the_range_and_the_interpolated_stop():
    per = pd.DataFrame({"statement": "5c_sigma2", "valve": "command",
                        "condition": ["a", "b", "c"], "x": [0.5, 2.0, 8.0],
                        "margin": [1.0, 1.0, -1.0]})
    per["holds"] = per["margin"] >= 0
    row = summarise(per, {"5c_sigma2": "c"}).iloc[0]
    assert row["holds for"] == "v/vs 0.5–2 (of 0.5–8)"
    assert row["stops"] == "above ≈ 4"  # margin 1 → −1 half-way between 2 and 8 in log
    assert row["at our cycle"] == "does not hold"
    everywhere = summarise(per.assign(margin=1.0, holds=True)).iloc[0]
    assert everywhere["holds for"].startswith("all of v/vs")
    assert everywhere["at our cycle"] == "not studied"
    nowhere = summarise(per.assign(margin=-1.0, holds=False)).iloc[0]
    assert nowhere["holds for"] == "nowhere in v/vs 0.5–8"
