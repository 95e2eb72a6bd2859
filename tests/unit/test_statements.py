"""The paper's statements as margins: known answers of the measures and of the summary."""

from __future__ import annotations

from types import SimpleNamespace

import pandas as pd
import pytest

from pneumact.errors import ArgumentError
from pneumact.reproduction import rank_groups
from pneumact.sensitivity import PAPER_VARIATIONS
from pneumact.statements import (
    EQ13_FC_RTOL,
    LUGRE,
    SIGMA0_FACTORS,
    STATEMENTS,
    VISIBLE,
    Statement,
    eq13_bias,
    evaluate_statements,
    statement_texts,
    summarise,
    variations_for,
)

_SYMBOL_OF = {"sigma0": "σ0", "sigma1": "σ1", "sigma2": "σ2", "Fs": "Fs", "Fc": "Fc",
              "vs": "vs"}


def test_eq13_gives_fc_only_well_above_vs(vgt):
    """g(v) − Fc = (Fs − Fc)·exp(−v/vs) (δ = 1): from 20·vs on it is 1e-9·Fc, so the
    fitted Fc is exact to the σ2 term's conditioning; from 0.5·vs the Stribeck hump
    biases it well beyond 1 %."""
    bias = eq13_bias(vgt, [0.5, 20.0]).set_index("lowest_vs")
    assert abs(bias.loc[20.0, "Fc_error"]) < 1e-6
    assert abs(bias.loc[20.0, "sigma2_error"]) < 1e-4
    assert bias.loc[0.5, "Fc_error"] > EQ13_FC_RTOL  # Fs pulls the low-speed friction up


def _study(changes: dict[float, dict[str, dict[float, float]]], valve: str = "source"):
    """A one-at-a-time ``ConditionStudy`` stand-in: per v/vs, per parameter, per factor
    the change of the loop width (share of the nominal width, 1 kPa; the break-away and
    the presliding travel unchanged)."""
    rows, results = [], []
    for speed, per_parameter in changes.items():
        runs = [{"parameter": "nominal", "change_%": 0.0, "loop_width_pressure": 1e3,
                 "loop_width_position": 1e-3, "delta_loop_width_pressure": 0.0,
                 "delta_breakaway_pressure": 0.0, "delta_presliding_travel": 0.0}]
        for name, by_factor in per_parameter.items():
            for factor, change in by_factor.items():
                runs.append({"parameter": name, "change_%": 100 * (factor - 1),
                             "delta_loop_width_pressure": 1e3 * change,
                             "delta_breakaway_pressure": 0.0, "delta_presliding_travel": 0.0})
        rows.append({"condition": f"{valve}, {speed:g}", "valve": valve, "period": 1 / speed,
                     "speed_vs": speed})
        results.append(SimpleNamespace(runs=pd.DataFrame(runs).fillna(0.0)))
    return SimpleNamespace(conditions=pd.DataFrame(rows), results=results)


def _paper(change: float, **own: float) -> dict[str, dict[float, float]]:
    """Every LuGre parameter at the paper's amounts moving the loop by ``change`` (both
    directions), and ``own`` as {parameter: change} at those amounts."""
    out = {}
    for name in LUGRE:
        share = PAPER_VARIATIONS[name]
        out[name] = {1 - share: own.get(name, change), 1 + share: own.get(name, change)}
    return out


def _evaluate(study, statements, floor=None):
    return evaluate_statements(study, statements=statements, loop_floor=floor)


def test_every_statement_is_about_one_parameter_and_fig3_is_split():
    """Issue #40, item 1: a conjunction is one statement per parameter, each with the
    paper's sentence beside our criterion."""
    by_source = {}
    for statement in STATEMENTS:
        assert statement.parameter in LUGRE
        assert _SYMBOL_OF[statement.parameter] in statement.criterion or \
            statement.measure == "eq13"
        by_source.setdefault(statement.paper, set()).add(statement.parameter)
    dynamics = next(s.paper for s in STATEMENTS if s.key.startswith("3_dynamics"))
    steady = next(s.paper for s in STATEMENTS if s.key.startswith("3_steady"))
    assert by_source[dynamics] == {"sigma0", "sigma1", "vs"}
    assert by_source[steady] == {"sigma2", "Fs", "Fc"}
    conclusion = next(s.paper for s in STATEMENTS if s.key.startswith("conclusion_oat"))
    assert by_source[conclusion] == {"Fs", "Fc"}
    texts = statement_texts()
    assert texts["statement"].is_unique and (texts["paper"].str.len() > 20).all()


def test_the_sigma0_claim_is_tested_beyond_fifty_percent(vgt):
    """Fig. 5a: 'important if we change its value from more than 50 %': σ0 ×0.1 … ×10,
    each factor its own verdict, each run once in the study."""
    sigma0 = [s for s in STATEMENTS if s.source == "Fig. 5a"]
    assert sorted(f for s in sigma0 for f in s.factors) == list(SIGMA0_FACTORS)
    assert min(SIGMA0_FACTORS) <= 0.1 and max(SIGMA0_FACTORS) >= 10
    runs = variations_for(vgt)["sigma0"]
    values = sorted({v for pair in runs for v in pair})
    expected = sorted({vgt["sigma0"] * f for f in (*SIGMA0_FACTORS, 1.5)})
    assert values == pytest.approx(expected)


def test_verdicts_per_factor_with_the_noise_floor_and_no_boundary_inside_it():
    """Known answers: σ0 ×0.1 moves the loop 17 % (holds), ×10 moves it 3 % (does not);
    a margin within the floor is 'within noise', and the boundary next to it is not
    interpolated."""
    study = _study({0.3: {**_paper(0.01), "sigma0": {0.1: 0.17, 0.5: 0.03, 1.5: 0.01,
                                                     10.0: 0.03}},
                    3.0: {**_paper(0.01), "sigma0": {0.1: 0.052, 0.5: 0.03, 1.5: 0.01,
                                                     10.0: 0.01}},
                    30.0: {**_paper(0.01), "sigma0": {0.1: 0.01, 0.5: 0.03, 1.5: 0.01,
                                                      10.0: 0.01}}})
    floor = pd.DataFrame({"condition": ["source, 0.3", "source, 3", "source, 30"],
                          "sliding": [0.001, 0.005, 0.001], "corner": 0.0,
                          "change": [0.001, 0.005, 0.001]})
    soft, stiff = (s for s in STATEMENTS if s.key in ("5a_sigma0_x0.1", "5a_sigma0_x10"))
    per = _evaluate(study, [soft, stiff], floor).set_index(["statement", "x"])
    assert per.loc[(soft.key, 0.3), "margin"] == pytest.approx(0.17 - VISIBLE)
    assert per.loc[(soft.key, 0.3), "verdict"] == "holds"
    assert per.loc[(soft.key, 3.0), "verdict"] == "within noise"  # 0.2 % margin, 0.5 % floor
    assert per.loc[(stiff.key, 0.3), "verdict"] == "does not hold"
    summary = summarise(per.reset_index(), [soft, stiff]).set_index("statement")
    assert summary.loc[soft.key, "holds for"] == "v/vs 0.3–3 (of 0.3–30); within noise at 3"
    assert summary.loc[soft.key, "stops"] == ("above somewhere in 3–30 (margin within "
                                              "noise)")
    assert summary.loc[soft.key, "noise floor"] == "0.1–0.5 %"
    assert summary.loc[stiff.key, "holds for"] == "nowhere in v/vs 0.3–30"
    assert summary.loc[soft.key, "command valve"] == "not studied"


def test_a_clear_boundary_is_interpolated_to_two_digits():
    study = _study({0.5: _paper(0.01, sigma2=0.01), 2.0: _paper(0.01, sigma2=0.01),
                    8.0: _paper(0.01, sigma2=0.09)})
    sigma2 = next(s for s in STATEMENTS if s.key == "5c_sigma2")
    row = summarise(_evaluate(study, [sigma2]), [sigma2]).iloc[0]
    assert row["holds for"] == "v/vs 0.5–2 (of 0.5–8)"
    assert row["stops"] == "above ≈ 4"  # margin 0.04 → −0.04: half-way between 2 and 8 in log
    assert row["noise floor"] == "not measured"


def test_comparisons_against_other_parameters():
    """'Fs largest of six' and 'Fs above σ0, σ1, σ2, vs' compare at the paper's amounts;
    'σ1 below σ0' likewise."""
    study = _study({1.0: _paper(0.01, Fs=0.08, Fc=0.1, sigma0=0.02, sigma1=0.03)})
    keys = ("5d_Fs_largest", "conclusion_oat_Fs", "5b_sigma1_below_sigma0")
    chosen = [s for s in STATEMENTS if s.key in keys]
    per = _evaluate(study, chosen).set_index("statement")
    assert per.loc["5d_Fs_largest", "margin"] == pytest.approx(0.08 - 0.1)  # Fc leads
    assert per.loc["conclusion_oat_Fs", "margin"] == pytest.approx(0.08 - 0.03)
    assert per.loc["5b_sigma1_below_sigma0", "margin"] == pytest.approx(0.02 - 0.03)
    assert per.loc["5d_Fs_largest", "value"] == "Fs 8 %, Fc 10 %"


def test_a_user_adds_a_statement():
    """A statement is data: Fc doubled, 'visible', on the loop; the study runs Fc ×2
    once and the verdict reads it."""
    mine = Statement("mine_Fc_x2", "my bench", "Doubling Fc shows.", "Fc", (2.0,))
    assert mine.amount == "×2" and mine.axis == "v/vs" and "Fc ×2" in mine.criterion
    params = {name: 1.0 for name in LUGRE}
    assert (2.0, 2.0) in variations_for(params, [*STATEMENTS, mine])["Fc"]
    study = _study({1.0: {**_paper(0.01), "Fc": {0.8464: 0.1, 1.1536: 0.1, 2.0: 0.6}}})
    per = _evaluate(study, [mine])
    assert per["margin"].iloc[0] == pytest.approx(0.6 - VISIBLE)
    with pytest.raises(ArgumentError, match="3_steady_Fc need a study"):
        evaluate_statements(study, statements=[s for s in STATEMENTS
                                               if s.key == "3_steady_Fc"])
    with pytest.raises(ArgumentError, match="parameter = 'k'"):
        Statement("bad", "x", "y", "k")
    with pytest.raises(ArgumentError, match="comparison"):
        Statement("bad", "x", "y", "Fc", comparison="bigger")
    with pytest.raises(ArgumentError, match="paper's amounts"):
        Statement("bad", "x", "y", "Fc", (2.0,), measure="friction steady")


def test_rank_groups_join_what_the_intervals_cannot_order():
    values = pd.Series({"Fc": 0.9, "sigma0": 0.05, "sigma1": 0.045, "vs": 0.035,
                        "Fs": 0.001})
    conf = pd.Series({"Fc": 0.05, "sigma0": 0.01, "sigma1": 0.01, "vs": 0.01, "Fs": 0.001})
    groups = rank_groups(values, conf)
    assert groups.to_dict() == {"Fc": 1, "sigma0": 2, "sigma1": 2, "vs": 2, "Fs": 3}
