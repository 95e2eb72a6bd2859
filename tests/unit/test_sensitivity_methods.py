"""Sensitivity methods against known analytic answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.errors import ParameterError, PneumactError
from pneumact.sensitivity import Factor, Problem, SensitivityWarning, morris, sobol, src


def _uniform(names, low, high):
    return Problem(tuple(Factor(n, low, high, 0.5 * (low + high)) for n in names))


def ishigami(x):
    a, b = ref.ISHIGAMI_A, ref.ISHIGAMI_B
    return pd.DataFrame({"y": np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2
                         + b * x[:, 2] ** 4 * np.sin(x[:, 0])})


def test_sobol_matches_the_ishigami_indices():
    a, b = ref.ISHIGAMI_A, ref.ISHIGAMI_B
    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    var = v1 + v2 + v13
    problem = _uniform(["x1", "x2", "x3"], -np.pi, np.pi)
    table = sobol(problem, ishigami, n=ref.SOBOL_N).to_pandas(output="y")
    assert table["S1"].to_numpy() == pytest.approx([v1 / var, v2 / var, 0.0],
                                                   abs=ref.SOBOL_ATOL)
    assert table["ST"].to_numpy() == pytest.approx([(v1 + v13) / var, v2 / var, v13 / var],
                                                   abs=ref.SOBOL_ATOL)


def test_sobol_matches_the_g_function_indices():
    a = np.array(ref.G_FUNCTION_A)
    partial = 1.0 / (3.0 * (1.0 + a) ** 2)  # V_i of (|4x − 2| + a)/(1 + a), x ~ U(0, 1)
    total = np.prod(1.0 + partial) - 1.0
    problem = _uniform([f"x{i}" for i in range(a.size)], 0.0, 1.0)

    def g_function(x):
        return pd.DataFrame({"y": np.prod((np.abs(4 * x - 2) + a) / (1 + a), axis=1)})

    table = sobol(problem, g_function, n=ref.SOBOL_N).to_pandas(output="y")
    expected_st = partial * np.prod(1.0 + partial) / (1.0 + partial) / total
    assert table["S1"].to_numpy() == pytest.approx(partial / total, abs=ref.SOBOL_ATOL)
    assert table["ST"].to_numpy() == pytest.approx(expected_st, abs=ref.SOBOL_ATOL)


def test_sobol_confidence_intervals_are_reproducible_with_seed_zero():
    problem = _uniform(["x1", "x2", "x3"], -np.pi, np.pi)
    first, again = (sobol(problem, ishigami, n=64, seed=0).indices for _ in range(2))
    pd.testing.assert_frame_equal(first, again)


def test_src_of_a_linear_model_is_exact():
    coefficients = np.array([3.0, -1.0, 0.5])
    problem = Problem((Factor("a", 0, 1, 0.5), Factor("b", 0, 2, 1), Factor("c", -1, 1, 0)))
    result = src(problem, lambda x: pd.DataFrame({"y": x @ coefficients}), n=400)
    table = result.to_pandas(output="y")
    x = result.sample.to_numpy()
    y = x @ coefficients
    expected = coefficients**2 * x.var(axis=0) / y.var()
    assert table["SRC2"].to_numpy() == pytest.approx(expected, rel=1e-6)
    assert table["R2"].iloc[0] == pytest.approx(1.0, abs=ref.SRC_RTOL)
    assert np.sign(table["SRC"].to_numpy()).tolist() == [1, -1, 1]


def test_src_warns_when_the_regression_explains_little():
    problem = _uniform(["x1", "x2", "x3"], -np.pi, np.pi)
    with pytest.warns(SensitivityWarning, match="R²"):
        src(problem, ishigami, n=300)


def test_morris_ranks_inputs_in_their_known_order():
    weights = np.array([10.0, 3.0, 1.0, 0.0])
    problem = _uniform(["w10", "w3", "w1", "w0"], 0, 1)
    result = morris(problem, lambda x: pd.DataFrame({"y": x @ weights + x[:, 0] ** 2}),
                    trajectories=ref.MORRIS_TRAJECTORIES)
    assert result.ranking("y") == ["w10", "w3", "w1", "w0"]
    assert result.to_pandas(output="y").loc["w0", "mu_star"] == pytest.approx(0.0, abs=1e-12)


def test_failed_runs_are_reported_not_dropped():
    problem = _uniform(["x1", "x2", "x3"], -np.pi, np.pi)

    def sometimes_nan(x):
        y = ishigami(x)
        y.loc[3, "y"] = np.nan
        return y

    with pytest.raises(PneumactError, match=r"1 of \d+ runs gave no value"):
        sobol(problem, sometimes_nan, n=64)


def test_problem_from_a_parameter_set_and_bad_ranges(vgt):
    problem = Problem.around(vgt, {"sigma0": "50%", "Fs": (2.8, 3.6)})
    assert (problem.factors[0].low, problem.factors[0].high) == pytest.approx((5e4, 1.5e5))
    assert problem.to_salib()["bounds"][1] == [2.8, 3.6]
    with pytest.raises(ParameterError, match="sigma9"):
        Problem.around(vgt, {"sigma9": "10%"})
    with pytest.raises(ParameterError, match="low < high"):
        Problem.around(vgt, {"Fs": (3.6, 2.8)})
    with pytest.raises(ParameterError, match="per cent"):
        Problem.around(vgt, {"Fs": "ten%"})


def _decay(times):
    def evaluate(x):
        return pd.DataFrame(x[:, [0]] * np.exp(-x[:, [1]] * np.asarray(times)[None, :]),
                            columns=[repr(float(t)) for t in times])
    return evaluate


def test_indices_along_time_match_the_closed_form():
    """x(t) = a·e^(−bt): S1_a = Var(a)·E[e^(−bt)]²/Var(x), S1_b = E[a]²·Var(e^(−bt))/Var(x)."""
    from pneumact.sensitivity import along_time

    t = np.asarray(ref.EXP_TIMES)
    problem = Problem((Factor("a", 1.0, 2.0, 1.5), Factor("b", 0.5, 1.5, 1.0)))
    s1 = along_time(sobol(problem, _decay(t), n=ref.EXP_SOBOL_N), "S1")
    safe = np.where(t > 0, t, 1.0)
    e_b = np.where(t > 0, (np.exp(-0.5 * t) - np.exp(-1.5 * t)) / safe, 1.0)
    e_b2 = np.where(t > 0, (np.exp(-t) - np.exp(-3.0 * t)) / (2 * safe), 1.0)
    mean_a, var_a = 1.5, 1.0 / 12.0
    variance = (mean_a**2 + var_a) * e_b2 - mean_a**2 * e_b**2
    assert s1.index.tolist() == pytest.approx(t.tolist())
    assert s1["a"].to_numpy() == pytest.approx(var_a * e_b**2 / variance, abs=ref.SOBOL_ATOL)
    assert s1["b"].to_numpy() == pytest.approx(mean_a**2 * (e_b2 - e_b**2) / variance,
                                               abs=ref.SOBOL_ATOL)


def test_convergence_reuses_the_sample_and_says_what_n_to_try():
    from pneumact.sensitivity import sobol_convergence

    problem = Problem((Factor("a", 1.0, 2.0, 1.5), Factor("b", 0.5, 1.5, 1.0)))
    calls = []

    def counted(x):
        calls.append(len(x))
        return _decay(ref.EXP_TIMES)(x)

    with pytest.warns(SensitivityWarning, match="try n = "):
        final, table = sobol_convergence(problem, counted, n_max=256, n_min=32,
                                         target_width=0.01)
    assert calls == [256 * 4]  # one evaluation of the largest sample
    assert sorted(table["n"].unique()) == [32, 64, 128, 256]
    direct = sobol(problem, _decay(ref.EXP_TIMES), n=256).indices
    assert np.allclose(final.indices["ST"], direct["ST"])
    widths = table[table["parameter"] == "b"].groupby("n")["ST_width"].mean()
    assert widths.iloc[-1] < widths.iloc[0]


def test_dgsm_of_known_derivatives_and_the_sobol_bound():
    """f = 2·x1 + sin(x2)·x3 on [0, 1]³: ν1 = 4, ν2 = E[cos²x2]·E[x3²], ν3 = E[sin²x2]."""
    from pneumact.sensitivity import dgsm

    problem = _uniform(["x1", "x2", "x3"], 0.0, 1.0)

    def gradient(x):
        y = 2 * x[:, 0] + np.sin(x[:, 1]) * x[:, 2]
        grads = np.stack([2 * np.ones(len(x)), np.cos(x[:, 1]) * x[:, 2], np.sin(x[:, 1])],
                         axis=1)
        return pd.DataFrame({"y": y}), grads[:, None, :]

    table = dgsm(problem, gradient, n=20_000).to_pandas(output="y")
    e_cos2 = 0.5 + np.sin(2.0) / 4
    expected = [4.0, e_cos2 / 3, 1 - e_cos2]
    assert table["nu"].to_numpy() == pytest.approx(expected, rel=0.02)
    st = sobol(problem, lambda x: gradient(x)[0], n=2048).to_pandas(output="y")["ST"].to_numpy()
    assert np.all(table["ST_bound"].to_numpy() >= st - ref.SOBOL_ATOL)


def test_where_gives_ranges_and_interpolated_boundaries():
    from pneumact.sensitivity import where

    ranges = where([8.0, 0.5, 2.0, 32.0], [-1.0, 1.0, 1.0, 3.0])  # sorted: 0.5 2 8 32
    assert ranges[["x_from", "x_to"]].to_numpy().tolist() == [[0.5, 2.0], [32.0, 32.0]]
    assert np.isnan(ranges["lower"].iloc[0])  # holds from the start of the range studied
    assert ranges["upper"].iloc[0] == pytest.approx(4.0)  # margin 1 → −1: half-way in log
    assert ranges["lower"].iloc[1] == pytest.approx(8.0 * 4 ** 0.25)  # −1 → 3: a quarter
    assert np.isnan(ranges["upper"].iloc[1])
    assert where([1.0, 2.0], [-1.0, -2.0]).empty


def test_conditions_refuse_impossible_cycles():
    from pneumact.sensitivity import Condition

    for kwargs, message in (({"period": 0.0}, "period"), ({"amplitude": 1.5}, "amplitude"),
                            ({"valve": "pump"}, "valve")):
        with pytest.raises(ParameterError, match=message):
            Condition(**kwargs)
    assert Condition(80.0, 0.5, "source").label == "source, 80 s, amplitude 0.5"


def test_src_intervals_are_nil_for_an_exact_line_and_cover_the_noise_otherwise():
    """Issue #40: SRC² carries a bootstrap 95 % half-width. On an exact line every
    resample gives the same SRC²; with noise equal in variance to the signal of a weak
    input, its interval covers zero while the strong input's stays clear of it."""
    problem = Problem((Factor("strong", 0, 1, 0.5), Factor("weak", 0, 1, 0.5)))
    exact = src(problem, lambda x: pd.DataFrame({"y": x @ [2.0, 0.0]}), n=200)
    assert exact.to_pandas(output="y")["SRC2_conf"].max() < 1e-9
    rng = np.random.default_rng(3)
    noisy = src(problem, lambda x: pd.DataFrame(
        {"y": x @ [2.0, 0.02] + 0.3 * rng.standard_normal(len(x))}), n=200)
    table = noisy.to_pandas(output="y")
    assert table.loc["weak", "SRC2"] < table.loc["weak", "SRC2_conf"]
    assert table.loc["strong", "SRC2"] - table.loc["strong", "SRC2_conf"] > 0.5
