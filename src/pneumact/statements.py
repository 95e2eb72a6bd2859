"""The seed paper's statements as measurable claims, one parameter each, and the
conditions under which each holds.

A statement such as "σ2 is negligible" or "Fs and Fc matter most" is true or false only
under a condition: LuGre friction changes character around the Stribeck velocity vs, so
which parameters move the hysteresis loop depends on how fast the diaphragm slides. Each
claim of the paper is a small ``Statement`` object: the paper's words, *one* parameter,
the amount it is changed by, the measure and the comparison that the words mean, and so
the axis its conditions are read on. A sentence that names several parameters ("σ0, σ1
and vs shape the dynamics") is several statements, so one weak parameter does not sink
the others; a user adds a statement by making one (``evaluate_statements(...,
statements=[*STATEMENTS, mine])``, the study run with ``variations_for``).

Each statement is turned into a *margin* (positive where it holds) at each condition,
beside the *noise floor* of its measure there; a verdict is "holds" or "does not hold"
only where the margin is beyond the noise, "within noise" otherwise, and a boundary
between conditions is printed only where the margins on both sides are beyond it.

Measures (every threshold is stated in ``Statement.criterion`` and in the report):

* ``loop`` (Fig. 5, on v/vs): the one-at-a-time study across conditions
  (``sensitivity.across_conditions``). The change a variation makes to the loop is the
  largest of |Δ loop width|, |Δ break-away| (both relative to the nominal loop width in
  pressure) and |Δ presliding travel| at the reversal (relative to the loop width in
  position). It is *visible* (the paper's "important", "impact") from ``VISIBLE`` = 5 %
  on, and "little" or "negligible" below. Noise floor: the same measure between the
  nominal run and its rerun at a 100× tighter tolerance and on a shifted output grid
  (``loop_noise``). ``loop sliding``: the sliding part only (width and break-away).
* ``index`` (the conclusion, on v/vs): SRC² of the loop width per condition, noise its
  bootstrap 95 % half-width.
* ``friction dynamics`` / ``friction steady`` (Fig. 3, on the sine's amplitude in units
  of vs): the RMS change of the rest F − F_ss(v) / of the steady-state curve
  F_ss(v) = g(v) + σ2·v, relative to Fc; noise: the nominal run against a tighter
  tolerance.
* ``eq13`` (III.2): Fc fitted by eq. 13 to the model's own steady-state curve from a
  lowest speed (axis, in units of vs) to ``EQ13_TOP_SPEED``; a least-squares fit to an
  exact curve, so no noise.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .plotting import tight_layout

__all__ = ["COMPARISONS", "EQ13_FC_RTOL", "HEADLINE_VALVE", "LAW_CLAIMS", "LUGRE", "MEASURES",
           "SIGMA0_FACTORS",
           "STATEMENTS", "VISIBLE", "Statement", "eq13_bias", "evaluate_statements",
           "friction_effects", "friction_noise", "law_changes", "loop_changes", "loop_noise",
           "plot_loop_changes", "run_changes", "statement_texts", "summarise",
           "variations_for"]

#: A change of the loop is visible from this share of the loop's own width on.
VISIBLE = 0.05
#: Eq. 13 "holds" when the Fc it gives is within this share of the true Fc.
EQ13_FC_RTOL = 0.01
#: The fastest steady speed of the eq. 13 fit [m/s] (the campaign's fastest ramp).
EQ13_TOP_SPEED = 0.04
#: The six LuGre parameters of the paper's Figs. 3 and 5.
LUGRE = ("sigma0", "sigma1", "sigma2", "Fs", "Fc", "vs")
#: Fig. 5a: "important if we change its value from more than 50 %": σ0 × these factors.
SIGMA0_FACTORS = (0.1, 0.2, 0.5, 2.0, 5.0, 10.0)
LOOP_AXIS = "v/vs"
SINE_AXIS = "sine amplitude / vs"
EQ13_AXIS = "lowest speed / vs"
#: What a statement can measure, and the axis its conditions are read on.
MEASURES = {"loop": LOOP_AXIS, "loop sliding": LOOP_AXIS, "index": LOOP_AXIS,
            "friction dynamics": SINE_AXIS, "friction steady": SINE_AXIS,
            "eq13": EQ13_AXIS}
#: How a measured value is compared: against the visibility threshold, against other
#: parameters at the paper's amounts (``"above:Fc,sigma0"``, ``"below:sigma0"``,
#: ``"largest"`` of the six), or (eq13) the fitted Fc ``within`` EQ13_FC_RTOL.
COMPARISONS = ("visible", "little", "largest", "above:", "below:", "within")
_SYMBOL = {"sigma0": "σ0", "sigma1": "σ1", "sigma2": "σ2", "Fs": "Fs", "Fc": "Fc",
           "vs": "vs"}
_LOOP_WORDS = ("loop change (largest |Δ| of loop width and break-away over the loop width, "
               "of the presliding travel over the loop width in position)")
_MEASURE_WORDS = {
    "loop": _LOOP_WORDS,
    "loop sliding": "change of the loop width and the break-away (over the loop width)",
    "index": "SRC² of the loop width (global, over the study's ranges)",
    "friction dynamics": "RMS change of F − F_ss(v) over the sine's period, over Fc",
    "friction steady": "RMS change of F_ss(v) over the sine's period, over Fc",
    "eq13": f"error of the Fc eq. 13 gives (fit from the lowest speed to "
            f"{1e3 * EQ13_TOP_SPEED:g} mm/s)",
}


def _paper_amount(parameter: str) -> float:
    from .sensitivity import PAPER_VARIATIONS

    return float(PAPER_VARIATIONS[parameter])


@dataclass(frozen=True)
class Statement:
    """One claim of the paper about one parameter, as a measurable comparison.

    ``key``: a short name; ``source``: where the paper makes it; ``paper``: its words;
    ``parameter``: the one parameter it is about (``LUGRE``); ``factors``: what the
    parameter is multiplied by (empty: the paper's amount in both directions,
    ``sensitivity.PAPER_VARIATIONS``); ``measure``: one of ``MEASURES``;
    ``comparison``: one of ``COMPARISONS``; ``note``: what a reader should know beside
    the verdict."""

    key: str
    source: str
    paper: str
    parameter: str
    factors: tuple[float, ...] = ()
    measure: str = "loop"
    comparison: str = "visible"
    note: str = ""

    def __post_init__(self) -> None:
        from .errors import ArgumentError

        problems = []
        if self.parameter not in LUGRE:
            problems.append(f"parameter = {self.parameter!r}; allowed: {', '.join(LUGRE)}")
        if self.measure not in MEASURES:
            problems.append(f"measure = {self.measure!r}; allowed: {', '.join(MEASURES)}")
        if not (self.comparison in COMPARISONS or self.comparison.startswith(
                ("above:", "below:"))):
            problems.append(f"comparison = {self.comparison!r}; allowed: "
                            f"{', '.join(COMPARISONS)} (above:/below: name parameters)")
        for name in self._others():
            if name not in LUGRE:
                problems.append(f"comparison names {name!r}; allowed: {', '.join(LUGRE)}")
        if any(not (np.isfinite(f) and f > 0) for f in self.factors):
            problems.append(f"factors = {self.factors!r}; must be > 0")
        if self.factors and self.measure not in ("loop", "loop sliding"):
            problems.append(f"measure {self.measure!r} is taken at the paper's amounts; "
                            "give no factors")
        if problems:
            raise ArgumentError(f"Statement {self.key!r}: " + "; ".join(problems))

    def _others(self) -> list[str]:
        if self.comparison.startswith(("above:", "below:")):
            return [n.strip() for n in self.comparison.split(":", 1)[1].split(",")]
        return []

    @property
    def axis(self) -> str:
        """The axis its conditions are read on."""
        return MEASURES[self.measure]

    @property
    def amounts(self) -> tuple[float, ...]:
        """The factors the parameter is multiplied by."""
        if self.factors:
            return tuple(float(f) for f in self.factors)
        share = _paper_amount(self.parameter)
        return (1.0 - share, 1.0 + share)

    @property
    def amount(self) -> str:
        """The amount in words: ±50 % (the paper's), ×0.1, ..."""
        if self.measure in ("index", "eq13"):
            return "–"
        if not self.factors:
            whose = "ours: the paper names none" if self.parameter == "vs" else "paper"
            return f"±{100 * _paper_amount(self.parameter):g} % ({whose})"
        return ", ".join(f"×{f:g}" for f in self.factors)

    @property
    def criterion(self) -> str:
        """What we measure, in words."""
        name = _SYMBOL[self.parameter]
        what = _MEASURE_WORDS[self.measure]
        at = "" if self.measure in ("index", "eq13") else f"{name} {self.amount}: "
        others = ", ".join(_SYMBOL[n] for n in self._others())
        if self.comparison == "visible":
            return f"{at}{what} ≥ {100 * VISIBLE:g} %"
        if self.comparison == "little":
            return f"{at}{what} < {100 * VISIBLE:g} %"
        if self.comparison == "largest":
            return f"{at}{what} the largest of the six (each at the paper's amount)"
        if self.comparison.startswith("above:"):
            return f"{at}{what} of {name} above that of each of {others}"
        if self.comparison.startswith("below:"):
            return f"{at}{what} below that of {others} (at the paper's amount)"
        return f"{what} within {100 * EQ13_FC_RTOL:g} % of the true Fc"


def _sigma0_statement(factor: float) -> Statement:
    side = "softer" if factor < 1 else "stiffer"
    return Statement(f"5a_sigma0_x{factor:g}", "Fig. 5a",
                     "Variation in the value of σ0 is important if we change its value from "
                     "more than 50 %.", "sigma0", (factor,),
                     note=f"σ0 ×{factor:g}: a {side} bristle; the paper's words ask for a "
                          "visible change beyond ±50 %, in either direction")


_FIG3_DYNAMICS = ("It is seen that parameters σ0, σ1 and vs has influence on the dynamics "
                  "of the friction model.")
_FIG3_STEADY = "Whereas, other parameters effects the steady state error of the friction model."
_CONCLUSION = ("It is seen that model parameters Fs and Fc are more sensitive as compared to "
               "other parameters.")
_FS = ("Static friction is most important parameter as the variation in the value of 16 % "
       "has an impact on the hysteresis curve.")
_SIGMA1 = ("σ1 is less sensitive as compared to σ0 as the variation up to 68 % has little "
           "significance on the results.")
_PRESLIDING = ("Remaining two parameters (σ0 and σ1) are determined using non linear least "
               "squares approach. Since these parameters exert influence in the pre-sliding "
               "region, only.")
_OTHERS_THAN_FS_FC = "above:sigma0,sigma1,sigma2,vs"
STATEMENTS = (
    *(_sigma0_statement(f) for f in SIGMA0_FACTORS),
    Statement("5b_sigma1_little", "Fig. 5b", _SIGMA1, "sigma1", comparison="little"),
    Statement("5b_sigma1_below_sigma0", "Fig. 5b", _SIGMA1, "sigma1",
              comparison="below:sigma0"),
    Statement("5c_sigma2", "Fig. 5c",
              "Effect of σ2 is negligible as by changing its value up to 90 % produce little "
              "variation in the results.", "sigma2", comparison="little"),
    Statement("5d_Fs_visible", "Fig. 5d, e", _FS, "Fs"),
    Statement("5d_Fs_largest", "Fig. 5d, e", _FS, "Fs", comparison="largest"),
    Statement("5e_Fc", "Fig. 5e", "Coulomb friction is varied up to 15.36 % and its impact "
              "is shown in Fig. 5(e).", "Fc"),
    Statement("5f_vs", "Fig. 5f", "Increase or decrease in the stribeck velocity effects the "
              "results as we change it from nominal position.", "vs",
              note="the paper names no amount for vs; ±50 % is ours"),
    *(Statement(f"3_dynamics_{name}", "Fig. 3", _FIG3_DYNAMICS, name,
                measure="friction dynamics",
                note="vs is a parameter of the steady-state (Stribeck) curve g(v): its "
                     "steady change is in the Fig. 3 table" if name == "vs" else "")
      for name in ("sigma0", "sigma1", "vs")),
    *(Statement(f"3_steady_{name}", "Fig. 3", _FIG3_STEADY, name, measure="friction steady")
      for name in ("sigma2", "Fs", "Fc")),
    *(Statement(f"id_presliding_{name}", "III.2", _PRESLIDING, name, measure="loop sliding",
                comparison="little") for name in ("sigma0", "sigma1")),
    Statement("id_eq13", "III.2, eq. 13",
              "Preforming the test at v ≫ vs above equation can be simplified to find Fc and "
              "σ2 (eq. 13: Fact − Fsm = Fc·v/|v| + σ2·v).", "Fc", measure="eq13",
              comparison="within"),
    *(Statement(f"conclusion_oat_{name}", "III.A (Figs. 3, 5), V", _CONCLUSION, name,
                comparison=_OTHERS_THAN_FS_FC) for name in ("Fs", "Fc")),
    *(Statement(f"conclusion_global_{name}", "III.A, V", _CONCLUSION, name, measure="index",
                comparison=_OTHERS_THAN_FS_FC) for name in ("Fs", "Fc")),
)


def variations_for(params, statements: Iterable[Statement] = STATEMENTS
                   ) -> dict[str, list[tuple[float, float]]]:
    """The one-at-a-time variations (``one_at_a_time``'s ``variations``: (low, high) pairs
    in SI for ``params``) that the statements need: the paper's amount of every LuGre
    parameter, and each loop statement's own factors (one run each)."""
    wanted: dict[str, set[float]] = {name: set() for name in LUGRE}
    for statement in statements:
        if statement.measure in ("loop", "loop sliding") and statement.factors:
            wanted[statement.parameter] |= set(statement.amounts)
    out: dict[str, list[tuple[float, float]]] = {}
    for name in LUGRE:
        nominal = float(params[name])
        low, high = 1.0 - _paper_amount(name), 1.0 + _paper_amount(name)
        extra = sorted(f for f in wanted[name] if not np.isclose([low, high], f).any())
        out[name] = [(nominal * low, nominal * high), *((nominal * f, nominal * f)
                                                        for f in extra)]
    return out


# --------------------------------------------------------------------------- measures
def run_changes(study) -> pd.DataFrame:
    """Per condition, parameter and factor (the varied value over the nominal one) of a
    one-at-a-time ``ConditionStudy`` (features loop_width_pressure, breakaway_pressure,
    loop_width_position, presliding_travel): the change of the sliding part
    (``sliding``), of the corner (``corner``) and their larger (``change``), each on the
    loop's own scale."""
    frames = []
    for (_, condition), oat in zip(study.conditions.iterrows(), study.results, strict=True):
        runs = oat.runs
        nominal = runs.iloc[0]
        varied = runs[runs["parameter"] != "nominal"]
        width_p = abs(float(nominal["loop_width_pressure"]))
        width_x = abs(float(nominal["loop_width_position"]))
        sliding = np.maximum(varied["delta_loop_width_pressure"].abs(),
                             varied["delta_breakaway_pressure"].abs()) / width_p
        corner = varied["delta_presliding_travel"].abs() / width_x
        frames.append(pd.DataFrame({
            "condition": condition["condition"], "valve": condition["valve"],
            "period": condition["period"], "speed_vs": condition["speed_vs"],
            "parameter": varied["parameter"].to_numpy(),
            "factor": 1.0 + varied["change_%"].to_numpy(float) / 100,
            "sliding": sliding.to_numpy(float), "corner": corner.to_numpy(float),
            "change": np.maximum(sliding, corner).to_numpy(float)}))
    return pd.concat(frames, ignore_index=True)


def _at_factors(changes: pd.DataFrame, parameter: str, factors: Sequence[float]
                ) -> pd.DataFrame:
    """The rows of ``run_changes`` of ``parameter`` at ``factors``, the largest per
    condition."""
    rows = changes[(changes["parameter"] == parameter)
                   & np.isclose(changes["factor"].to_numpy()[:, None],
                                np.asarray(factors)[None, :], rtol=1e-9).any(axis=1)]
    return rows.groupby("condition", sort=False)[["sliding", "corner", "change"]].max()


def loop_changes(study) -> pd.DataFrame:
    """Per condition and parameter, the loop change at the paper's amount (both
    directions; ``run_changes`` has every factor): sliding, corner, change, with the
    condition's valve, period and v/vs."""
    changes = run_changes(study)
    frames = []
    for name in dict.fromkeys(changes["parameter"]):
        share = _paper_amount(name) if name in LUGRE else np.nan
        at = _at_factors(changes, name, (1.0 - share, 1.0 + share))
        frames.append(at.reset_index().assign(parameter=name))
    out = pd.concat(frames, ignore_index=True)
    columns = ["condition", "valve", "period", "speed_vs"]
    out = out.merge(study.conditions[columns], on="condition")
    order = {c: i for i, c in enumerate(study.conditions["condition"])}
    out = out.sort_values("condition", key=lambda c: c.map(order), kind="stable")
    return out[["condition", "parameter", "sliding", "corner", "change", "valve", "period",
                "speed_vs"]].reset_index(drop=True)


def loop_noise(model, conditions, *, tight_rtol: float = 1e-8) -> pd.DataFrame:
    """The noise floor of the loop measures at each condition: the nominal run against
    itself at a tolerance ``tight_rtol`` (default 100× tighter) and on an output grid
    1.37× as fine, in the same units as ``run_changes`` (sliding, corner, change: the
    largest of the two reruns)."""
    from .simulation import simulate
    from .simulation.solvers import Solver

    rows = []
    for condition in conditions:
        actuator = condition.model(model)
        experiment = condition.experiment(model.params)
        base = simulate(actuator, experiment)
        grid = np.linspace(base.time[0], base.time[-1], int(1.37 * base.time.size))
        reruns = [simulate(actuator, experiment, Solver(rtol=tight_rtol)).summary(),
                  simulate(actuator, experiment, t_eval=grid).summary()]
        nominal = base.summary()
        width_p = abs(nominal["loop_width_pressure"])
        width_x = abs(nominal["loop_width_position"])
        sliding = max(max(abs(r["loop_width_pressure"] - nominal["loop_width_pressure"]),
                          abs(r["breakaway_pressure"] - nominal["breakaway_pressure"]))
                      for r in reruns) / width_p
        corner = max(abs(r["presliding_travel"] - nominal["presliding_travel"])
                     for r in reruns) / width_x
        rows.append({"condition": condition.label, "sliding": sliding, "corner": corner,
                     "change": max(sliding, corner)})
    return pd.DataFrame(rows)


#: The paper's words on the friction law itself (section III.1, eq. 8), and the model
#: each is checked against: LuGre with δ = 1 replaced by Dahl, or by δ = 2.
LAW_CLAIMS = {
    "Dahl": "LuGre and Dahl model studied here shows similar results for simulation.",
    "δ = 2": "Eq. 8 prints exp(−|v|/vs) (δ = 1); the LuGre literature uses δ = 2.",
}


def law_changes(model, conditions, floor: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per condition, the loop change (``run_changes``' measure) when the friction law is
    replaced: Dahl for LuGre ("similar results", section III.1) and δ = 2 for δ = 1;
    with the noise floor (``loop_noise``) and a verdict: similar (below ``VISIBLE``),
    differs, or within noise."""
    import dataclasses

    from .models import Dahl
    from .simulation import simulate

    alternatives = {"Dahl": lambda m: dataclasses.replace(m, friction=Dahl()),
                    "δ = 2": lambda m: dataclasses.replace(
                        m, params=m.params.replace(delta=2.0))}
    noise = floor.set_index("condition")["change"] if floor is not None else None
    rows = []
    for condition in conditions:
        actuator = condition.model(model)
        experiment = condition.experiment(model.params)
        nominal = simulate(actuator, experiment).summary()
        for name, swap in alternatives.items():
            other = simulate(swap(actuator), experiment).summary()
            sliding = max(abs(other[k] - nominal[k]) for k in ("loop_width_pressure",
                                                                "breakaway_pressure"))
            sliding /= abs(nominal["loop_width_pressure"])
            corner = abs(other["presliding_travel"] - nominal["presliding_travel"]) / abs(
                nominal["loop_width_position"])
            change = max(sliding, corner)
            floor_here = float(noise.get(condition.label, np.nan)) if noise is not None \
                else np.nan
            verdict = _verdict(VISIBLE - change, floor_here)
            rows.append({"law": name, "paper": LAW_CLAIMS[name], "condition": condition.label,
                         "speed_vs": nominal["sliding_speed"] / model.params["vs"],
                         "loop change": change, "noise floor": floor_here,
                         "verdict": {"holds": "similar", "does not hold": "differs"}.get(
                             verdict, verdict)})
    return pd.DataFrame(rows)


def friction_noise(params, amplitudes_vs, period: float = 2.0, friction=None, *,
                   tight_rtol: float = 1e-8) -> pd.DataFrame:
    """The noise floor of Fig. 3's measures per amplitude: the RMS difference of the
    nominal friction at the default and a ``tight_rtol`` tolerance, relative to Fc."""
    from .experiments import Experiment, Sine
    from .models import FrictionRig, LuGre
    from .simulation import simulate
    from .simulation.solvers import Solver

    rig = FrictionRig(params, friction=LuGre() if friction is None else friction,
                      drive="velocity")
    rows = []
    for amplitude in amplitudes_vs:
        experiment = Experiment(Sine(float(amplitude) * params["vs"], 1.0 / period),
                                "velocity", 2 * period, n_points=4002)
        runs = [simulate(rig, experiment, solver)["friction"]
                for solver in (None, Solver(rtol=tight_rtol))]
        rows.append({"amplitude_vs": float(amplitude),
                     "noise": _rms(runs[1] - runs[0]) / params["Fc"]})
    return pd.DataFrame(rows)


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
@dataclass(frozen=True)
class _Measured:
    """One measure at every condition: where each condition sits (``meta``: condition,
    valve, x), the value of each parameter at the paper's amount (``paper``, condition ×
    parameter), its noise (``noise``: per condition, or per condition × parameter), and
    the values at other factors (``changes``: ``run_changes``, loop measures only)."""

    meta: pd.DataFrame
    paper: pd.DataFrame
    noise: pd.DataFrame
    column: str = ""
    changes: pd.DataFrame | None = None

    def value(self, statement: Statement) -> pd.Series:
        if not statement.factors or self.changes is None:
            return self.paper[statement.parameter]
        at = _at_factors(self.changes, statement.parameter, statement.amounts)[self.column]
        return at.reindex(self.paper.index)

    def noise_of(self, parameter: str) -> pd.Series:
        return self.noise[parameter] if parameter in self.noise else self.noise["all"]


def _loop_measure(oat_study, noise: pd.DataFrame | None, column: str) -> _Measured:
    changes = run_changes(oat_study)
    paper = loop_changes(oat_study).pivot(index="condition", columns="parameter",
                                          values=column)
    meta = oat_study.conditions.set_index("condition")[["valve", "speed_vs"]].rename(
        columns={"speed_vs": "x"})
    paper = paper.reindex(meta.index)
    floor = (noise.set_index("condition")[column].reindex(meta.index) if noise is not None
             else pd.Series(np.nan, index=meta.index))
    return _Measured(meta, paper, pd.DataFrame({"all": floor}), column, changes)


def _index_measure(global_study, index: str) -> _Measured:
    values = global_study.index("loop_width_pressure", index).abs()
    try:
        conf = global_study.index("loop_width_pressure", f"{index}_conf").abs()
    except Exception:  # a method without intervals
        conf = values * np.nan
    meta = global_study.conditions.set_index("condition")[["valve", "speed_vs"]].rename(
        columns={"speed_vs": "x"}).reindex(values.index)
    return _Measured(meta, values, conf)


def _friction_measure(effects: pd.DataFrame, noise: pd.DataFrame | None, column: str,
                      period: float) -> _Measured:
    paper = effects.pivot(index="amplitude_vs", columns="parameter", values=column)
    labels = [f"sine ±{a:g}·vs, {period:g} s" for a in paper.index]
    meta = pd.DataFrame({"valve": "", "x": paper.index.to_numpy(float)}, index=labels)
    paper.index = labels
    floor = (noise.set_index("amplitude_vs")["noise"].reindex(meta["x"]).to_numpy()
             if noise is not None else np.nan)
    return _Measured(meta, paper, pd.DataFrame({"all": floor}, index=labels), column)


def _eq13_measure(bias: pd.DataFrame) -> _Measured:
    labels = [f"{r:g}·vs … {1e3 * EQ13_TOP_SPEED:g} mm/s" for r in bias["lowest_vs"]]
    meta = pd.DataFrame({"valve": "", "x": bias["lowest_vs"].to_numpy(float)}, index=labels)
    paper = pd.DataFrame({"Fc": bias["Fc_error"].abs().to_numpy(float)}, index=labels)
    return _Measured(meta, paper, pd.DataFrame({"all": 0.0}, index=labels))


def _shown(statement: Statement, value: float) -> str:
    if statement.measure == "index":
        return f"{value:.2g}"
    return f"{100 * value:.3g} %"


def _compare(statement: Statement, measured: _Measured
             ) -> tuple[pd.Series, pd.Series, pd.Series]:
    """(margin, noise, what was measured in words) at each condition."""
    value = measured.value(statement)
    noise = measured.noise_of(statement.parameter)
    words = value.map(lambda v: _shown(statement, v))
    comparison = statement.comparison
    if comparison == "visible":
        return value - VISIBLE, noise, words
    if comparison == "little":
        return VISIBLE - value, noise, words
    if comparison == "within":
        return EQ13_FC_RTOL - value, noise, words
    if comparison == "largest":
        others = [n for n in measured.paper.columns if n != statement.parameter]
    else:
        others = statement._others()
    rival = measured.paper[others].idxmax(axis=1)
    top = measured.paper[others].max(axis=1)
    rival_noise = pd.Series([measured.noise_of(n).get(c, np.nan) if n == n else np.nan
                             for c, n in rival.items()], index=rival.index)
    words = pd.Series([f"{_SYMBOL[statement.parameter]} {_shown(statement, v)}, "
                       f"{_SYMBOL.get(r, r)} {_shown(statement, o)}"
                       for v, r, o in zip(value, rival, top, strict=True)], index=value.index)
    margin = top - value if comparison.startswith("below:") else value - top
    return margin, noise + rival_noise, words


def _verdict(margin: float, noise: float) -> str:
    if not np.isfinite(margin):
        return "not measured"
    if np.isfinite(noise) and abs(margin) <= noise:
        return "within noise"
    return "holds" if margin >= 0 else "does not hold"


def evaluate_statements(oat_study, global_study=None, effects: pd.DataFrame | None = None,
                        bias: pd.DataFrame | None = None, *,
                        statements: Sequence[Statement] = STATEMENTS,
                        loop_floor: pd.DataFrame | None = None,
                        friction_floor: pd.DataFrame | None = None,
                        index: str = "SRC2", fig3_period: float = 2.0) -> pd.DataFrame:
    """Every statement at every condition: statement, parameter, amount, condition,
    valve, axis, x (the condition on the axis), value (what was measured), margin
    (positive: it holds), noise (the measure's floor there: ``loop_noise``,
    ``friction_noise``, the index's bootstrap interval), verdict (holds, does not hold,
    within noise) and holds (margin ≥ 0). ``oat_study``: the one-at-a-time
    ``across_conditions`` study run with ``variations_for``'s variations; the global
    study (SRC across conditions), Fig. 3's ``friction_effects`` and eq. 13's
    ``eq13_bias`` are needed only by the statements that measure them."""
    from .errors import ArgumentError

    given = {"loop": oat_study, "loop sliding": oat_study, "index": global_study,
             "friction dynamics": effects, "friction steady": effects, "eq13": bias}
    missing = sorted({s.key for s in statements if given[s.measure] is None})
    if missing:
        raise ArgumentError(f"evaluate_statements: {', '.join(missing)} need a study that "
                            "was not given (global_study, effects or bias)")
    measures = {
        "loop": lambda: _loop_measure(oat_study, loop_floor, "change"),
        "loop sliding": lambda: _loop_measure(oat_study, loop_floor, "sliding"),
        "index": lambda: _index_measure(global_study, index),
        "friction dynamics": lambda: _friction_measure(effects, friction_floor, "dynamic",
                                                       fig3_period),
        "friction steady": lambda: _friction_measure(effects, friction_floor, "steady",
                                                     fig3_period),
        "eq13": lambda: _eq13_measure(bias),
    }
    made: dict[str, _Measured] = {}
    frames = []
    for statement in statements:
        if statement.measure not in made:
            made[statement.measure] = measures[statement.measure]()
        measured = made[statement.measure]
        margin, noise, words = _compare(statement, measured)
        frames.append(pd.DataFrame({
            "statement": statement.key, "parameter": statement.parameter,
            "amount": statement.amount, "condition": measured.meta.index,
            "valve": measured.meta["valve"].to_numpy(), "axis": statement.axis,
            "x": measured.meta["x"].to_numpy(float), "value": words.to_numpy(),
            "margin": margin.to_numpy(float), "noise": np.asarray(noise, dtype=float)}))
    table = pd.concat(frames, ignore_index=True)
    table["verdict"] = [_verdict(m, n) for m, n in zip(table["margin"], table["noise"],
                                                       strict=True)]
    table["holds"] = table["margin"] >= 0
    return table


# --------------------------------------------------------------------------- summary
def statement_texts(statements: Sequence[Statement] = STATEMENTS) -> pd.DataFrame:
    """One row per statement: where the paper makes it, its words, the parameter and
    amount, our criterion and what a reader should know beside it."""
    return pd.DataFrame([{"statement": s.key, "source": s.source, "paper": s.paper,
                          "parameter": s.parameter, "amount": s.amount,
                          "criterion": s.criterion, "note": s.note} for s in statements])


#: The valve whose verdict leads (the paper's Figs. 5–6 are position against the applied
#: pressure), then the others as further columns.
HEADLINE_VALVE = "source"
OTHER_VALVES = ("command", "regulator")


def summarise(per_condition: pd.DataFrame, statements: Sequence[Statement] = STATEMENTS
              ) -> pd.DataFrame:
    """One row per statement: the paper's words beside our criterion; where it holds on
    its axis under applied pressure (the source valve, the paper's Figs. 5–6; Fig. 3 and
    eq. 13 on their own axes), where it stops (a boundary only where the margins on both
    sides are beyond the noise floor), the noise floor, and where it holds behind the
    command valve and the regulator."""
    rows = []
    for statement in statements:
        sub = per_condition[per_condition["statement"] == statement.key]
        row = {"statement": statement.key, "source": statement.source,
               "paper": statement.paper, "criterion": statement.criterion}
        on_axis = statement.axis != LOOP_AXIS
        headline = sub if on_axis else sub[sub["valve"] == HEADLINE_VALVE]
        row["holds for"] = _holds_text(headline, statement.axis)
        row["stops"] = _stops_text(headline)
        row["noise floor"] = _noise_text(headline, statement)
        for valve in OTHER_VALVES:
            row[f"{valve} valve"] = "–" if on_axis else _holds_text(
                sub[sub["valve"] == valve], statement.axis, with_stops=True)
        rows.append(row)
    return pd.DataFrame(rows)


def _num(value: float) -> str:
    """A condition on its axis, two significant digits (plain up to 9999)."""
    return f"{value:.0f}" if 100 <= abs(value) < 1e4 else f"{value:.2g}"


def _sorted(sub: pd.DataFrame) -> pd.DataFrame:
    return sub.sort_values("x", kind="stable")


def _holds_text(sub: pd.DataFrame, axis: str, with_stops: bool = False) -> str:
    from .sensitivity import where

    if sub.empty:
        return "not studied"
    sub = _sorted(sub)
    span = f"{_num(sub['x'].min())}–{_num(sub['x'].max())}"
    ranges = where(sub["x"], sub["margin"])
    unclear = sub.loc[sub["verdict"] == "within noise", "x"]
    tail = (f"; within noise at {', '.join(_num(x) for x in unclear)}"
            if len(unclear) else "")
    if ranges.empty:
        text = f"nowhere in {axis} {span}"
    elif len(ranges) == 1 and np.isnan(ranges["lower"].iloc[0]) and \
            np.isnan(ranges["upper"].iloc[0]):
        text = f"all of {axis} {span} studied"
    else:
        parts = [_num(r.x_from) if r.x_from == r.x_to else f"{_num(r.x_from)}–{_num(r.x_to)}"
                 for r in ranges.itertuples()]
        text = f"{axis} {' and '.join(parts)} (of {span})"
        if with_stops:
            text += f"; stops {_stops_text(sub)}"
    return text + tail


def _stops_text(sub: pd.DataFrame) -> str:
    """The boundaries between conditions where the verdict changes sign: interpolated
    (two significant digits) where the margins on both sides exceed their noise floors,
    otherwise only the bracket."""
    if sub.empty:
        return "not studied"
    sub = _sorted(sub)
    x, m, n = (sub[c].to_numpy(float) for c in ("x", "margin", "noise"))
    stops = []
    for i in range(len(x) - 1):
        if (m[i] >= 0) == (m[i + 1] >= 0):
            continue
        side = "above" if m[i] >= 0 else "below"
        clear = all(abs(m[j]) > (n[j] if np.isfinite(n[j]) else 0.0) for j in (i, i + 1))
        if clear:
            stops.append(f"{side} ≈ {_num(_crossing(x[i], x[i + 1], m[i], m[i + 1]))}")
        else:
            stops.append(f"{side} somewhere in {_num(x[i])}–{_num(x[i + 1])} (margin within "
                         "noise)")
    return ", ".join(stops) or "no boundary in the range studied"


def _crossing(x0: float, x1: float, m0: float, m1: float) -> float:
    """Where the margin crosses zero between two conditions (linear in log x)."""
    share = m0 / (m0 - m1)
    return float(np.exp(np.log(x0) + share * (np.log(x1) - np.log(x0))))


def _noise_text(sub: pd.DataFrame, statement: Statement) -> str:
    noise = sub["noise"].to_numpy(float)
    if not len(noise) or not np.isfinite(noise).any():
        return "not measured"
    if np.nanmax(noise) == 0:
        return "exact (no sampling)"
    low, high = np.nanmin(noise), np.nanmax(noise)
    if statement.measure == "index":
        return f"± {low:.2g}–{high:.2g} (95 % bootstrap)"
    return f"{100 * low:.2g}–{100 * high:.2g} %" if high > low else f"{100 * high:.2g} %"


def plot_loop_changes(changes: pd.DataFrame, floor: pd.DataFrame | None = None):
    """The loop change of each parameter variation (% of the loop's width) against v/vs,
    a panel per valve, with the visibility line and (``floor``: ``loop_noise``) the
    noise floor."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, NullFormatter

    valves = list(dict.fromkeys(changes["valve"]))
    fig, axes = plt.subplots(1, len(valves), squeeze=False, sharey=True,
                             figsize=(min(4.6 * len(valves), 12.0), 3.8))
    for ax, valve in zip(axes[0], valves, strict=True):
        sub = changes[changes["valve"] == valve]
        for name, line in sub.groupby("parameter", sort=False):
            line = line.sort_values("speed_vs")
            ax.plot(line["speed_vs"], 100 * line["change"].clip(lower=1e-4), "o-", ms=3,
                    lw=1.2, label=name)
        if floor is not None:
            speeds = sub.drop_duplicates("condition").set_index("condition")["speed_vs"]
            noise = floor.set_index("condition")["change"].reindex(speeds.index)
            order = np.argsort(speeds.to_numpy())
            ax.fill_between(speeds.to_numpy()[order], 1e-4,
                            100 * noise.clip(lower=1e-4).to_numpy()[order], color="0.6",
                            alpha=0.35, label="noise floor")
        ax.axhline(100 * VISIBLE, color="k", lw=0.8, ls="--", label="visible (5 %)")
        ax.axvline(1.0, color="k", lw=0.6, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("sliding speed v / vs [1] (nominal run)")
        ax.set_ylabel("loop change [% of its width]")
        title = "applied pressure (source)" if valve == "source" else f"{valve} valve"
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    tight_layout(fig)
    return fig
