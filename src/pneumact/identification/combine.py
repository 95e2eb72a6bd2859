"""Two rounds of identification of one actuator, combined per parameter (issue 38).

A second round designed from the first (``rounds.next_round``) gains some parameters
and can lose others: its identification starts from its own records. Both rounds are
independent measurements of one actuator (other records, other noise), so their
results combine, parameter by parameter (``combine_rounds(first, second)``):

- a value with a reported interval in one round only (identified, or poorly identified
  with a finite interval) is taken from that round, with its interval and verdict;
- a value with an interval in both rounds is the inverse-variance weighted mean, with
  the interval of that mean, when the two agree: |a − b| ≤ ``CONSISTENCY_Z`` ·
  √(σa² + σb²); its verdict is judged again from the combined interval (the rules of
  ``diagnostics.verdicts``). When they do not agree, the parameter is refused ("the
  rounds disagree", poorly identified): one of them is wrong, and a weighted mean of a
  wrong value and a right one is a wrong value with a tight interval. What it reports
  instead is the interval that covers both rounds' intervals, about its middle (as
  ``optima.cover_optima`` does for two optima of one fit): the truth is not known to be
  nearer either;
- a parameter without an interval in either round keeps the better of the two verdicts
  (identified, poorly identified, not identifiable; the later round on a tie) with its
  reason and remedy, and no interval.

Each value says its round ("1", "2" or "1+2") in ``to_pandas``, ``summary``, the
report and identified.toml.

What the per-parameter rule neglects: the estimates of one joint fit are correlated
(F0 with k, Fs with vs, σ0 with σ1), and a generalised least-squares combination of the
two rounds' vectors would let a parameter one round pins down sharpen a correlated one
that it does not; the weighted mean per parameter gives that up. It is never
overconfident for it: the rounds are independent, so the variance of each weighted
mean is exact, and the covariance of the combined vector is computed from the rounds'
covariances with the weights used (cov = W₁C₁W₁ + W₂C₂W₂), correlations within a
round kept. The combined set is not fitted to the records again: a pair from two
rounds (Fs from one, vs from the other) is not the optimum of either round's records,
so the result draws no prediction band. The rounds' covariances also give a joint
consistency test of every parameter combined (a χ² test of the differences with
C₁ + C₂): a disagreement along a correlated direction, which no single parameter
shows, is named as a warning.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import DataError, ParameterError
from ..plotting import tight_layout
from .diagnostics import IDENTIFIED, NOT_IDENTIFIABLE, POORLY, Diagnostic, Verdict, verdicts
from .estimates import Estimates
from .paper import PaperIdentification, with_estimates

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["CONSISTENCY_Z", "CombinedIdentification", "RoundEstimates", "combine_rounds",
           "combined_table", "read_round", "round_estimates"]

#: Two rounds agree on a parameter when they differ by at most this many standard
#: deviations of the difference (95 %, two-sided): an honest pair is called
#: disagreeing 5 % of the time, which costs a verdict, never a wrong value.
CONSISTENCY_Z = 1.96
#: The joint test of all the parameters combined: its level.
JOINT_LEVEL = 0.95
#: What a refused disagreement asks for.
DISAGREE_REMEDY = ("a third round, or find what changed between the rounds (the bench, "
                   "the sensors, the actuator's wear or temperature)")
#: The columns of a round's table (``RoundEstimates.table``).
COLUMNS = ("unit", "value", "stderr", "ci95_low", "ci95_high", "verdict", "reason",
           "remedy", "initial", "round")
#: Better verdicts first.
RANK = {IDENTIFIED: 0, POORLY: 1, NOT_IDENTIFIABLE: 2}


@dataclass(frozen=True)
class RoundEstimates:
    """What one round of identification says per parameter (``table``, index the
    parameter, columns ``COLUMNS``) and the covariance [SI²] of the parameters with a
    reported interval (``covariance``, a DataFrame), with the residual degrees of
    freedom and where it came from."""

    table: pd.DataFrame
    covariance: pd.DataFrame
    dof: int
    source: str

    @property
    def with_interval(self) -> list[str]:
        """The parameters whose interval the round reports (identified or poorly
        identified with a finite interval)."""
        t = self.table
        usable = (t["verdict"].isin([IDENTIFIED, POORLY]) & np.isfinite(t["ci95_low"])
                  & np.isfinite(t["ci95_high"]) & np.isfinite(t["stderr"]))
        return [n for n in t.index[usable] if n in self.covariance.index]


def round_estimates(ident: PaperIdentification, number: int) -> RoundEstimates:
    """An identification result as round ``number`` (a combined one keeps its rounds)."""
    table = ident.to_pandas().join(ident.verdicts_table()[["remedy"]])
    if "round" not in table.columns:
        table["round"] = str(number)
    return RoundEstimates(table[list(COLUMNS)], ident.covariance_table(),
                          int(ident.estimates.dof), f"round {number}")


def read_round(folder: str | PathLike[str], number: int = 1) -> RoundEstimates:
    """Round ``number`` as an earlier ``identify paper`` wrote it into ``folder``
    (estimates.csv, verdicts.csv and covariance.csv; without covariance.csv, written by
    versions before it, the variances alone)."""
    folder = Path(folder)
    needed = ("estimates.csv", "verdicts.csv")
    missing = [n for n in needed if not (folder / n).is_file()]
    if missing:
        raise DataError(f"previous = {folder}: no {', '.join(missing)} there; give the "
                        "folder an earlier `pneumact identify paper --out` wrote")
    table = pd.read_csv(folder / "estimates.csv", index_col="parameter")
    remedies = pd.read_csv(folder / "verdicts.csv", index_col="parameter")
    table = table.join(remedies[["remedy"]])
    for column in ("remedy", "reason"):  # an empty cell reads as NaN
        table[column] = table[column].astype(object).where(table[column].notna(), "")
    if "round" not in table.columns:
        table["round"] = str(number)
    table["round"] = table["round"].astype(str)
    lacking = [c for c in COLUMNS if c not in table.columns]
    if lacking:
        raise DataError(f"previous = {folder}: estimates.csv lacks the columns "
                        f"{', '.join(lacking)}; give a folder `identify paper` wrote")
    path = folder / "covariance.csv"
    if path.is_file():
        covariance = pd.read_csv(path, index_col="parameter")
    else:
        shown = table.dropna(subset=["ci95_low", "ci95_high", "stderr"])
        covariance = pd.DataFrame(np.diag(shown["stderr"].to_numpy(float) ** 2),
                                  index=shown.index, columns=shown.index)
    return RoundEstimates(table[list(COLUMNS)], covariance, 0, str(folder))


@dataclass(frozen=True)
class Combined:
    """One parameter combined: its value, the weight of each round's estimate, its
    verdict, the rounds it rests on, whether it has an interval, and (rounds that
    disagree) the variance of the interval covering both."""

    value: float
    weights: tuple[float, float]
    verdict: Verdict
    rounds: str
    has_interval: bool
    covering: float | None = None

    @property
    def agreed(self) -> bool:
        """A weighted mean of two rounds that agree."""
        return "+" in self.rounds and self.has_interval and self.covering is None


def combine_parameter(name: str, first: pd.Series | None, second: pd.Series | None,
                      usable: tuple[bool, bool]) -> Combined:
    """The rules of the module docstring for one parameter; ``first``, ``second``: its
    row in each round's table (None where a round has no estimate of it), ``usable``:
    whether each has a reported interval."""
    if usable[0] and usable[1] and first is not None and second is not None:
        return _weighted_mean(name, first, second)
    present = [(k, row) for k, row in enumerate((first, second)) if row is not None]
    with_interval = [(k, row) for k, row in present if usable[k]]
    if with_interval:
        return _carried(name, *with_interval[0], True)
    k, row = min(present, key=lambda pair: (RANK.get(pair[1]["verdict"], 3), -pair[0]))
    return _carried(name, k, row, False)


def _carried(name: str, k: int, row: pd.Series, has_interval: bool) -> Combined:
    """Round ``k``'s (0: the earlier) value and verdict, saying its round."""
    verdict = Verdict(name, row["verdict"], f"round {row['round']}: {row['reason']}",
                      row["remedy"] or "")
    return Combined(float(row["value"]), (1.0, 0.0) if k == 0 else (0.0, 1.0), verdict,
                    str(row["round"]), has_interval)


def _weighted_mean(name: str, first: pd.Series, second: pd.Series) -> Combined:
    """Both rounds have an interval: the inverse-variance weighted mean where they agree,
    refused where they do not."""
    a, b = float(first["value"]), float(second["value"])
    var_a, var_b = float(first["stderr"]) ** 2, float(second["stderr"]) ** 2
    w_a = var_b / (var_a + var_b)
    value = w_a * a + (1 - w_a) * b
    rounds = f"{first['round']}+{second['round']}"
    apart = abs(a - b) / np.sqrt(var_a + var_b)
    if not apart <= CONSISTENCY_Z:
        reason = (f"the rounds disagree: round {first['round']} {a:.6g} ± "
                  f"{1.96 * np.sqrt(var_a):.2g}, round {second['round']} {b:.6g} ± "
                  f"{1.96 * np.sqrt(var_b):.2g} (95 %), {apart:.1f} standard deviations of "
                  f"their difference apart (at most {CONSISTENCY_Z:g}); the interval "
                  "covers both")
        low = min(a - 1.96 * np.sqrt(var_a), b - 1.96 * np.sqrt(var_b))
        high = max(a + 1.96 * np.sqrt(var_a), b + 1.96 * np.sqrt(var_b))
        return Combined((low + high) / 2, (w_a, 1 - w_a), Verdict(
            name, POORLY, reason, DISAGREE_REMEDY), rounds, True,
            ((high - low) / 2 / 1.96) ** 2)
    stderr = np.sqrt(var_a * var_b / (var_a + var_b))
    judged = verdicts([name], np.array([value]), np.array([1.96 * stderr]), [False])[0]
    reason = (f"rounds {first['round']} and {second['round']} agree ({apart:.1f} standard "
              f"deviations apart), weighted mean: {judged.reason}")
    return Combined(value, (w_a, 1 - w_a), Verdict(name, judged.verdict, reason,
                                                   judged.remedy), rounds, True)


def combined_covariance(names: list[str], combined: dict[str, Combined],
                        rounds: tuple[RoundEstimates, RoundEstimates]) -> np.ndarray:
    """cov = W₁C₁W₁ + W₂C₂W₂ over ``names`` (each round's covariance where it reports an
    interval, zero elsewhere); infinite for a parameter without a combined interval; a
    covering interval's variance alone (uncorrelated) for rounds that disagree."""
    n = len(names)
    out = np.zeros((n, n))
    for k, part in enumerate(rounds):
        shown = [i for i, name in enumerate(names) if name in part.with_interval
                 and combined[name].weights[k] > 0 and combined[name].covering is None]
        if not shown:
            continue
        picked = [names[i] for i in shown]
        block = part.covariance.loc[picked, picked].to_numpy(float)
        weights = np.array([combined[names[i]].weights[k] for i in shown])
        out[np.ix_(shown, shown)] += block * np.outer(weights, weights)
    for i, name in enumerate(names):
        if combined[name].covering is not None:
            out[i, i] = combined[name].covering
    dead = np.array([not combined[name].has_interval for name in names])
    out[dead, :] = np.inf
    out[:, dead] = np.inf
    return out


def joint_disagreement(names: list[str], rounds: tuple[RoundEstimates, RoundEstimates]
                       ) -> Diagnostic | None:
    """A warning when the parameters both rounds report fail a χ² test of their
    differences (covariance C₁ + C₂) at ``JOINT_LEVEL``, though each agrees alone."""
    from scipy import stats

    if len(names) < 2:
        return None
    first, second = rounds
    diff = (first.table.loc[names, "value"].to_numpy(float)
            - second.table.loc[names, "value"].to_numpy(float))
    total = (first.covariance.loc[names, names].to_numpy(float)
             + second.covariance.loc[names, names].to_numpy(float))
    scale = np.sqrt(np.diag(total))
    scaled = total / np.outer(scale, scale)
    chi2 = float((diff / scale) @ np.linalg.pinv(scaled, rcond=1e-12) @ (diff / scale))
    limit = float(stats.chi2.ppf(JOINT_LEVEL, len(names)))
    if chi2 <= limit:
        return None
    return Diagnostic("warning", "rounds", f"the rounds agree on each of {', '.join(names)} "
                      f"alone but not jointly (χ² = {chi2:.3g} for {len(names)} degrees of "
                      f"freedom, {100 * JOINT_LEVEL:.0f} % limit {limit:.3g}): they differ "
                      "along a direction their correlations make unlikely", DISAGREE_REMEDY)


def combine_rounds(first: PaperIdentification | RoundEstimates,
                   second: PaperIdentification) -> CombinedIdentification:
    """The two rounds' identifications of one actuator, from independent records,
    combined per parameter (see the module docstring). ``first``: the earlier round's
    result, or what ``read_round`` read of it; ``second``: the later round's result.
    Refused when the rounds share a record (the combination assumes independent
    records: identify the later round from its own records only)."""
    if not isinstance(second, PaperIdentification):
        raise ParameterError(f"combine_rounds: second = {type(second).__name__}; give the "
                             "later round's identify_paper result")
    earlier = first if isinstance(first, RoundEstimates) else round_estimates(first, 1)
    if isinstance(first, PaperIdentification):
        _check_independent(first, second)
    later = round_estimates(second, _next_number(earlier))
    combined = combine_parameters(earlier, later)
    names = list(combined)
    joint = joint_disagreement([n for n in names if combined[n].agreed], (earlier, later))
    return _result(names, combined, (earlier, later), first, second,
                   [joint] if joint else [])


def combine_parameters(earlier: RoundEstimates, later: RoundEstimates
                       ) -> dict[str, Combined]:
    """Each parameter of either round combined (``combine_parameter``), the later
    round's parameters first."""
    parts = (earlier, later)
    names = list(dict.fromkeys([*later.table.index, *earlier.table.index]))
    combined = {}
    for name in names:
        rows = tuple(p.table.loc[name] if name in p.table.index else None for p in parts)
        usable = (name in earlier.with_interval, name in later.with_interval)
        combined[name] = combine_parameter(name, rows[0], rows[1], usable)
    return combined


def combined_table(earlier: RoundEstimates, later: RoundEstimates) -> pd.DataFrame:
    """Per parameter: the round, the combined value, its standard error and 95 %
    interval (NaN without one), the verdict and its reason: the combination without an
    identification result (from two rounds' tables alone)."""
    combined = combine_parameters(earlier, later)
    names = list(combined)
    estimates = _estimates(names, combined, (earlier, later))
    ci = estimates.interval(0.95)
    shown = np.isfinite(estimates.stderr)
    return pd.DataFrame({
        "round": [combined[n].rounds for n in names], "value": estimates.values,
        "stderr": np.where(shown, estimates.stderr, np.nan),
        "ci95_low": np.where(shown, ci[:, 0], np.nan),
        "ci95_high": np.where(shown, ci[:, 1], np.nan),
        "verdict": [combined[n].verdict.verdict for n in names],
        "reason": [combined[n].verdict.reason for n in names]},
        index=pd.Index(names, name="parameter"))


def _next_number(earlier: RoundEstimates) -> int:
    """The later round's number: one past the highest round the earlier result holds."""
    labels = "+".join(earlier.table["round"].astype(str))
    return max(int(x) for x in labels.split("+") if x.strip().isdigit()) + 1


def _check_independent(first: PaperIdentification, second: PaperIdentification) -> None:
    shared = sorted({Path(r.source).name for r in first.records}
                    & {Path(r.source).name for r in second.records})
    if shared:
        raise ParameterError(f"combine_rounds: both rounds used the records "
                             f"{', '.join(shared[:3])}{' ...' if len(shared) > 3 else ''}; "
                             "a combination needs independent records (identify the later "
                             "round from its own records only)")


def _result(names, combined, parts, first, second: PaperIdentification,
            findings: list[Diagnostic]) -> CombinedIdentification:
    """The combined values as a ``PaperIdentification``: estimates with the combined
    covariance, a verdict and a round per parameter, both rounds' diagnostics and
    residuals, the later round's bench."""
    estimates = _estimates(names, combined, parts)
    sources = {n: _source_words(combined[n]) for n in names}
    base = second.parameters_unchecked
    params = with_estimates(base, estimates, sources, base.name,
                            {"combined": f"rounds {', '.join(sorted(_labels(parts)))}"})
    earlier_ident = first if isinstance(first, PaperIdentification) else None
    records = ([*earlier_ident.records] if earlier_ident else []) + list(second.records)
    diagnostics = [*_labelled(earlier_ident.diagnostics if earlier_ident else [],
                              parts[0].source), *_labelled(second.diagnostics,
                                                           parts[1].source), *findings]
    residuals = pd.concat([_with_round(earlier_ident.residuals, parts[0].source)
                           if earlier_ident else pd.DataFrame(),
                           _with_round(second.residuals, parts[1].source)],
                          ignore_index=True)
    initial = earlier_ident.initial if earlier_ident else _initial_of(parts[0], second)
    keep = {k: second.extra[k] for k in ("friction", "chamber", "pressure_side", "sensors")
            if k in second.extra}
    return CombinedIdentification(
        {}, None, estimates, [combined[n].verdict for n in names], diagnostics, residuals,
        params, initial, records, None, None,
        {**keep, "no_interval": [n for n in names if not combined[n].has_interval],
         "disagree": [n for n in names if combined[n].covering is not None]},
        rounds={n: combined[n].rounds for n in names}, parts=parts)


def _estimates(names: list[str], combined: dict[str, Combined], parts) -> Estimates:
    """The combined values as ``Estimates``: the combined covariance, the fewer degrees
    of freedom of the two rounds (none known: the normal quantile)."""
    units = tuple(str(parts[1].table.loc[n, "unit"]) if n in parts[1].table.index else
                  str(parts[0].table.loc[n, "unit"]) for n in names)
    covariance = combined_covariance(names, combined, parts)
    dofs = [p.dof for p in parts if p.dof > 0]
    return Estimates(tuple(names), np.array([combined[n].value for n in names]),
                     np.sqrt(np.diag(covariance)), covariance, min(dofs) if dofs else 0,
                     units)


def _labels(parts) -> set[str]:
    return {x for p in parts for label in p.table["round"].astype(str)
            for x in label.split("+")}


def _source_words(one: Combined) -> str:
    if one.agreed:
        return f"identified, rounds {one.rounds.replace('+', ' and ')}: weighted mean"
    if "+" in one.rounds:
        return f"rounds {one.rounds.replace('+', ' and ')} disagree: not identified"
    return f"round {one.rounds}: {one.verdict.verdict}"


def _labelled(diagnostics, source: str) -> list[Diagnostic]:
    return [Diagnostic(d.severity, f"{source}: {d.stage}", f"{source}: {d.message}",
                       d.remedy) for d in diagnostics]


def _with_round(residuals: pd.DataFrame, source: str) -> pd.DataFrame:
    return residuals.assign(round=source) if len(residuals) else residuals


def _initial_of(earlier: RoundEstimates, second: PaperIdentification):
    """The first round's prior: its ``initial`` column over the later round's set."""
    known = earlier.table["initial"].dropna()
    return second.initial.replace({n: float(v) for n, v in known.items()
                                   if n in second.initial})


@dataclass(eq=False)
class CombinedIdentification(PaperIdentification):
    """Two rounds of one actuator combined per parameter (``combine_rounds``): the
    vocabulary of ``PaperIdentification``, each value with its round (``rounds``:
    "1", "2" or "1+2"), the rounds' own tables in ``parts``. Nothing is fitted again:
    no joint fit, no stage, no prediction band (``band`` refuses)."""

    report_title = "Identification of the actuator: two rounds combined per parameter"
    figure_name = "rounds"

    rounds: dict[str, str] = field(default_factory=dict)
    parts: tuple[RoundEstimates, ...] = ()

    @property
    def intervals_hold(self) -> bool:
        """Some parameter has a combined interval (each round judged its own)."""
        return bool(self._with_interval())

    @property
    def ok(self) -> bool:
        """Every parameter identified (the rounds' findings are in their verdicts)."""
        return all(v.identified for v in self.verdicts)

    def _with_interval(self) -> set[str]:
        no_interval = set(self.extra.get("no_interval", ()))
        return {n for n in self.estimates.names if n not in no_interval}

    def to_pandas(self, name: str | None = None, truth=None) -> pd.DataFrame:
        """``PaperIdentification.to_pandas`` with the round each value came from; no
        staged columns (each round's are in its own result)."""
        if name is not None:
            return super().to_pandas(name)
        table = super().to_pandas(truth=truth)
        table = table.drop(columns=[c for c in table.columns if c.startswith("stage")])
        table.insert(1, "round", [self.rounds.get(n, "") for n in table.index])
        return table

    def verdicts_table(self) -> pd.DataFrame:
        table = super().verdicts_table()
        table.insert(0, "round", [self.rounds.get(n, "") for n in table.index])
        return table

    def summary(self) -> str:
        """The headline, where each value comes from, then as ``PaperIdentification``."""
        lines = super().summary().split("\n")
        groups: dict[str, list[str]] = {}
        for n, label in self.rounds.items():
            key = (f"rounds {label.replace('+', ' and ')} (disagree)"
                   if n in self.extra.get("disagree", ())
                   else f"rounds {label.replace('+', ' and ')} (weighted mean)"
                   if "+" in label else f"round {label}")
            groups.setdefault(key, []).append(n)
        where = "; ".join(f"{key}: {', '.join(names)}" for key, names in groups.items())
        return "\n".join([lines[0], f"  from {where}", *lines[1:]])

    def band(self, record, draws: int = 60):
        raise ParameterError("identification: no prediction band for a combination of "
                             "rounds: the combined set is not fitted to any round's records "
                             "(draw the band of one round's result)")

    def figures(self) -> dict[str, Callable[[], Figure]]:
        return {"rounds": self.plot}

    def plot(self) -> Figure:
        """Each parameter's value and 95 % interval in each round and combined, in % of
        the combined value (no interval: the value alone, hollow)."""
        import matplotlib.pyplot as plt

        table = self.to_pandas()
        fig, ax = plt.subplots(figsize=(7.0, 0.45 * len(table) + 1.5))
        series = [(p.source, p.table) for p in self.parts] + [("combined", table)]
        for k, (label, part) in enumerate(series):
            _draw_round(ax, table, part, k - (len(series) - 1) / 2, label)
        ax.set_yticks(np.arange(len(table)), list(table.index))
        ax.invert_yaxis()
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_xlabel("value and 95 % interval [% from the combined value]")
        ax.grid(True, axis="x", alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
        tight_layout(fig)
        return fig


def _draw_round(ax, combined: pd.DataFrame, part: pd.DataFrame, offset: float,
                label: str) -> None:
    """One round's values and intervals on ``ax``, in % of the combined values."""
    y, value, low, high = [], [], [], []
    for i, name in enumerate(combined.index):
        if name not in part.index:
            continue
        scale = abs(float(combined.loc[name, "value"])) or 1.0
        ref = float(combined.loc[name, "value"])
        y.append(i + 0.2 * offset)
        value.append(100 * (float(part.loc[name, "value"]) - ref) / scale)
        low.append(100 * (float(part.loc[name, "ci95_low"]) - ref) / scale)
        high.append(100 * (float(part.loc[name, "ci95_high"]) - ref) / scale)
    v, lo, hi = np.array(value), np.array(low), np.array(high)
    shown = np.isfinite(lo) & np.isfinite(hi)
    line = ax.errorbar(v[shown], np.array(y)[shown], xerr=np.vstack([v - lo, hi - v])[:, shown],
                       fmt="o", capsize=3, label=label)
    ax.plot(v[~shown], np.array(y)[~shown], "o", mfc="none", color=line[0].get_color())
