"""The seed paper's statements as measurable claims, and the conditions under which each
holds.

A statement such as "σ2 is negligible" or "Fs and Fc matter most" is true or false only
under a condition: LuGre friction changes character around the Stribeck velocity vs, so
which parameters move the hysteresis loop depends on how fast the diaphragm slides. Each
statement here is turned into a *margin* (positive where it holds) computed from a study
at each condition, and the conditions where the margin is positive are summarised as
ranges of the condition's axis (v/vs for the loops) with the boundaries interpolated.

What is measured (every threshold is stated in ``criterion`` and in the report):

* Fig. 5 and the identification: the one-at-a-time study at the paper's amounts across
  conditions (``sensitivity.across_conditions``). The change a variation makes to the
  loop is the largest of |Δ loop width|, |Δ break-away| (both relative to the nominal
  loop width in pressure) and |Δ presliding travel| at the reversal (relative to the
  loop width in position): the sliding part and the corners, on the loop's own scale.
  It is *visible* (the paper's "important", "impact") from ``VISIBLE`` = 5 % on, and
  "little" or "negligible" below.
* The conclusion: a global index of the loop width (SRC², Sobol ST, ...) per condition.
* Fig. 3: the friction law under a velocity sine; the change of its steady-state curve
  F_ss(v) = g(v) + σ2·v and the change of the rest (F − F_ss(v): the dynamics), RMS over
  a period, relative to Fc; axis: the sine's amplitude in units of vs.
* Eq. 13: Fc and σ2 fitted by eq. 13 to the model's own steady-state curve over speeds
  from a lowest speed (axis, in units of vs) to ``EQ13_TOP_SPEED``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

__all__ = ["EQ13_FC_RTOL", "STATEMENTS", "VISIBLE", "Statement", "eq13_bias",
           "evaluate_statements", "friction_effects", "loop_changes", "plot_loop_changes",
           "statement_texts", "summarise"]

#: A change of the loop is visible from this share of the loop's own width on.
VISIBLE = 0.05
#: Eq. 13 "holds" when the Fc it gives is within this share of the true Fc.
EQ13_FC_RTOL = 0.01
#: The fastest steady speed of the eq. 13 fit [m/s] (the campaign's fastest ramp).
EQ13_TOP_SPEED = 0.04
#: The six LuGre parameters of the paper's Figs. 3 and 5.
LUGRE = ("sigma0", "sigma1", "sigma2", "Fs", "Fc", "vs")
DYNAMIC = ("sigma0", "sigma1", "vs")
STEADY = ("sigma2", "Fs", "Fc")


@dataclass(frozen=True)
class Statement:
    """One claim of the paper: where it is made, its words, what we measure, and on
    which axis its conditions are read."""

    key: str
    source: str
    paper: str
    criterion: str
    axis: str


LOOP_AXIS = "v/vs"
_CHANGE = ("the loop change (largest |Δ| of loop width and break-away over the loop width, "
           "of the presliding travel over the loop width in position) is")
STATEMENTS = (
    Statement("5a_sigma0", "Fig. 5a",
              "Variation in the value of σ0 is important if we change its value from more "
              "than 50 %.",
              f"σ0 ±50 %: {_CHANGE} ≥ {100 * VISIBLE:g} %", LOOP_AXIS),
    Statement("5b_sigma1", "Fig. 5b",
              "σ1 is less sensitive as compared to σ0 as the variation up to 68 % has little "
              "significance on the results.",
              f"σ1 ±68 %: {_CHANGE} < {100 * VISIBLE:g} % and below that of σ0 ±50 %",
              LOOP_AXIS),
    Statement("5c_sigma2", "Fig. 5c",
              "Effect of σ2 is negligible as by changing its value up to 90 % produce little "
              "variation in the results.",
              f"σ2 ±90 %: {_CHANGE} < {100 * VISIBLE:g} %", LOOP_AXIS),
    Statement("5d_Fs", "Fig. 5d, e",
              "Static friction is most important parameter as the variation in the value of "
              "16 % has an impact on the hysteresis curve.",
              f"Fs ±16 %: {_CHANGE} ≥ {100 * VISIBLE:g} % and the largest of the six",
              LOOP_AXIS),
    Statement("5e_Fc", "Fig. 5e",
              "Coulomb friction is varied up to 15.36 % and its impact is shown.",
              f"Fc ±15.36 %: {_CHANGE} ≥ {100 * VISIBLE:g} %", LOOP_AXIS),
    Statement("5f_vs", "Fig. 5f",
              "Increase or decrease in the Stribeck velocity effects the results.",
              f"vs ±50 %: {_CHANGE} ≥ {100 * VISIBLE:g} %", LOOP_AXIS),
    Statement("3_dynamics", "Fig. 3",
              "Parameters σ0, σ1 and vs have influence on the dynamics of the friction "
              "model.",
              f"each of σ0 ±50 %, σ1 ±68 %, vs ±50 % changes F − F_ss(v) by ≥ "
              f"{100 * VISIBLE:g} % of Fc (RMS over the sine's period)",
              "sine amplitude / vs"),
    Statement("3_steady", "Fig. 3",
              "Other parameters [σ2, Fs, Fc] effect the steady state of the friction model.",
              f"each of σ2 ±90 %, Fs ±16 %, Fc ±15.36 % changes F_ss(v) by ≥ "
              f"{100 * VISIBLE:g} % of Fc (RMS over the sine's period)",
              "sine amplitude / vs"),
    Statement("id_presliding", "III.2",
              "σ0 and σ1 exert influence in the presliding region only.",
              f"σ0 ±50 % and σ1 ±68 % change the loop width and the break-away by < "
              f"{100 * VISIBLE:g} % of the loop width", LOOP_AXIS),
    Statement("id_eq13", "III.2, eq. 13",
              "With v ≫ vs, eq. 13 (Fact − Fsm = Fc·sgn(v) + σ2·v) identifies Fc and σ2.",
              f"Fc from eq. 13 fitted over lowest speed … {1e3 * EQ13_TOP_SPEED:g} mm/s "
              f"within {100 * EQ13_FC_RTOL:g} % of the true Fc", "lowest speed / vs"),
    Statement("conclusion_oat", "III.A (Figs. 3, 5), V",
              "Model parameters Fs and Fc are more sensitive as compared to other "
              "parameters.",
              f"at the paper's amounts the two largest loop changes are those of Fs and Fc, "
              f"each ≥ {100 * VISIBLE:g} %", LOOP_AXIS),
    Statement("conclusion_global", "III.A, V",
              "Model parameters Fs and Fc are more sensitive as compared to other "
              "parameters.",
              f"the two largest global indices of the loop width are those of Fs and Fc, "
              f"each ≥ {VISIBLE:g}", LOOP_AXIS),
)


# --------------------------------------------------------------------------- measures
def loop_changes(study) -> pd.DataFrame:
    """Per condition and parameter of a one-at-a-time ``ConditionStudy`` (features
    loop_width_pressure, breakaway_pressure, loop_width_position, presliding_travel):
    the change of the sliding part (``sliding``), of the corner (``corner``) and their
    larger (``change``), each on the loop's own scale."""
    wide = study.indices.pivot_table(index=["condition", "parameter"], columns="output",
                                     values="max_abs_change")
    nominal = study.conditions.set_index("condition")
    width_p = nominal["nominal_loop_width_pressure"].reindex(
        wide.index.get_level_values("condition")).to_numpy()
    width_x = nominal["nominal_loop_width_position"].reindex(
        wide.index.get_level_values("condition")).to_numpy()
    sliding = np.maximum(wide["loop_width_pressure"], wide["breakaway_pressure"]) / width_p
    corner = wide["presliding_travel"] / width_x
    out = pd.DataFrame({"sliding": sliding, "corner": corner,
                        "change": np.maximum(sliding, corner)}).reset_index()
    columns = ["condition", "valve", "period", "speed_vs"]
    return out.merge(study.conditions[columns], on="condition")


def friction_effects(params, amplitudes_vs, period: float = 2.0, friction=None
                     ) -> pd.DataFrame:
    """Fig. 3 across velocity amplitudes (in units of vs, at a sine of ``period``): per
    amplitude and parameter, the RMS change of the steady-state curve (``steady``) and
    of the rest (``dynamic``), relative to Fc, at the paper's amounts."""
    from .models import LuGre
    from .sensitivity import friction_velocity

    law = LuGre() if friction is None else friction
    rows = []
    for amplitude in amplitudes_vs:
        curves = friction_velocity(params, period=period, friction=law,
                                   amplitude=float(amplitude) * params["vs"])
        for name, entries in curves.curves.items():
            _, v0, f0 = entries[0]
            steady0 = law.steady_force(v0, params)
            dynamic = steady = 0.0
            for (_, v, f), sign in zip(entries[1:], (-1.0, 1.0), strict=True):
                varied = params.replace(**{name: _varied(params, name, sign)})
                steady1 = law.steady_force(v, varied)
                dynamic = max(dynamic, _rms((f - steady1) - (f0 - steady0)))
                steady = max(steady, _rms(steady1 - steady0))
            rows.append({"amplitude_vs": float(amplitude), "parameter": name,
                         "dynamic": dynamic / params["Fc"], "steady": steady / params["Fc"]})
    return pd.DataFrame(rows)


def _varied(params, name: str, sign: float) -> float:
    from .sensitivity import PAPER_VARIATIONS

    return params[name] * (1 + sign * PAPER_VARIATIONS[name])


def _rms(values) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def eq13_bias(params, lowest_vs, friction=None, points: int = 20) -> pd.DataFrame:
    """Eq. 13 fitted (least squares, both directions) to the steady-state friction at
    ``points`` speeds from each lowest speed (in units of vs) to ``EQ13_TOP_SPEED``: the
    relative errors of the Fc and σ2 it gives."""
    from .models import LuGre

    law = LuGre() if friction is None else friction
    rows = []
    for lowest in lowest_vs:
        speeds = np.geomspace(float(lowest) * params["vs"], EQ13_TOP_SPEED, points)
        v = np.concatenate([-speeds[::-1], speeds])
        design = np.column_stack([np.sign(v), v])
        (fc, sigma2), *_ = np.linalg.lstsq(design, law.steady_force(v, params), rcond=None)
        rows.append({"lowest_vs": float(lowest), "Fc_error": fc / params["Fc"] - 1,
                     "sigma2_error": sigma2 / params["sigma2"] - 1})
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- margins
def _fig5_margins(changes: pd.DataFrame) -> list[dict]:
    rows = []
    for condition, sub in changes.groupby("condition", sort=False):
        change = sub.set_index("parameter")["change"]
        sliding = sub.set_index("parameter")["sliding"]
        others = change.drop("Fs")
        margins = {
            "5a_sigma0": (change["sigma0"], change["sigma0"] - VISIBLE),
            "5b_sigma1": (change["sigma1"], min(VISIBLE - change["sigma1"],
                                                change["sigma0"] - change["sigma1"])),
            "5c_sigma2": (change["sigma2"], VISIBLE - change["sigma2"]),
            "5d_Fs": (change["Fs"], min(change["Fs"] - VISIBLE,
                                        change["Fs"] - others.max())),
            "5e_Fc": (change["Fc"], change["Fc"] - VISIBLE),
            "5f_vs": (change["vs"], change["vs"] - VISIBLE),
            "id_presliding": (max(sliding["sigma0"], sliding["sigma1"]),
                              VISIBLE - max(sliding["sigma0"], sliding["sigma1"])),
        }
        ranked = change.sort_values(ascending=False)
        both = min(change["Fs"], change["Fc"])
        margins["conclusion_oat"] = (f"{ranked.index[0]}, {ranked.index[1]}",
                                     min(both - VISIBLE,
                                         both - change.drop(["Fs", "Fc"]).max()))
        first = sub.iloc[0]
        for key, (value, margin) in margins.items():
            rows.append({"statement": key, "condition": condition, "valve": first["valve"],
                         "axis": LOOP_AXIS, "x": first["speed_vs"],
                         "value": value if isinstance(value, str) else float(value),
                         "margin": float(margin)})
    return rows


def _conclusion_margins(global_study, index: str | None) -> list[dict]:
    table = global_study.index("loop_width_pressure", index).abs()
    conditions = global_study.conditions.set_index("condition")
    rows = []
    for condition, row in table.iterrows():
        others = row.drop(["Fs", "Fc"])
        top = row.sort_values(ascending=False)
        both = min(row["Fs"], row["Fc"])
        rows.append({"statement": "conclusion_global", "condition": condition,
                     "valve": conditions.loc[condition, "valve"], "axis": LOOP_AXIS,
                     "x": conditions.loc[condition, "speed_vs"],
                     "value": f"{top.index[0]}, {top.index[1]}",
                     "margin": float(min(both - VISIBLE, both - others.max()))})
    return rows


def _fig3_margins(effects: pd.DataFrame, period: float) -> list[dict]:
    rows = []
    for amplitude, sub in effects.groupby("amplitude_vs"):
        sub = sub.set_index("parameter")
        dynamic = sub.loc[list(DYNAMIC), "dynamic"]
        steady = sub.loc[list(STEADY), "steady"]
        for key, values in (("3_dynamics", dynamic), ("3_steady", steady)):
            weakest = values.idxmin()
            rows.append({"statement": key, "condition": f"sine ±{amplitude:g}·vs, "
                                                        f"{period:g} s",
                         "valve": "", "axis": "sine amplitude / vs", "x": float(amplitude),
                         "value": f"weakest {weakest}: {100 * values.min():.3g} % of Fc",
                         "margin": float(values.min() - VISIBLE)})
    return rows


def _eq13_margins(bias: pd.DataFrame) -> list[dict]:
    return [{"statement": "id_eq13", "condition": f"{r.lowest_vs:g}·vs … "
                                                  f"{1e3 * EQ13_TOP_SPEED:g} mm/s",
             "valve": "", "axis": "lowest speed / vs", "x": r.lowest_vs,
             "value": f"Fc {100 * r.Fc_error:+.3g} %, σ2 {100 * r.sigma2_error:+.3g} %",
             "margin": EQ13_FC_RTOL - abs(r.Fc_error)} for r in bias.itertuples()]


def evaluate_statements(oat_study, global_study, effects: pd.DataFrame, bias: pd.DataFrame,
                        *, index: str | None = None, fig3_period: float = 2.0
                        ) -> pd.DataFrame:
    """Every statement at every condition: statement, condition, valve, axis, x (the
    condition on the axis), value (what was measured), margin, holds."""
    rows = [*_fig5_margins(loop_changes(oat_study)),
            *_conclusion_margins(global_study, index),
            *_fig3_margins(effects, fig3_period), *_eq13_margins(bias)]
    table = pd.DataFrame(rows)
    table["value"] = table["value"].map(lambda v: f"{100 * v:.3g} %"
                                        if isinstance(v, float) else v)
    table["holds"] = table["margin"] >= 0
    order = {s.key: i for i, s in enumerate(STATEMENTS)}
    return table.sort_values(["statement", "valve", "x"], key=lambda c: c.map(order)
                             if c.name == "statement" else c, kind="stable"
                             ).reset_index(drop=True)


# --------------------------------------------------------------------------- summary
def statement_texts() -> pd.DataFrame:
    """One row per statement: where the paper makes it, its words, and our criterion."""
    return pd.DataFrame([{"statement": s.key, "source": s.source, "paper": s.paper,
                          "criterion": s.criterion} for s in STATEMENTS])


def summarise(per_condition: pd.DataFrame, reference: dict[str, str] | None = None
              ) -> pd.DataFrame:
    """One row per statement (and valve): the axis of its condition, the range of that
    axis where it holds, where it stops, and whether it holds at the ``reference``
    condition of each statement (its label, e.g. the reproduction's own cycle); the words
    and criteria are in ``statement_texts()``."""
    from .sensitivity import where

    reference = reference or {}
    by_key = {s.key: s for s in STATEMENTS}
    rows = []
    for (key, valve), sub in per_condition.groupby(["statement", "valve"], sort=False):
        statement = by_key[key]
        ranges = where(sub["x"], sub["margin"])
        span = f"{sub['x'].min():.3g}–{sub['x'].max():.3g}"
        at = sub[sub["condition"] == reference.get(key)]
        rows.append({"statement": key, "source": statement.source,
                     "valve": valve or "–", "axis": statement.axis,
                     "holds for": _holds_text(ranges, statement.axis, span, len(sub)),
                     "stops": _stops_text(ranges),
                     "at our cycle": _at_text(at)})
    return pd.DataFrame(rows)


def _at_text(at: pd.DataFrame) -> str:
    if not len(at):
        return "not studied"
    return "holds" if bool(at["holds"].iloc[0]) else "does not hold"


def _holds_text(ranges: pd.DataFrame, axis: str, span: str, count: int) -> str:
    if ranges.empty:
        return f"nowhere in {axis} {span}"
    if len(ranges) == 1 and np.isnan(ranges["lower"].iloc[0]) and \
            np.isnan(ranges["upper"].iloc[0]):
        return f"all of {axis} {span} studied"
    parts = [f"{r.x_from:.3g}" if r.x_from == r.x_to else f"{r.x_from:.3g}–{r.x_to:.3g}"
             for r in ranges.itertuples()]
    return f"{axis} {' and '.join(parts)} (of {span})"


def _stops_text(ranges: pd.DataFrame) -> str:
    stops = []
    for r in ranges.itertuples():
        if np.isfinite(r.lower):
            stops.append(f"below ≈ {r.lower:.3g}")
        if np.isfinite(r.upper):
            stops.append(f"above ≈ {r.upper:.3g}")
    return ", ".join(stops) or "no boundary in the range studied"


def plot_loop_changes(changes: pd.DataFrame):
    """The loop change of each parameter variation (% of the loop's width) against v/vs,
    a panel per valve, with the visibility line."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, NullFormatter

    valves = list(dict.fromkeys(changes["valve"]))
    fig, axes = plt.subplots(1, len(valves), squeeze=False,
                             figsize=(min(4.6 * len(valves), 12.0), 3.8))
    for ax, valve in zip(axes[0], valves, strict=True):
        sub = changes[changes["valve"] == valve]
        for name, line in sub.groupby("parameter", sort=False):
            line = line.sort_values("speed_vs")
            ax.plot(line["speed_vs"], 100 * line["change"].clip(lower=1e-4), "o-", ms=3,
                    lw=1.2, label=name)
        ax.axhline(100 * VISIBLE, color="k", lw=0.8, ls="--", label="visible (5 %)")
        ax.axvline(1.0, color="k", lw=0.6, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("sliding speed v / vs (nominal run)")
        ax.set_ylabel("loop change [% of its width]")
        ax.set_title(f"{valve} valve", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig
