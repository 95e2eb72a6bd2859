"""The seed paper reproduced end to end: one call, one folder, one index report.

``reproduce()`` runs, on the built-in ``vgt-paper`` set (the paper's Table I):

1. Table I as loaded, with the values the paper does not give marked as assumed;
2. Fig. 2: LuGre friction against velocity, with the steady-state (Stribeck) curve;
3. Fig. 3: friction against velocity under each of the paper's parameter variations;
4. Fig. 5 a–f: pressure–position loops under the same variations, and the one-at-a-time
   table of feature changes;
5. the identification procedure of section III.2 on a synthetic bench campaign generated
   from Table I with measurement noise (the paper's bench data is not public);
6. Fig. 6: the identified model against a held-back synthetic record, with its metrics;
7. the sensitivity ranking (one at a time, SRC, Sobol) beside the paper's statements,
   each marked as agreeing or not, from the computed numbers.

``quick=True`` shrinks the campaign and the global samples for the test suite; every
figure and table is still produced.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["PAPER_STATEMENTS", "Reproduction", "reproduce"]

FEATURES = ("loop_width_pressure", "breakaway_pressure")
#: The paper's statements about which parameters matter, checked against our numbers.
PAPER_STATEMENTS = {
    "static": "Static friction is the most important parameter: a 16 % change of Fs "
              "changes the hysteresis curve (section IV, Fig. 5d).",
    "sigma2": "The effect of sigma2 is negligible: changing it by up to 90 % produces "
              "little variation (Fig. 5c).",
    "conclusion": "Fs and Fc are the parameters that matter most for the hysteresis.",
}
#: A parameter whose largest one-at-a-time change is below this share of the largest
#: parameter's is called negligible.
NEGLIGIBLE_SHARE = 0.10


@dataclass(frozen=True)
class Sizes:
    """How much work each part does (the quick mode shrinks the samples)."""

    ramp_speeds: tuple[float, ...]
    sweep_period: float
    src_n: int
    sobol_n: int

    @classmethod
    def full(cls) -> Sizes:
        return cls((1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 3e-2, 4e-2), 60.0, 512,
                   512)

    @classmethod
    def quick(cls) -> Sizes:
        return cls((2e-4, 1e-3, 5e-3, 2e-2), 30.0, 64, 32)


@dataclass(eq=False)
class Reproduction:
    """What ``reproduce`` computed (tables in SI) and the files it wrote."""

    out_dir: Path
    files: list[Path]
    tables: dict[str, pd.DataFrame]
    wall_time: float
    quick: bool
    identified: object = None

    @property
    def report(self) -> Path:
        return self.out_dir / "index.html"


@dataclass(eq=False)
class _Parts:
    """Tables, figures and report blocks gathered along the way."""

    report: object
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    writers: dict[str, Callable[[Path], object]] = field(default_factory=dict)

    def table(self, name: str, frame: pd.DataFrame, caption: str, index: bool = False):
        self.tables[name] = frame
        self.writers[f"{name}.csv"] = lambda p, f=frame: f.to_csv(p, index=index)
        self.report.table(frame, caption, index=index)

    def figure(self, name: str, make, caption: str):
        """Render once: the PNG file and the report's embedded copy."""
        from .io.report import figure_png

        png = figure_png(make(), dpi=120)
        self.writers[f"{name}.png"] = lambda p: Path(p).write_bytes(png)
        self.report.image(png, caption)


def reproduce(out_dir: str | os.PathLike = "pneumact-paper", *, quick: bool = False,
              params="vgt-paper", seed: int = 0, call: str = "",
              progress: Callable[[str], None] | None = None) -> Reproduction:
    """Reproduce the paper into ``out_dir`` (index.html, CSV tables, PNG figures)."""
    import matplotlib

    from .checks import check_bool, check_out_dir, check_seed
    from .errors import ArgumentTypeError

    check_out_dir("out_dir", out_dir, where="reproduce")
    check_bool("quick", quick, where="reproduce")
    check_seed("seed", seed, where="reproduce")
    if progress is not None and not callable(progress):
        raise ArgumentTypeError(f"reproduce: progress = {progress!r}: must be a function "
                                "progress(label)")
    from .errors import PassivityWarning
    from .io.report import Report
    from .io.tables import write_files
    from .parameters import ParameterSet, load_params
    from .parameters.validation import lugre_passivity_problem

    matplotlib.use("Agg")
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PassivityWarning)
        params = params if isinstance(params, ParameterSet) else load_params(params)
    passivity = [str(w.message) for w in caught if issubclass(w.category, PassivityWarning)]
    passivity = passivity or [lugre_passivity_problem(params.values) or ""]
    sizes = Sizes.quick() if quick else Sizes.full()
    step = progress or (lambda label: None)
    report = Report("LuGre friction in a pneumatic diaphragm actuator: the paper reproduced",
                    call=call or f"pneumact.reproduce(quick={quick}, seed={seed})",
                    parameters=params)
    parts = _Parts(report)
    report.text("Each section below recomputes one result of the seed paper from the "
                f"parameter set '{params.name}'. "
                + ("Quick mode: small campaign and samples (for tests); the numbers are "
                   "rough." if quick else ""))
    step("Table I")
    _table_one(parts, params, [text for text in passivity if text])
    step("Figs. 2 and 3")
    _friction_figures(parts, params)
    step("Fig. 5")
    oat = _loops_figure(parts, params)
    step("identification")
    identified = _identification(parts, params, sizes, seed)
    step("Fig. 6")
    _validation(parts, params, identified, sizes, seed)
    step("sensitivity")
    _sensitivity(parts, params, oat, sizes, seed)
    step("writing")
    parts.writers["index.html"] = report.write
    files = write_files(out_dir, parts.writers)
    return Reproduction(Path(out_dir), files, parts.tables, time.perf_counter() - started,
                        quick, identified.parameters)


# --------------------------------------------------------------------------- sections
def _table_one(parts: _Parts, params, passivity: list[str]) -> None:
    frame = params.to_frame()
    paper = frame["source"].str.startswith("paper")
    table = frame[paper | (frame["source"] == "assumed")][
        ["name", "value", "unit", "given", "source"]].copy()
    table["assumed"] = ~table["source"].str.startswith("paper")
    parts.report.heading("Table I: the parameter set as loaded")
    parts.report.text(f"{int(paper.sum())} values from the paper; {int(table['assumed'].sum())}"
                      " assumed where the paper gives none (marked). Values in SI.")
    parts.table("table_1", table, "Table I (SI), with the source of each value")
    for text in passivity:
        parts.report.note(f"Table I as published: {text}. We simulate it as given.")


def _friction_figures(parts: _Parts, params) -> None:
    from . import sensitivity as sa

    parts.report.heading("Figs. 2 and 3: LuGre friction against velocity")
    parts.figure("fig2_friction_velocity", lambda: _fig2(params),
                 "Fig. 2: friction of a velocity sine (±5 mm/s, 0.5 Hz; the bristles' "
                 "hysteresis) and the steady-state Stribeck curve")
    parts.figure("fig3_friction_variations", sa.friction_velocity(params).plot,
                 "Fig. 3: friction against velocity, each parameter at its low and high "
                 "value (the paper's amounts)")


def _fig2(params):
    import matplotlib.pyplot as plt

    from . import sensitivity as sa
    from .models import LuGre

    curves = sa.friction_velocity(params, {"Fc": 0.0})  # zero variation: the nominal run
    _, v, f = curves.curves["Fc"][0]
    grid = np.linspace(-5e-3, 5e-3, 801)
    fig, ax = plt.subplots(figsize=(6.5, 4.0))
    ax.plot(v * 1e3, f, "C0-", lw=1.2, label="LuGre, velocity sine")
    ax.plot(grid * 1e3, LuGre().steady_state(grid, params), "k--", lw=1,
            label="steady state (Stribeck curve + viscous)")
    ax.set_xlabel("velocity [mm/s]")
    ax.set_ylabel("friction [N]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _loops_figure(parts: _Parts, params):
    from . import sensitivity as sa
    from .experiments import CommandCycle
    from .models import Actuator, CommandValve

    model = Actuator(params, valve=CommandValve())
    oat = sa.one_at_a_time(model, CommandCycle(period=20.0))
    parts.report.heading("Fig. 5 a–f: pressure–position loops under the paper's variations")
    parts.figure("fig5_loops", oat.plot_loops,
                 "Fig. 5: one panel per parameter, varied by the paper's amounts (σ0 50 %, "
                 "σ1 68 %, σ2 90 %, Fs 16 %, Fc 15.36 %, vs 50 %), 20 s command cycle")
    parts.table("oat_runs", oat.runs, "One at a time (eq. 15): features of every run and "
                                      "their change against the nominal run (SI)")
    return oat


def _identification(parts: _Parts, params, sizes: Sizes, seed: int):
    from .identification import Noise, identify_paper, paper_campaign, synthetic_campaign

    tests = paper_campaign(params, speeds=sizes.ramp_speeds, sweep_period=sizes.sweep_period)
    noise = Noise()
    records = synthetic_campaign(params, tests, noise=noise, seed=seed)
    identified = identify_paper(records, params)
    parts.report.heading("Identification (section III.2) on a synthetic bench campaign")
    parts.report.note(
        "Synthetic data: the paper's bench records are not public, so the campaign is "
        f"simulated from Table I ({len(records)} records: a quasi-static sweep, "
        f"{len(sizes.ramp_speeds)} ramp pairs from {1e3 * min(sizes.ramp_speeds):g} to "
        f"{1e3 * max(sizes.ramp_speeds):g} mm/s, a presliding test) with measurement noise "
        f"(pressure {noise.pressure:g} Pa, position {1e6 * noise.position:g} µm, seed {seed}).")
    table = identified.table(params).reset_index()
    parts.table("identification", table, "Identified parameters beside Table I (truth), "
                "with standard errors and 95 % intervals")
    missed = table.loc[~table["truth_in_ci95"], "parameter"].tolist()
    if missed:
        parts.report.note(f"Table I's value lies outside the 95 % interval for: "
                          f"{', '.join(missed)} (the interval reflects noise only, not the "
                          "bias of the staged procedure).")
    for name, stage in identified.stages.items():
        parts.figure(f"identification_{name}", stage.plot, stage.title)
    return identified


def _validation(parts: _Parts, params, identified, sizes: Sizes, seed: int) -> None:
    from .identification import paper_campaign, synthetic_campaign
    from .models import Actuator, PressureRegulator
    from .validation import validate

    sweep = paper_campaign(params, speeds=(), sweep_period=2 * sizes.sweep_period)[:1]
    held_back = synthetic_campaign(params, sweep, seed=seed + 1)
    model = Actuator(identified.parameters, valve=PressureRegulator())
    validation = validate(model, held_back, signals=("position", "pressure"))
    parts.report.heading("Fig. 6: the identified model against a held-back record")
    parts.report.text(f"A sweep of {2 * sizes.sweep_period:g} s (twice the identification "
                      "sweep's period, its own noise), never used in the identification; "
                      "the identified model is driven by its logged regulator set-point.")
    parts.figure("fig6_validation", validation.plot_loops,
                 "Fig. 6: measured (synthetic, dashed) and predicted hysteresis loops")
    parts.table("validation_metrics", validation.metrics(), "Error metrics (SI)")
    parts.table("validation_loops", validation.loops(), "Loop measures, model against "
                                                        "measurement (SI)")


def _sensitivity(parts: _Parts, params, oat, sizes: Sizes, seed: int) -> None:
    from . import sensitivity as sa
    from .experiments import CommandCycle
    from .models import Actuator, CommandValve

    model = Actuator(params, valve=CommandValve())
    problem = sa.Problem.around(params, sa.DEFAULT_RANGES)
    evaluate = sa.model_outputs(model, CommandCycle(period=20.0), problem, FEATURES)
    with warnings.catch_warnings():  # small quick samples: their warnings go in the table
        warnings.simplefilter("ignore", sa.SensitivityWarning)
        src = sa.src(problem, evaluate, sizes.src_n, seed)
        sobol = sa.sobol(problem, evaluate, sizes.sobol_n, seed=seed)
    ranking = ranking_table(oat, src, sobol)
    parts.report.heading("Sensitivity: which parameters matter")
    parts.report.text(
        "One at a time with the paper's amounts (|Δ| against nominal), SRC (eq. 14, "
        f"{sizes.src_n} runs) and Sobol total indices ({len(sobol.sample)} runs) over "
        "±20 % of σ0, σ1, σ2, vs and ±10 % of Fc, Fs, on the loop width in pressure and "
        "the break-away pressure of the 20 s command cycle.")
    parts.table("sensitivity_ranking", ranking, "Rank of each parameter (1 = most "
                "influential) per method and feature, with the value ranked by")
    statements = check_statements(oat, sobol)
    parts.table("paper_statements", statements, "The paper's statements against our numbers")
    for _, row in statements[~statements["agrees"]].iterrows():
        parts.report.note(f"We disagree with the paper: “{row['paper']}” Our numbers: "
                          f"{row['ours']}")
    for feature in FEATURES:
        parts.figure(f"sobol_{feature}", lambda f=feature: sobol.plot(f),
                     f"Sobol S1 and ST of {feature}, with 95 % confidence intervals")


def ranking_table(oat, src, sobol) -> pd.DataFrame:
    """Long table: method, feature, parameter, value, rank (1 = most influential)."""
    rows = []
    for feature in FEATURES:
        per_method = {"one at a time |Δ|": oat.ranking(feature),
                      "SRC²": src.table(feature)["SRC2"],
                      "Sobol ST": sobol.table(feature)["ST"]}
        for method, values in per_method.items():
            ordered = values.abs().sort_values(ascending=False)
            for rank, (name, value) in enumerate(ordered.items(), start=1):
                rows.append({"method": method, "feature": feature, "parameter": name,
                             "value": float(value), "rank": rank})
    return pd.DataFrame(rows)


def check_statements(oat, sobol) -> pd.DataFrame:
    """Each of ``PAPER_STATEMENTS`` with what our numbers say and whether they agree."""
    width = oat.ranking("loop_width_pressure")
    top = width.index[0]
    sigma2_share = float(width["sigma2"] / width.iloc[0])
    top_two = {feature: list(sobol.table(feature)["ST"].sort_values(ascending=False)
                             .index[:2]) for feature in FEATURES}
    both = all(set(names) == {"Fs", "Fc"} for names in top_two.values())
    return pd.DataFrame([
        {"statement": "static", "paper": PAPER_STATEMENTS["static"],
         "ours": f"the largest change of the loop width comes from {top} "
                 f"({width.iloc[0]:.4g} Pa); Fs changes it by {width['Fs']:.4g} Pa",
         "agrees": top == "Fs"},
        {"statement": "sigma2", "paper": PAPER_STATEMENTS["sigma2"],
         "ours": f"σ2 ±90 % changes the loop width by {100 * sigma2_share:.3g} % of the "
                 f"largest parameter's change",
         "agrees": sigma2_share < NEGLIGIBLE_SHARE},
        {"statement": "conclusion", "paper": PAPER_STATEMENTS["conclusion"],
         "ours": "; ".join(f"the two largest Sobol ST of {f}: {', '.join(n)}"
                           for f, n in top_two.items()),
         "agrees": both},
    ])
