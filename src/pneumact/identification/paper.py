"""The paper's identification (section III.2), made to hold on any actuator, in one call.

``identify_paper(records, prior)`` runs

1. the paper's four stages (``identification.stages``: spring, eq. 13, eq. 12,
   presliding output error), every threshold derived from the records or an earlier
   stage, each stage's findings kept as diagnostics;
2. a joint refinement of all spring and friction parameters over all records at once
   (``identification.joint``), started at the staged estimates: its estimates are the
   result;
3. intervals that hold: the joint fit's residual (HAC) covariance plus the share of the
   noise on the measured inputs (``identification.uncertainty``);
4. checks that the model fits each record (residual RMS against the sensor noise) and
   that the presliding test stayed in presliding, and a verdict per parameter
   (``identification.diagnostics``): identified, poorly identified or not identifiable,
   with the reason and the test that would fix it.

``prior`` gives what a user knows (geometry, gas, valve) and rough starting values of
the rest. The result's parameter set is written (``identified.toml``) only when every
parameter is identified, unless a partial result is asked for.
"""

from __future__ import annotations

import datetime as _dt
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import DataError, ParameterError, SolverError
from ..io.records import PRESSURE_SIGNAL, Record
from ..io.report import ResultVocabulary
from ..models.actuator import CHAMBER_PRESSURE
from ..models.sensors import SENSOR_PARAMETERS
from ..options import Executor
from ..plotting import tight_layout
from ..progress import ProgressCallback, check_progress, notify
from .campaign import DEFAULT_SPREAD, RAMP_SPEEDS, CampaignPlan
from .diagnostics import (
    MISFIT_RATIO,
    MISFIT_REFIT_SHARE,
    MISFIT_REMEDY,
    MISFIT_STRUCTURE,
    MODEL_FIDELITY,
    NOT_IDENTIFIABLE,
    POORLY,
    REMEDIES,
    Diagnostic,
    Verdict,
    misfit_influence,
    named_list,
    residual_checks,
    verdicts,
)
from .estimates import Estimates
from .faults import (
    LAG_GAIN,
    PRESLIDING_ALIASED,
    finest_sample_period,
    lag_search,
    position_zero,
    pressure_side,
    quantisation_covariance,
    quantised_records,
    regulator_check,
    sensor_notes,
    undersampled_presliding,
    viscous_lag_bound,
    without_lag,
)
from .fit import FitResult, one_blas_thread
from .joint import (
    JOINT_RTOL,
    MAX_EVALUATIONS,
    SPRING_AND_FRICTION,
    feasible,
    joint_refinement,
    refit_without,
    restart_at_bounds,
    stuck_at_bounds,
)
from .memo import remembered
from .optima import CHI2_95_1DOF, cover_optima, cover_values
from .stages import (
    STAGES,
    StageResult,
    presliding_range,
    presliding_window,
    segments_of,
    sliding_and_stribeck,
    stage_presliding,
    stage_spring,
)
from .uncertainty import (
    INPUT_REPLICATES,
    InputNoise,
    input_noise_covariance,
    nuisance_covariance,
    prediction_band,
    with_covariance,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..io.report import Report
    from ..parameters.parameter_set import ParameterSet

__all__ = ["STAGES", "PaperIdentification", "SignatureIdentification", "StageResult",
           "identify_paper", "identify_signature", "record_kind", "with_estimates"]

#: The presliding test is presliding while its excursion after the approach stays below
#: this many static deflections Fs/σ0 (LuGre's presliding creep ends near 3·Fs/σ0).
PRESLIDING_EXCURSION = 3.0


def record_kind(record: Record) -> str:
    """``sweep``, ``ramp`` or ``presliding``: from the record's meta, else its file name."""
    from .campaign import KINDS

    kind = record.meta.get("kind")
    if kind in KINDS:
        return kind
    stem = Path(record.source).name.lower()
    for kind in KINDS:
        if stem.startswith(kind):
            return kind
    raise DataError(f"{record.source}: cannot tell which test this record is; name the file "
                    f"sweep*, ramp* or presliding* (or set meta['kind'])")


def with_estimates(params, estimates: Estimates, sources: dict[str, str], name: str,
                   provenance: dict[str, str], keep: Sequence[str] | None = None):
    """``params`` with the ``estimates`` (only those named in ``keep``, default all),
    each value's source from ``sources`` and its standard error in the note."""
    from ..parameters import ParameterSet
    from ..parameters.parameter_set import ParameterInfo, number_text

    values = dict(params.values)
    info = dict(params.info)
    chosen = feasible(estimates.as_dict(), params)  # Fs never below Fc in a parameter set
    for j, pname in enumerate(estimates.names):
        if (pname not in params and pname not in SENSOR_PARAMETERS) or \
                (keep is not None and pname not in keep):
            continue
        value = float(chosen.get(pname, estimates.values[j]))
        values[pname] = value
        info[pname] = ParameterInfo(
            number_text(pname, value), sources[pname],
            f"± {estimates.stderr[j]:.3g} (standard error, input noise included)")
    return ParameterSet(values, name=name, description=f"identified from {params.name}",
                        provenance={**params.provenance, **provenance}, info=info)


@dataclass(eq=False)
class PaperIdentification(ResultVocabulary):
    """The stages, the joint refinement, the final estimates with their verdicts, and
    the identified parameter set (see the module docstring).

    ``parameters``: the identified set, only when every parameter is identified (else it
    raises and says why); ``parameter_set(partial=True)``: the identified values with the
    prior's for the others, each marked in its source; ``parameters_unchecked``: every
    estimate as it came out, unchecked (for diagnosis, not for use).

    ``to_pandas(truth=None)``: the estimates (``"verdicts"``, ``"diagnostics"``,
    ``"residuals"``: the others); ``plot()``: the joint fit (the first stage's fit when
    there is none); ``write(folder)``: every table and figure, report.md, report.html
    and identified.toml (see ``writers``)."""

    report_title = ("Identification of the actuator (paper section III.2, then a joint "
                    "refinement)")
    figure_name = "joint_fit"

    stages: dict[str, StageResult]
    joint: FitResult | None
    estimates: Estimates
    verdicts: list[Verdict]
    diagnostics: list[Diagnostic]
    residuals: pd.DataFrame
    parameters_unchecked: ParameterSet
    initial: ParameterSet
    records: list[Record]
    input_noise: InputNoise | None = None
    staged_parameters: ParameterSet | None = None
    extra: dict = field(default_factory=dict)

    # -- the verdict ------------------------------------------------------------------
    @property
    def intervals_hold(self) -> bool:
        """Whether the intervals mean what they say: the joint fit converged and the model
        fits every record it used (else no interval is reported)."""
        fits = bool(self.residuals["fits"].all()) if len(self.residuals) else True
        if self.joint is None:  # staged: the model at the staged values predicts them
            return fits and not self.extra.get("joint_failed", False)
        return fits and bool(self.joint.success)

    @property
    def ok(self) -> bool:
        """Every parameter identified and no error found: the result can be used."""
        return all(v.identified for v in self.verdicts) and \
            not any(d.severity == "error" for d in self.diagnostics)

    @property
    def identified(self) -> list[str]:
        return [v.parameter for v in self.verdicts if v.identified]

    @property
    def parameters(self) -> ParameterSet:
        """The identified parameter set, when every parameter is identified; otherwise a
        ``ParameterError`` that names the others (``parameter_set(partial=True)`` gives
        the identified values with the prior's for the rest, marked;
        ``parameters_unchecked`` the estimates as they are)."""
        if not self.ok:
            raise ParameterError(
                "identification: " + self.headline() + "; the parameter set is not "
                "checked. Use parameter_set(partial=True) for the identified values with "
                "the prior's for the others (each marked in its source), or "
                "parameters_unchecked for the raw estimates")
        return self.parameters_unchecked

    def headline(self) -> str:
        """One line: how many parameters are identified, and which are not."""
        bad = [v.parameter for v in self.verdicts if not v.identified]
        if not bad and self.ok:
            return f"all {len(self.verdicts)} parameters identified"
        head = f"{len(self.verdicts) - len(bad)} of {len(self.verdicts)} parameters identified"
        return head + (f" (not: {', '.join(bad)})" if bad else " (errors found)")

    def summary(self) -> str:
        """At most a screen: the headline, one line per parameter not identified (its
        verdict and reason), each remedy once, and the errors found."""
        lines = [self.headline()]
        bad = [v for v in self.verdicts if not v.identified]
        for v in bad:
            lines.append(f"  {v.parameter}: {v.verdict}: {_shorten(v.reason)}")
        errors = list(dict.fromkeys(_shorten(d.message) for d in self.diagnostics
                                    if d.severity == "error"))
        for message in errors[:SUMMARY_ERRORS]:
            lines.append(f"  error: {message}")
        if len(errors) > SUMMARY_ERRORS:
            lines.append(f"  ... and {len(errors) - SUMMARY_ERRORS} more errors (see the "
                         "diagnostics table)")
        remedies = list(dict.fromkeys([v.remedy for v in bad if v.remedy]
                                      + [d.remedy for d in self.diagnostics
                                         if d.severity == "error" and d.remedy]))
        if remedies:
            lines.append("  what would fix it:")
            lines += [f"  - {_shorten(r)}" for r in remedies[:SUMMARY_REMEDIES]]
        return "\n".join(lines)

    # -- tables ------------------------------------------------------------------------
    def tables(self) -> dict[str, pd.DataFrame]:
        return {"estimates": self.to_pandas(), "verdicts": self.verdicts_table(),
                "diagnostics": self.diagnostics_table(), "residuals": self.residuals,
                "bench": self.bench_table()}

    def plot(self) -> Figure:
        """Measured and fitted position of the joint refinement (of the first stage when
        the identification stopped after the stages)."""
        if self.joint is not None:
            return self.joint.plot_fit()
        return next(iter(self.stages.values())).plot()

    def to_pandas(self, name: str | None = None, truth=None) -> pd.DataFrame:
        """(``name`` None) Per parameter: the staged estimate and its (conditional)
        standard error, the final (joint) estimate, its standard error and 95 % interval,
        the verdict and its reason (with the truth and the errors in % when ``truth`` is
        given). Where the model does not fit the records (``intervals_hold`` is False)
        no standard error or interval is reported: they would not hold. ``name``:
        "verdicts", "diagnostics" or "residuals" for those tables."""
        if name is not None:
            return super().to_pandas(name)
        ci = self.estimates.interval(0.95)
        shown = self._with_interval()
        for j, name in enumerate(self.estimates.names):
            if name not in shown:
                ci[j] = np.nan
        rows = []
        staged = self._staged_values()
        for j, name in enumerate(self.estimates.names):
            if "[" in name:
                continue
            verdict = next(v for v in self.verdicts if v.parameter == name)
            stage, s_value, s_err = staged.get(name, ("", np.nan, np.nan))
            row = {"parameter": name, "unit": self.estimates.units[j], "stage": stage,
                   "staged": s_value, "staged_stderr": s_err,
                   "value": self.estimates.values[j],
                   "stderr": self.estimates.stderr[j] if name in shown else np.nan,
                   "ci95_low": ci[j, 0], "ci95_high": ci[j, 1],
                   "initial": _value_in(self.initial, name), "verdict": verdict.verdict,
                   "reason": verdict.reason}
            if truth is not None:
                true = _value_in(truth, name)
                row["truth"] = true
                row["staged_error_%"] = 100 * (s_value - true) / true
                row["error_%"] = 100 * (row["value"] - true) / true
                row["truth_in_ci95"] = (bool(ci[j, 0] <= true <= ci[j, 1])
                                        if name in shown and np.isfinite(true) else None)
            rows.append(row)
        return pd.DataFrame(rows).set_index("parameter")

    def _with_interval(self) -> set[str]:
        """The parameters whose interval holds: all when the model fits every record;
        else those the misfit records neither carry nor move (``misfit_influence``); in
        both, none for Fs and vs resting on faster records (``_stribeck_dip_check``)."""
        shown = (set(self.estimates.names) if self.intervals_hold
                 else set(self.extra.get("trusted", ())))
        return shown - set(self.extra.get("no_interval", ()))

    def _staged_values(self) -> dict[str, tuple[str, float, float]]:
        out = {}
        for stage in self.stages.values():
            for j, name in enumerate(stage.estimates.names):
                out[name] = (stage.title.split()[0], float(stage.estimates.values[j]),
                             float(stage.estimates.stderr[j]))
        return out

    def extra_tables(self) -> dict[str, pd.DataFrame]:
        """Tables a kind of identification adds to its report, by caption: the bench."""
        bench = self.bench_table()
        return {"The bench: what the records say about the sensors and the regulator":
                bench} if len(bench) else {}

    def bench_table(self) -> pd.DataFrame:
        """The bench's parameters as the records tell them (``models.sensors``): the
        pressure sensor's offset (from the set-point/pressure pairs), the position
        sensor's offset (from the records at rest on the stop), the position
        sensor's lag (fitted, when the records needed it), its resolution and the sample
        rates (read from the records), each with how it was found."""
        rows = []
        side = self.extra.get("pressure_side")
        if side is not None and len(side.table):
            rows.append({"parameter": "pressure_offset", "value": side.offset,
                         "ci95_low": side.offset - 1.96 * side.offset_stderr,
                         "ci95_high": side.offset + 1.96 * side.offset_stderr, "unit": "Pa",
                         "how": "set-point/pressure pairs, median of "
                                f"{len(side.table)} records; "
                                + ("taken off the records" if side.applied else
                                   "not significant: left on")})
        zero = self.extra.get("position_zero")
        if zero is not None and len(zero.table):
            rows.append({"parameter": "position_offset", "value": zero.offset,
                         "ci95_low": zero.offset - 1.96 * zero.offset_stderr,
                         "ci95_high": zero.offset + 1.96 * zero.offset_stderr, "unit": "m",
                         "how": f"at rest on the stop, median of {len(zero.table)} "
                                "records; " + ("taken off the records" if zero.applied else
                                               "not significant: left on")})
        if "position_lag" in self.estimates.names:
            j = self.estimates.names.index("position_lag")
            low, high = self.estimates.interval(0.95)[j]
            rows.append({"parameter": "position_lag", "value": self.estimates.values[j],
                         "ci95_low": low, "ci95_high": high, "unit": "s",
                         "how": "fitted with the spring and friction (joint)"})
        sensors = self.extra.get("sensors")
        if sensors is not None and len(sensors):
            step = float(sensors["position_resolution"].max())
            rows.append({"parameter": "position_resolution", "value": step,
                         "ci95_low": np.nan, "ci95_high": np.nan, "unit": "m",
                         "how": "read from the records (the smallest step)" if step else
                                "no quantisation seen in the records"})
            rates = sensors["sample_rate"]
            rows.append({"parameter": "sample_rate", "value": float(rates.min()),
                         "ci95_low": np.nan, "ci95_high": np.nan, "unit": "Hz",
                         "how": f"read from the records ({rates.min():.4g}–"
                                f"{rates.max():.4g} Hz)"})
        return pd.DataFrame(rows, columns=["parameter", "value", "ci95_low", "ci95_high",
                                           "unit", "how"])

    def covariance_table(self) -> pd.DataFrame:
        """The covariance [SI²] of the estimates that have a reported interval (see
        ``to_pandas``), rescaled to their reported standard errors (a widening for a
        misfit or a second optimum enlarges the variance, not the correlations): what a
        later round combines with (``identification.combine``)."""
        table = self.to_pandas()
        shown = [n for n in table.index if np.isfinite(table.loc[n, "ci95_low"])
                 and np.isfinite(table.loc[n, "ci95_high"])]
        stderr = table.loc[shown, "stderr"].to_numpy(float)
        idx = [self.estimates.names.index(n) for n in shown]
        covariance = self.estimates.covariance[np.ix_(idx, idx)].copy()
        spread = np.sqrt(np.abs(np.diag(covariance)))
        usable = np.isfinite(covariance).all() and np.all(spread > 0)
        if usable:
            covariance *= np.outer(stderr / spread, stderr / spread)
        else:  # no correlations to keep: the variances alone
            covariance = np.diag(stderr**2)
        return pd.DataFrame(covariance, index=pd.Index(shown, name="parameter"),
                            columns=shown)

    def diagnostics_table(self) -> pd.DataFrame:
        return pd.DataFrame([{"severity": d.severity, "stage": d.stage,
                              "message": d.message, "remedy": d.remedy}
                             for d in self.diagnostics],
                            columns=["severity", "stage", "message", "remedy"])

    def verdicts_table(self) -> pd.DataFrame:
        return pd.DataFrame([{"parameter": v.parameter, "verdict": v.verdict,
                              "reason": v.reason, "remedy": v.remedy}
                             for v in self.verdicts]).set_index("parameter")

    # -- figures -----------------------------------------------------------------------
    def plot_band(self, record: str | None = None):
        """The pressure-position loop of a record (default: the first sweep) with the
        band the parameter uncertainty leaves, and the measurement."""
        import matplotlib.pyplot as plt

        sweeps = [r for r in self.records if record_kind(r) == "sweep"]
        chosen = next((r for r in self.records if Path(r.source).name == record),
                      sweeps[0] if sweeps else self.records[0])
        band = self.band(chosen)
        fig, (ax_loop, ax_time, ax_zoom) = plt.subplots(1, 3, figsize=(15.5, 4.2))
        for run_p, run_x in zip(band.samples[CHAMBER_PRESSURE], band.samples["position"],
                                strict=True):
            ax_loop.plot(run_p * 1e-3, run_x * 1e3, color="C0", alpha=0.05, lw=0.8)
        ax_loop.plot(chosen[PRESSURE_SIGNAL] * 1e-3, chosen["position"] * 1e3, "k.", ms=1,
                     label="measured")
        ax_loop.plot(band.nominal[CHAMBER_PRESSURE] * 1e-3, band.nominal["position"] * 1e3,
                     "C3-", lw=1, label="identified model")
        ax_loop.set_xlabel("chamber pressure [kPa abs]")
        ax_loop.set_ylabel("position [mm]")
        ax_loop.set_title(f"{Path(chosen.source).name}: loop, {len(band.samples['position'])}"
                          " draws from the estimates' uncertainty", fontsize=9)
        # a fixed corner: "best" scans every point, and on a long record under load
        # matplotlib warns that it is slow (a failed test, once)
        ax_loop.legend(fontsize=8, loc="lower left")
        ax_time.fill_between(band.time, band.lower["position"] * 1e3,
                             band.upper["position"] * 1e3, color="C0", alpha=0.3,
                             label=f"{100 * band.level:.0f} % band")
        ax_time.plot(chosen.time, chosen["position"] * 1e3, "k-", lw=0.5, label="measured")
        ax_time.plot(band.time, band.nominal["position"] * 1e3, "C3-", lw=0.8,
                     label="identified model")
        ax_time.set_xlabel("time [s]")
        ax_time.set_ylabel("position [mm]")
        ax_time.legend(fontsize=8, loc="upper right")
        # the band is some µm on a stroke of mm: drawn about the model, in µm, it shows
        nominal = band.nominal["position"]
        measured = np.interp(band.time, chosen.time, chosen["position"])
        ax_zoom.fill_between(band.time, (band.lower["position"] - nominal) * 1e6,
                             (band.upper["position"] - nominal) * 1e6, color="C0",
                             alpha=0.35, label=f"{100 * band.level:.0f} % band")
        ax_zoom.plot(band.time, (measured - nominal) * 1e6, "k.", ms=1,
                     label="measured − model")
        ax_zoom.axhline(0.0, color="C3", lw=0.8)
        ax_zoom.set_xlabel("time [s]")
        ax_zoom.set_ylabel("position − identified model [µm]")
        ax_zoom.set_title("the band about the model (zoom)", fontsize=9)
        ax_zoom.legend(fontsize=8, loc="upper right")
        for a in (ax_loop, ax_time, ax_zoom):
            a.grid(True, alpha=0.3)
        tight_layout(fig)
        return fig

    def band(self, record: Record, draws: int = 60):
        """``uncertainty.prediction_band`` of the identified model on ``record`` (the
        actuator's signals, before its sensors), drawn from the parameters with an
        interval; refused where no interval holds (the model
        does not fit the records) or none has one."""
        from ..simulation import Rodas4
        from .fit import experiment_for
        from .joint import bench_model

        if not self.intervals_hold:
            raise ParameterError("identification: no prediction band: the model does not "
                                 "fit every record, so no interval holds (" +
                                 self.headline() + ")")
        if not np.any(np.isfinite(self.estimates.stderr)):
            raise ParameterError("identification: no prediction band: no parameter has an "
                                 "interval")
        model = bench_model(record, self.parameters_unchecked, self.extra.get("friction"),
                            self.extra.get("chamber"))
        experiment = experiment_for(model, record, smooth=True)
        names = [n for j, n in enumerate(self.estimates.names) if "[" not in n and
                 n not in SENSOR_PARAMETERS and np.isfinite(self.estimates.stderr[j])]
        idx = [self.estimates.names.index(n) for n in names]
        est = Estimates(tuple(names), self.estimates.values[idx], self.estimates.stderr[idx],
                        self.estimates.covariance[np.ix_(idx, idx)], self.estimates.dof,
                        tuple(self.estimates.units[i] for i in idx))
        return prediction_band(model, experiment, est, draws=draws, t_eval=record.time,
                               solver=Rodas4(rtol=JOINT_RTOL * 100))

    # -- output ------------------------------------------------------------------------
    def writers(self, truth=None, call: str = "", partial: bool = True) -> dict:
        """File name -> writer: estimates.csv, verdicts.csv, diagnostics.csv,
        residuals.csv, covariance.csv (``covariance_table``), bench.csv
        (``bench_table``), stage_*.png, joint_fit.png, band.png,
        report.md, report.html, and identified.toml: the identified values, the prior's
        for the others, each marked in its source (``parameter_set(partial=True)``;
        ``partial=False``: only when every parameter is identified)."""
        from ..parameters import write_params

        rendered: dict[str, bytes] = {}

        def pngs() -> dict[str, bytes]:  # drawn once, when the first one is written
            if not rendered:
                rendered.update(self._pngs())
            return rendered

        writers: dict = {}
        if self.ok or partial:
            writers["identified.toml"] = lambda p: write_params(
                self.parameter_set(partial=True), p)
        writers["estimates.csv"] = lambda p: self.to_pandas(truth=truth).to_csv(p)
        writers["verdicts.csv"] = lambda p: self.verdicts_table().to_csv(p)
        writers["diagnostics.csv"] = lambda p: self.diagnostics_table().to_csv(p, index=False)
        writers["residuals.csv"] = lambda p: self.residuals.to_csv(p, index=False)
        writers["covariance.csv"] = lambda p: self.covariance_table().to_csv(p)
        if len(self.bench_table()):
            writers["bench.csv"] = lambda p: self.bench_table().to_csv(p, index=False)
        for name in self.figures():
            writers[f"{name}.png"] = lambda p, name=name: Path(p).write_bytes(pngs()[name])
        writers["report.md"] = lambda p: Path(p).write_text(self.markdown(truth),
                                                            encoding="utf-8")
        writers["report.html"] = lambda p: self.report(call, truth=truth,
                                                       pngs=pngs()).write(p)
        return writers

    def figures(self) -> dict[str, Callable[[], Figure]]:
        """The figures ``write`` draws, by file name: each stage's, then (after a joint
        refinement) the joint fit (joint_fit, joint_fit-2, ... beyond a page of records)
        and the prediction band."""
        from ..plotting import page_name

        makers = {f"stage_{name}": stage.plot for name, stage in self.stages.items()}
        if self.joint is not None:  # a page per PANELS_PER_PAGE records
            for k in range(1, self.joint.fit_pages + 1):
                makers[page_name("joint_fit", k)] = functools.partial(self.joint.plot_fit, k)
            makers["band"] = self.plot_band
        return makers

    def _pngs(self) -> dict[str, bytes]:
        """Every figure as PNG, drawn once for both its file and the report (the
        prediction band simulates its draws)."""
        from ..io.report import figure_png
        from ..plotting import PNG_DPI

        return {name: figure_png(make(), dpi=PNG_DPI) for name, make in self.figures().items()}

    def parameter_set(self, partial: bool = False):
        """The identified set; with ``partial`` the parameters that are not identified
        keep the prior's values (and say so in their source)."""
        from ..parameters import ParameterSet
        from ..parameters.parameter_set import ParameterInfo, number_text

        if not (self.ok or partial):
            raise ParameterError("identification: " + self.headline() + "; ask for a "
                                 "partial result explicitly (partial=True)")
        if self.ok:
            return self.parameters_unchecked
        params = self.parameters_unchecked
        values, info = dict(params.values), dict(params.info)
        for v in self.verdicts:
            if not v.identified and v.parameter not in self.initial:
                values.pop(v.parameter, None)  # a bench parameter: the ideal sensor
                info.pop(v.parameter, None)
            elif not v.identified:
                values[v.parameter], source = self._fallback(v.parameter, values)
                info[v.parameter] = ParameterInfo(
                    number_text(v.parameter, values[v.parameter]), source,
                    f"{v.verdict}: {v.reason}")
        return ParameterSet(values, name=params.name, description=params.description
                            + " (partial)", provenance=params.provenance, info=info)

    def next_round(self, spread: float = DEFAULT_SPREAD, ramps: int = RAMP_SPEEDS,
                   number: int = 2) -> CampaignPlan:
        """The bench tests of the next round, designed from this result
        (``identification.rounds.next_round``: its estimates where they have an interval,
        the prior's values elsewhere, each named in the plan's notes; ``spread``: this
        round's prior's). Identify both rounds' records together from ``plan.prior``."""
        from .rounds import next_round

        return next_round(self, spread, ramps, number)

    def combine(self, later: PaperIdentification) -> PaperIdentification:
        """This round's result combined per parameter with a ``later`` round's, identified
        from other records (``identification.combine.combine_rounds``: a value from one
        round with its interval, the weighted mean where both rounds agree, refused where
        they disagree; each value says its round)."""
        from .combine import combine_rounds

        return combine_rounds(self, later)

    def _fallback(self, name: str, values: dict[str, float]) -> tuple[float, str]:
        """The value a parameter that is not identified takes in the partial set, and
        its source: the prior's, except a static friction below the set's Coulomb
        level (which no parameter set holds): the prior's ratio Fs/Fc on that level."""
        prior = self.initial[name]
        if name == "Fs" and "Fc" in values and prior < values["Fc"]:
            return (prior / self.initial["Fc"] * values["Fc"],
                    "prior's ratio Fs/Fc on the identified Fc: not identified")
        return prior, "prior value: not identified"

    def report(self, call: str = "", png: bytes | None = None, truth=None,
               pngs: dict[str, bytes] | None = None) -> Report:
        """Verdicts, estimates (staged and joint), diagnostics, residual checks and the
        figures as a self-contained HTML ``Report`` (not yet written; ``png``: the joint
        fit's figure if already drawn; ``pngs``: any figures already drawn, by name)."""
        from ..io.report import Report
        from ..plotting import page_names

        drawn = dict(pngs or {})
        if png is not None:
            drawn.setdefault("joint_fit", png)
        makers = self.figures()

        def figure(name: str, caption: str) -> None:
            if name in drawn:
                report.image(drawn[name], caption)
            else:
                report.figure(makers[name](), caption)

        report = Report(self.report_title, call=call,
                        parameters=self.parameter_set(partial=True))
        report.text(("Result: " if self.ok else "Result NOT usable as it is: ")
                    + self.summary())
        report.text("Records: " + ", ".join(Path(r.source).name for r in self.records))
        report.table(self.verdicts_table(), "Verdict per parameter")
        for caption, table in self.extra_tables().items():
            report.table(table, caption)
        report.table(self.to_pandas(truth=truth), "Staged and joint estimates, standard errors and "
                     "95 % intervals (SI; the joint ones include the input noise)")
        if len(self.diagnostics):
            report.table(self.diagnostics_table(), "Diagnostics", index=False)
        if len(self.residuals):
            report.table(self.residuals, "Does the model fit each record? (residual RMS "
                         "against the sensor noise)", index=False)
        if self.joint is not None:
            report.heading("Prediction band")
            figure("band", "The loop and the time series with the band the parameter "
                   "uncertainty leaves")
            report.heading("Joint refinement")
            pages = page_names(makers, "joint_fit")
            for k, name in enumerate(pages, start=1):
                figure(name, "Measured and fitted position, all records" + (
                    f" (page {k} of {len(pages)})" if len(pages) > 1 else ""))
        for name, stage in self.stages.items():
            report.heading(stage.title)
            figure(f"stage_{name}", stage.title)
        return report

    def write(self, out_dir: str | PathLike[str], truth=None, *, call: str = "",
              partial: bool = True) -> list[Path]:
        """Write every file of ``writers`` into ``out_dir``, all or none (identified.toml
        with the prior's values for what is not identified, marked; ``partial=False``:
        only when every parameter is identified)."""
        from ..io.tables import write_files

        return write_files(out_dir, self.writers(truth, call, partial))

    def markdown(self, truth=None) -> str:
        """A short Markdown report: the verdict, the estimates table, the figures."""
        table = self.to_pandas(truth=truth)
        lines = ["# Identification of the actuator (paper section III.2)", "",
                 ("**Result:** " if self.ok else "**Result NOT usable as it is:** ")
                 + self.summary(), "",
                 "Records: " + ", ".join(f"`{Path(r.source).name}`" for r in self.records),
                 "", _markdown(table), ""]
        if self.diagnostics:
            lines += ["## Diagnostics", ""] + [f"- {d.line()}" for d in self.diagnostics]
            lines.append("")
        for name in self.stages:
            lines += [f"## {STAGES[name]}", "", f"![{name}](stage_{name}.png)", ""]
        return "\n".join(lines)


#: ``summary`` lists at most this many distinct errors and remedies (a screen).
SUMMARY_ERRORS = 5
SUMMARY_REMEDIES = 8
#: ... each cut to this many characters.
SUMMARY_WIDTH = 160


def _value_in(params, name: str) -> float:
    """``params[name]``, or NaN for a bench parameter the set does not state."""
    return float(params[name]) if name in params else float("nan")


def _shorten(text: str) -> str:
    return text if len(text) <= SUMMARY_WIDTH else text[: SUMMARY_WIDTH - 1] + "…"


def _markdown(table: pd.DataFrame) -> str:
    """A DataFrame as a Markdown table (numbers to 5 significant digits)."""
    def cell(value) -> str:
        if isinstance(value, (float, np.floating)):
            return f"{value:.5g}"
        return str(value)

    header = [table.index.name or "", *map(str, table.columns)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for index, row in table.iterrows():
        lines.append("| " + " | ".join([str(index), *map(cell, row)]) + " |")
    return "\n".join(lines)


# --------------------------------------------------------------------------- the procedure
def _kinds(records: Sequence[Record]) -> dict[str, list[Record]]:
    kinds: dict[str, list[Record]] = {"sweep": [], "ramp": [], "presliding": []}
    for rec in records:
        kinds[record_kind(rec)].append(rec)
    missing = [k for k, v in kinds.items() if not v]
    if missing:
        raise DataError(f"identify_paper: no {', '.join(missing)} record among "
                        f"{', '.join(Path(r.source).name for r in records)}; a sweep alone "
                        "is a signature (identify_signature, pneumact identify signature); "
                        "for every parameter, run the tests of `pneumact campaign --plan`")
    return kinds


def _staged(kinds, prior, friction, fit_delta, sliding_speed, prior_spread, step):
    """Stages (a)-(d): (stages, staged parameter set, diagnostics). A stage the records
    cannot support leaves the prior's values, with a diagnostic."""
    diagnostics: list[Diagnostic] = []
    step("spring", 0.0)
    spring = stage_spring(kinds["sweep"], prior)
    current = prior.with_values({"F0": spring.estimates["F0"], "k": spring.estimates["k"]})
    stages = {"spring": spring}
    step("sliding", 0.1)
    # the slowest creep that is not sliding: the prior's presliding range, at the low end
    # of the prior's σ0
    creep = presliding_range(prior) / max(1.0 - prior_spread, 0.1)
    try:
        segments = segments_of(kinds["sweep"] + kinds["ramp"], current, creep)
    except DataError as exc:
        diagnostics.append(Diagnostic("warning", "(b, c)", str(exc),
                                      "add ramps at several steady speeds"))
        segments = None
    if segments is not None:
        sliding, stribeck, notes = sliding_and_stribeck(segments, current, fit_delta,
                                                        sliding_speed)
        diagnostics += notes
        if sliding is not None and stribeck is not None:
            stages.update(sliding=sliding, stribeck=stribeck)
            current, found = _accept(current, {"Fc": sliding.estimates["Fc"],
                                               "sigma2": sliding.estimates["sigma2"],
                                               **stribeck.estimates.as_dict()}, "(b, c)")
            diagnostics += found
    step("presliding", 0.2)
    try:
        presliding = stage_presliding(kinds["presliding"], current, friction, prior=prior)
        stages["presliding"] = presliding
        if presliding.extra["stuck"]:  # no value at a bound goes on: the prior's does
            diagnostics.append(Diagnostic(
                "warning", "(d)", f"{presliding.extra['stuck']}; the next stages start "
                "from the prior's σ0 and σ1", REMEDIES["sigma0"]))
        else:
            current, found = _accept(current, presliding.estimates.as_dict(), "(d)")
            diagnostics += found
    except (DataError, SolverError) as exc:
        diagnostics.append(Diagnostic("warning", "(d)", f"the presliding fit failed: {exc}"))
    return stages, current, diagnostics


def _accept(params, updates: dict[str, float], stage: str):
    """``params`` with a stage's estimates; one the parameter set refuses (a negative σ2
    from noisy segments) keeps its earlier value, with a diagnostic."""
    from ..parameters import catalogue

    specs = catalogue()
    refused = {n for n, v in updates.items()
               if not (np.isfinite(v) and specs[n].in_range(np.array([v]))[0])}
    notes = [Diagnostic("warning", stage, f"the estimate {n} = {updates[n]:.4g} is not "
                        "physical; the next stages start from the earlier value "
                        f"{params[n]:.4g}", REMEDIES.get(n, "")) for n in sorted(refused)]
    kept = {n: v for n, v in updates.items() if n not in refused}
    try:
        return params.with_values(kept), notes
    except ParameterError as exc:  # a relation between the kept ones (Fs < Fc)
        return params, [*notes, Diagnostic("warning", stage, f"its estimates are not "
                                           f"physical together ({exc}); the next stages "
                                           "start from the earlier values")]


#: σ0 and σ1 are identifiable from a presliding test only when its static deflection
#: Fs/σ0 is at least this many position-noise standard deviations: below it the stuck
#: mode's steps and ringing drown in the sensor's noise and resolution, and any
#: estimate comes from the fine shape of the slow ramps' motion, which an output-error
#: fit follows into spurious optima (measured: σ0 27 % off with a 1.4 % standard error
#: on a drawn actuator whose Fs/σ0 was 1.2 µm against 1.2 µm of noise).
PRESLIDING_SIGNAL = 3.0
PRESLIDING_PARAMETERS = ("sigma0", "sigma1")


def _presliding_identifiable(kinds, staged) -> tuple[bool, str]:
    """(whether the presliding records can tell σ0 and σ1, the reason if not)."""
    from .inputs import sensor_noise

    deflection = staged["Fs"] / staged["sigma0"]
    noise = max(sensor_noise(r["position"]) for r in kinds["presliding"])
    if deflection >= PRESLIDING_SIGNAL * noise:
        return True, ""
    return False, (f"the presliding deflection Fs/σ0 ≈ {deflection * 1e6:.2g} µm is within "
                   f"{PRESLIDING_SIGNAL:g}× the position noise ({noise * 1e6:.2g} µm)")


def _refine(records, kinds, staged, *, friction, chamber, free, replicates, seed, workers,
            step, prior, held: dict[str, float], max_evaluations: int,
            partial: bool = False):
    """The joint refinement, its input-noise covariance, the share of the parameters
    ``held`` at the prior (name -> standard deviation of the prior's value), and its
    residual checks. Returns (joint fit, input noise, final estimates, residual checks,
    diagnostics). With ``partial``, a fit that follows too few of the records to speak
    for the campaign is kept (``joint_refinement``): the verdicts then refuse what rests
    on the records it left out."""
    from ..simulation import Rodas4

    diagnostics: list[Diagnostic] = []
    step("joint refinement", 0.3)
    chaotic: list[str] = []
    joint = joint_refinement(records, kinds, staged, friction=friction, chamber=chamber,
                             free=free, replicates=replicates, seed=seed, executor=workers,
                             prior=prior, excluded=chaotic,
                             max_evaluations=max_evaluations, partial=partial)
    joint, optima, stuck = restart_at_bounds(joint, prior, max_evaluations=max_evaluations)
    if stuck:
        diagnostics.append(Diagnostic(
            "warning", "joint", f"{stuck} (started again from the prior's value and spread "
            "starts): the records do not hold it inside its search range", "the tests "
            "the verdicts name for it, designed from the prior (not from the stuck value)"))
    for name in chaotic:
        diagnostics.append(Diagnostic(
            "warning", "joint", f"{Path(name).name} left out of the joint fit: the model "
            "fitted to the steady records does not follow it (a stick-slip whose timing "
            "no output-error fit follows sample by sample)", "ramps at steadier speeds "
            "(above the stick-slip range) carry the same information; compare the loops "
            "with pneumact validate"))
    step("input noise", 0.7)
    noise = input_noise_covariance(joint, replicates=replicates or INPUT_REPLICATES,
                                   seed=seed + 1, workers=workers,
                                   solver=Rodas4(rtol=JOINT_RTOL))
    checks = residual_checks(joint, noise.moves)
    fidelity = np.diag((MODEL_FIDELITY * joint.estimates.values) ** 2)
    fidelity[[j for j, n in enumerate(joint.estimates.names) if "[" in n]] = 0.0
    covariance = joint.estimates.covariance + noise.covariance + fidelity
    steps = quantised_records(joint)
    if steps:
        covariance = covariance + quantisation_covariance(joint, steps, seed=seed + 2)
    if held:
        covariance = covariance + nuisance_covariance(joint, held, Rodas4(rtol=JOINT_RTOL),
                                                      workers)
    estimates = with_covariance(joint.estimates, covariance)
    estimates, found = _covering(joint, estimates, optima)
    diagnostics += found
    if not joint.success:
        diagnostics.append(Diagnostic("error", "joint", "the joint fit did not converge: "
                                      + joint.message,
                                      "check the starting values (the prior) and the records"))
    for r in checks.itertuples():
        if not r.fits:
            diagnostics.append(Diagnostic(
                "error", "joint", f"the model does not fit {Path(r.record).name}: its "
                f"residual RMS is {r.ratio:.3g}× the noise ({r.residual_rms:.3g} against "
                f"{r.sensor_noise:.3g}) and its slow part {r.structure:.3g}× what noise "
                "leaves", MISFIT_REMEDY + "; or the fit stopped in a local optimum"))
    return joint, noise, estimates, checks, diagnostics


def _noise_variance(joint) -> float:
    """The joint fit's residual variance in its scaled cost (2·cost/dof): the noise the
    other optima and refits are judged against."""
    return 2.0 * joint.cost / max(joint.estimates.dof, 1)


def _covering(joint, estimates: Estimates, optima: list) -> tuple[Estimates, list[Diagnostic]]:
    """``estimates`` whose intervals reach every other optimum of the joint fit's restarts
    within the noise (``optima.cover_optima``; the noise variance is the joint fit's
    residual variance), and a warning that names the parameters so widened."""
    covariance, widened = cover_optima(estimates.covariance, estimates.values, joint.cost,
                                       [(o.estimates.values, o.cost) for o in optima],
                                       _noise_variance(joint))
    names = [n for n, w in zip(estimates.names, widened, strict=True) if w and "[" not in n]
    if not names:
        return estimates, []
    return with_covariance(estimates, covariance), [Diagnostic(
        "warning", "joint", f"the joint fit has more than one optimum within the noise for "
        f"{', '.join(names)}: their intervals cover them all",
        "; ".join(dict.fromkeys(REMEDIES.get(n, "") for n in names)))]


#: A refit at a held parameter's end starts at the joint optimum and is given this many
#: evaluations: on `family-7-32` (seed 1) they took 9-19; the 20-actuator validation
#: family had one actuator whose four took 54 s on one core with 40.
HELD_REFIT_EVALUATIONS = 20


def _covering_held(joint, estimates: Estimates, held: dict[str, float], workers: int
                   ) -> tuple[Estimates, list[Diagnostic]]:
    """``estimates`` whose intervals reach the joint fit's optimum with each parameter
    ``held`` at either end of its 95 % range (its value ± 1.96 × the standard deviation
    ``held`` gives), and a warning naming the parameters so widened. The linear share
    (``uncertainty.nuisance_covariance``) misses what a held value does beyond its
    tangent: on a drawn actuator whose presliding test could not tell σ0, the prior's σ0
    (+39 %) took vs to +10.7 % at ±1.9 %, where the linear share had added ±0.2 %."""
    from .fit import map_on_threads

    ends = [{name: joint.base_values[name] + sign * 1.96 * std}
            for name, std in held.items() for sign in (-1.0, 1.0)
            if joint.base_values[name] - 1.96 * std > 0 or sign > 0]
    every = [True] * len(joint.records)
    refits = map_on_threads(workers, lambda end: refit_without(
        joint, every, HELD_REFIT_EVALUATIONS, held=end), ends)
    others = [np.array([r.values.get(n, v) for n, v in zip(
        estimates.names, estimates.values, strict=True)]) for r in refits if r is not None]
    covariance, widened = cover_values(estimates.covariance, estimates.values, others)
    names = [n for n, w in zip(estimates.names, widened, strict=True) if w and "[" not in n]
    if not names:
        return estimates, []
    return with_covariance(estimates, covariance), [Diagnostic(
        "warning", "joint", f"{', '.join(names)} move{'s' if len(names) == 1 else ''} with "
        f"the value at which {', '.join(held)} {'is' if len(held) == 1 else 'are'} held "
        "(refitted at either end of the prior's range): their intervals cover that",
        "; ".join(dict.fromkeys(REMEDIES[n] for n in held)))]


#: A position-sensor lag the prior does not state and the joint fit did not take is
#: freed in one refit from the joint optimum (``_freed_lag``), started at zero and
#: searched in [``LAG_REFIT_RANGE``] [s] (linear scale): on the 40-actuator study 17 lags
#: of 0.5-15 ms were not found, and 21 intervals missed on them.
LAG_REFIT_RANGE = (0.0, 0.05)
#: The lag hypothesis fits a lag that refit found where it lowered the cost by this share
#: at least: a 1 ms lag on a drawn actuator 95 %, a 9.4 ms lag under 26 µm steps 30 %;
#: a stick-slipping campaign without one 0.02 % (beyond the noise all the same)
LAG_COST_GAIN = 0.05


def _freed_lag(joint, refits: dict) -> FitResult | None:
    """The ``joint`` fit refitted from its optimum with a position-sensor lag freed from
    zero (``LAG_REFIT_RANGE``, ``HELD_REFIT_EVALUATIONS``), kept in ``refits`` by the
    joint fit's identity (the lag hypothesis and the intervals ask the same)."""
    kept = refits.get(id(joint))
    if kept is None or kept[0] is not joint:  # the joint fit itself is kept: ids recur
        kept = refits[id(joint)] = (joint, refit_without(
            joint, [True] * len(joint.records), HELD_REFIT_EVALUATIONS,
            freed={"position_lag": (0.0, *LAG_REFIT_RANGE)}))
    return kept[1]


def _lowers_cost(joint, refit) -> bool:
    """Whether ``refit`` fits the records better than ``joint`` beyond the noise
    (``optima.CHI2_95_1DOF`` in scaled cost) and by at least ``LAG_COST_GAIN`` of the
    cost (a misfit's cost falls beyond the noise with any parameter freed)."""
    return bool(2.0 * (joint.cost - refit.cost) / _noise_variance(joint) > CHI2_95_1DOF
                and refit.cost <= (1.0 - LAG_COST_GAIN) * joint.cost)


def _covering_lag(joint, estimates: Estimates, refits: dict
                  ) -> tuple[Estimates, list[Diagnostic]]:
    """``estimates`` whose intervals reach the joint fit's optimum with a position-sensor
    lag freed (``LAG_REFIT_RANGE``) where that refit fits the records within the noise
    of the joint fit or better, and a warning naming the lag and the parameters so
    widened. A lag is k·τ of viscous friction to the steady slides and a delay to the
    transients: one the records barely tell from none moves σ2, vs and the spring line
    by more than their intervals (a drawn actuator, 0.62 ms at 461 Hz: vs −0.52 % at
    ±0.4 %)."""
    refit = _freed_lag(joint, refits)
    if refit is None:
        return estimates, []
    other = np.array([refit.values.get(n, v) for n, v in zip(
        estimates.names, estimates.values, strict=True)])
    covariance, widened = cover_optima(estimates.covariance, estimates.values, joint.cost,
                                       [(other, refit.cost)], _noise_variance(joint))
    names = [n for n, w in zip(estimates.names, widened, strict=True) if w and "[" not in n]
    if not names:
        return estimates, []
    lag = refit.values["position_lag"]
    return with_covariance(estimates, covariance), [Diagnostic(
        "warning", "bench", f"{', '.join(names)} move{'s' if len(names) == 1 else ''} with "
        f"a position-sensor lag the prior does not state: a refit that frees it "
        f"({lag * 1e3:.3g} ms) fits the records as well, and their intervals cover it",
        "state the position sensor's time constant as position_lag in the prior (its "
        "datasheet, or its response to a step)")]


def _attempt(records, kinds, staged, free, options) -> tuple[tuple | None, list[Diagnostic]]:
    """The joint refinement (``_refine``) as (joint fit, input noise, estimates, residual
    checks) and its diagnostics, or None and the reason it could not run."""
    try:
        joint, noise, final, residuals, found = _refine(records, kinds, staged, free=free,
                                                        **options)
    except DataError as exc:
        return None, [Diagnostic("error", "joint", str(exc), "ramps at speeds where the "
                                 "diaphragm slides steadily")]
    return (joint, noise, final, residuals), found


def _misfits(outcome) -> float:
    """How many records the joint fit does not fit (inf when it could not run)."""
    if outcome is None:
        return np.inf
    return float((~outcome[3]["fits"]).sum()) + (0.0 if outcome[0].success else 0.5)


def _lag_hypothesis(records, kinds, staged, free, first, options, restage, longest,
                    refits: dict):
    """Where the model does not fit: does a position-sensor lag explain it? The lag that
    predicts the records best (``faults.lag_search``) starts a joint fit that frees it
    (``position_lag``) from the stages run again on the records with that lag undone
    (``restage``); where no lag of the search predicts them much better but a refit of
    the first joint fit that frees one (``_freed_lag``) fits them better beyond the
    noise and by ``LAG_COST_GAIN``, a joint fit frees it from the staged values and half
    a sample period, and where that misses records, from the refit's values (where the
    first joint fit could not run, the refit is of the partial fit of the records the
    model follows, which is then returned when no lag is taken). Kept only when the
    model with it fits every record and the lag's interval excludes none. Lags up to
    ``longest`` [s] are searched (``faults.viscous_lag_bound``). Returns
    (outcome, its diagnostics, the staged values it started from, the free names,
    notes)."""
    outcome, found = first
    tau, lagged, error_with, error_without = lag_search(
        records, kinds, staged, restage, options["friction"], options["chamber"],
        options["workers"], longest)
    starts = [(lagged, "the stages on the records with the lag undone (stage (c) takes "
               "k·τ of a lag for viscous friction)")]
    if not (tau > 0 and error_with <= LAG_GAIN * error_without):
        # no lag of the grid predicts the records much better (a 9.4 ms lag under 26 µm
        # quantisation at 253 Hz, which the staged σ2 had taken as k·τ: the grid's best
        # predicted 0.74 of the error); a joint fit that frees one fitted every record
        if outcome is None:  # the partial answer the caller would fit next, asked here
            outcome, partial_found = _attempt(records, kinds, staged, free,
                                              {**options, "partial": True})
            found = found + partial_found
        refit = None if outcome is None else _freed_lag(outcome[0], refits)
        if refit is None or not _lowers_cost(outcome[0], refit):
            return outcome, found, staged, free, []
        # from the staged values and half a sample period, then from the refit's values:
        # on the 40-actuator study each start fitted campaigns the other missed (from the
        # refit, 0.78 and 1.26 ms lags stopped at 8.8 and 1.05 ms; from the stages, a
        # campaign whose refit found its lag missed records)
        tau = 0.0
        starts = [(staged.with_values({"position_lag": 0.5 * finest_sample_period(
                      records, kinds)}), "the staged values and half a sample period of lag"),
                  (staged.with_values(feasible(refit.values, staged)),
                   "a refit of the joint fit that freed it")]
    with_lag = [*free, "position_lag"]
    for start, how in starts:
        lagged, started = start.with_values({n: staged[n] for n in options["held"]}), how
        again, found_again = _attempt(records, kinds, lagged, with_lag, options)
        if _misfits(again) == 0:
            break
    if _misfits(again) > 0:
        searched = f"a position-sensor lag of {tau * 1e3:.3g} ms predicts the records " \
            "better than none, but " if tau > 0 else ""
        return outcome, found, staged, free, [Diagnostic(
            "note", "bench", f"{searched}the joint fit that frees a position-sensor lag "
            "does not fit every record either: no lag taken for the cause")]
    assert again is not None  # it fits more records than the first attempt
    estimates = again[2]
    j = estimates.names.index("position_lag")
    low, high = estimates.interval(0.95)[j]
    if not low > 0 or stuck_at_bounds(again[0])[j]:
        return outcome, found, staged, free, [Diagnostic(
            "note", "bench", f"a joint fit that frees a position-sensor lag fits the records "
            f"with {estimates.values[j] * 1e3:.3g} ms, but its interval reaches no lag at "
            "all: not taken for the cause")]
    note = Diagnostic(
        "warning", "bench", f"the position sensor lags: a first-order lag of "
        f"{estimates.values[j] * 1e3:.4g} ms [{low * 1e3:.4g}, {high * 1e3:.4g}] makes the "
        f"model fit records it did not without it; it is fitted with the other parameters "
        f"(position_lag), started from {started}",
        "a faster position sensor, or state its time constant as position_lag in the prior")
    return again, found_again, lagged, with_lag, [note]


def _staged_checks(records, staged, friction, chamber, workers: int) -> pd.DataFrame:
    """Does the model at the staged values predict each record (``joint.
    prediction_ratio``: the position error's RMS within ``MISFIT_RATIO`` noise
    deviations)? The stages fit force balances, not the motion: a sensor lag that eq. 13
    takes for viscous friction (σ2 ten times too large) fits them and misses the
    records; a staged result is judged by the same residual check as a joint one. The
    records run on ``workers`` threads."""
    from .fit import map_on_threads
    from .joint import prediction_ratio

    ratios = map_on_threads(workers, lambda r: prediction_ratio(
        r, record_kind(r), staged, friction, chamber), records)
    return pd.DataFrame([{"record": Path(r.source).name, "signal": "position", "ratio": ratio,
                          "fits": bool(ratio <= MISFIT_RATIO)}
                         for r, ratio in zip(records, ratios, strict=True)],
                        columns=["record", "signal", "ratio", "fits"])


def _presliding_check(records, kinds, params) -> list[Diagnostic]:
    """Did each presliding test stay in presliding (excursion below
    ``PRESLIDING_EXCURSION``·Fs/σ0 after its approach)?"""
    out = []
    deflection = params["Fs"] / params["sigma0"]
    for record in kinds["presliding"]:
        start = presliding_window(record, params)
        x = record["position"][record.time >= start]
        if x.size < 2:
            continue
        excursion = float(np.ptp(x))
        if excursion > PRESLIDING_EXCURSION * deflection:
            out.append(Diagnostic(
                "warning", "presliding", f"{Path(record.source).name} moved {excursion * 1e6:.3g}"
                f" µm after its approach, more than {PRESLIDING_EXCURSION:g}·Fs/σ0 = "
                f"{PRESLIDING_EXCURSION * deflection * 1e6:.3g} µm: it slid, so it tells "
                "σ0 and σ1 apart from sliding friction less well",
                f"use pressure steps below {params['Fs'] / params['A_d'] * 1e-3:.3g} kPa "
                "(Fs/A_d) after the stop"))
    return out


def _slow_end_only(records: Sequence[Record], fits: Sequence[bool]) -> bool:
    """Whether the model misses only the slow end of the campaign: every sweep fitted,
    every ramp it misses slower than every ramp it fits, and nothing else missed but
    presliding tests. That is the stick-slip regime output error cannot follow (a drawn
    actuator: the five slowest ramps and the presliding test missed at estimates a
    refit without them puts within 0.02 % of the truth for F0, k and Fc); a steady ramp
    missed among fitted ones says the model lacks something everywhere (an unmodelled
    44 µm / 1.6 ms sensor: a refit without the missed records put Fc 0.65 % off at
    ±0.23 %), and then the missed records are judged by one linear step."""
    from .bench import typical_speed

    kinds = [record_kind(r) for r in records]
    if any(not ok and kind == "sweep" for ok, kind in zip(fits, kinds, strict=True)):
        return False
    speeds = {ok: [typical_speed(r) for r, k, f in zip(records, kinds, fits, strict=True)
                   if k == "ramp" and f == ok] for ok in (True, False)}
    return bool(speeds[True]) and (not speeds[False] or max(speeds[False]) < min(speeds[True]))


def _undersampled(sensors: pd.DataFrame, params, refused,
                  estimate: dict[str, float] | None = None) -> dict[str, str]:
    """σ0 and σ1 (those not in ``refused``) where the presliding test is sampled below
    ``faults.PRESLIDING_ALIASED`` samples per period of the stuck mode, at the prior's
    σ0 or at the ``estimate``'s, whichever is stiffer (a prior is a guess): name -> why.
    Slow ramps are not judged so: the paper's own campaign slides through them steadily
    at 100 Hz, and its Fs and vs hold."""
    stiffer = params
    if estimate and estimate.get("sigma0", 0.0) > params["sigma0"]:
        stiffer = params.with_values({"sigma0": estimate["sigma0"]})
    rate = undersampled_presliding(sensors, stiffer, PRESLIDING_ALIASED)
    if rate is None:
        return {}
    why = (f"the presliding test is sampled at {rate:.3g} Hz, under "
           f"{PRESLIDING_ALIASED:g} samples per stuck-mode period: it aliases")
    return {n: why for n in PRESLIDING_PARAMETERS if n not in refused}


def _resting_on_misfits(kinds, residuals, refused: dict[str, str]
                        ) -> dict[str, str]:
    """σ0 and σ1 rest on the presliding tests: where the model fits none of them, the
    sliding records the refit keeps (``joint.refit_without``) still give σ0 and σ1
    finite standard errors, from the bristles' small part in sliding, and an interval
    that does not hold (measured on a drawn actuator: σ0 −2.8 % at ±1.3 %). Refused
    then, with the reason; ``refused`` (already refused) is left as it is."""
    fitting = list(residuals.loc[residuals["fits"], "record"])
    tests = [Path(r.source).name for r in kinds["presliding"]]
    # a presliding test is fitted after its approach: "presliding (0..2.83 s)"
    if not tests or any(fitted == name or fitted.startswith(f"{name} (")
                        for name in tests for fitted in fitting):
        return {}
    why = (f"it rests on the presliding test{'s' if len(tests) > 1 else ''} "
           f"({', '.join(tests)}), which the model does not fit or the fit left out")
    return {n: why for n in PRESLIDING_PARAMETERS if n not in refused}


#: the parameters only the ramps slower than vs pin down (the Stribeck dip)
STRIBECK_DIP_PARAMETERS = ("Fs", "vs")


def _stribeck_dip_check(ramp_records, residuals, estimate, judged, diagnostics):
    """Fs and vs are pinned down by the ramps slower than vs. If the joint fit left every
    such ramp out (their stick-slip is not followed sample by sample), or there is none
    (a second round's ramps above the speeds that stick-slip), Fs and vs rest on
    faster records, where the Stribeck curve can trade Fs against vs: measured, a
    campaign of 4 ramp pairs gave Fs +18 %, vs −16 % with ±1 % intervals. Then they are
    poorly identified, for that reason (a diagnostic says so), and shown without an
    interval (it would not hold), whatever their verdict. Returns (verdicts, the
    parameters shown without an interval)."""
    from .bench import typical_speed

    vs = estimate.get("vs")
    ramps = [(r, typical_speed(r)) for r in ramp_records]
    if vs is None or not ramps:
        return judged, []
    used = set(residuals.loc[residuals["fits"], "record"]) if len(residuals) else set()
    slow = [(r, v) for r, v in ramps if v < vs]
    if any(Path(r.source).name in used for r, _ in slow):
        return judged, []
    names = ", ".join(Path(r.source).name for r, _ in slow)
    reason = (f"the ramps slower than vs = {vs * 1e3:.3g} mm/s ({names}) were left out of "
              "the joint fit or are not fitted by it: Fs and vs rest on faster records"
              if slow else
              f"no ramp is slower than vs = {vs * 1e3:.3g} mm/s: Fs and vs rest on faster "
              "records")
    diagnostics.append(Diagnostic("warning", "joint", reason, "ramps below vs that the "
                                  "diaphragm slides through steadily (a stiffer regulator, "
                                  "or more ramp speeds between vs/3 and vs)"))
    refused = [v.parameter for v in judged
               if v.parameter in STRIBECK_DIP_PARAMETERS and v.identified]
    return [Verdict(v.parameter, POORLY, reason, REMEDIES.get(v.parameter, ""))
            if v.parameter in refused else v for v in judged], \
        [v.parameter for v in judged if v.parameter in STRIBECK_DIP_PARAMETERS]


@one_blas_thread
@remembered  # runs repeated across stages, restarts and rounds are done once (``memo``)
def identify_paper(records: Sequence[Record], params, *, friction=None, chamber=None,
                   fit_delta: bool = False, sliding_speed: float | None = None,
                   prior_spread: float = 0.5, refine: bool = True,
                   replicates: int | None = None, seed: int = 0,
                   executor: Executor | int | None = None,
                   max_evaluations: int = MAX_EVALUATIONS, name: str | None = None,
                   progress: ProgressCallback | None = None
                   ) -> PaperIdentification:
    """Identify the actuator from bench ``records`` (sweeps, ramps, presliding tests; see
    ``record_kind``) and the ``params`` a user knows (see the module docstring).

    ``params`` gives the geometry, gas and valve, and rough starting values of the spring
    and friction (``prior_spread``: their relative uncertainty, ±50 % by default, sizes
    the creep a steady segment must exceed). ``friction`` and ``chamber`` are the laws
    the model uses (LuGre, isothermal by default). ``sliding_speed`` [m/s] fixes the
    threshold of eq. 13 instead of deriving it from vs (it is then only checked).
    ``refine=False`` stops after the stages (fast; their intervals are conditional on
    the earlier stages). ``replicates`` of the input-noise bootstrap (default
    ``uncertainty.INPUT_REPLICATES``, drawn with ``seed``) run on the ``executor``'s
    threads (an ``Executor`` or a number of threads); each round of the joint
    fit gives up after ``max_evaluations``. ``progress`` is called with a
    ``pneumact.progress.Progress`` (the stage's name, the fraction of the whole done) as
    the work goes on.
    """
    from ..io.records import as_records
    from ..parameters import as_parameter_set

    records = as_records(records, "identify_paper")
    _check_unique_names(records)
    params = as_parameter_set(params, "identify_paper")
    if "x_max" in params:  # positions in % labelled [mm] (83 mm on a 20 mm stroke)
        for record in records:
            record.check_within_stroke(params["x_max"], "identify_paper")
    pool = Executor.of(executor, "identify_paper")
    workers = pool.workers
    if not 0 <= prior_spread < 1:
        raise ParameterError(f"identify_paper: prior_spread = {prior_spread}; must be in "
                             "[0, 1) (the prior's relative uncertainty)")
    check_progress(progress, "identify_paper")

    def step(label: str, fraction: float) -> None:
        notify(progress, label, fraction, 1.0)

    if not any(record_kind(r) == "ramp" for r in records) and \
            any(record_kind(r) == "sweep" for r in records):
        return identify_signature(records, params, prior_spread=prior_spread, name=name,
                                  progress=progress)
    zero = position_zero(records, params, prior_spread)
    side = pressure_side(zero.records, params, friction, chamber, pool.threads)
    records = side.records
    kinds = _kinds(records)
    stages, staged, diagnostics = _staged(kinds, params, friction, fit_delta, sliding_speed,
                                          prior_spread, step)
    diagnostics = zero.diagnostics + side.diagnostics + diagnostics
    notes, sensors = sensor_notes(records, [record_kind(r) for r in records], params)
    diagnostics += notes
    free = list(SPRING_AND_FRICTION) + (["delta"] if fit_delta else [])
    presliding_ok, why_not = _presliding_identifiable(kinds, staged)
    held: dict[str, float] = {}
    if not presliding_ok:  # held at the prior; their uncertainty goes into the others'
        held = {n: params[n] * prior_spread / 1.96 for n in PRESLIDING_PARAMETERS}
        free = [n for n in free if n not in held]
        staged = staged.with_values({n: params[n] for n in held})
        diagnostics.append(Diagnostic(
            "warning", "presliding", f"σ0 and σ1 are not identifiable: {why_not}; they are "
            "held at the prior's values, and the uncertainty of those (±"
            f"{100 * prior_spread:.0f} %) is carried into the other parameters' intervals",
            "a position sensor with less noise and a finer resolution, or larger presliding "
            "steps if the friction allows"))
    joint = input_noise = regulator = None
    if refine:
        options = dict(friction=friction, chamber=chamber, replicates=replicates, seed=seed,
                       workers=workers, step=step, prior=params, held=held,
                       max_evaluations=max_evaluations)
        kind_list = [record_kind(r) for r in records]
        lag_refits: dict[int, tuple[FitResult, FitResult | None]] = {}
        outcome, found = _attempt(records, kind_list, staged, free, options)
        if _misfits(outcome) and "position_lag" not in params:
            def restage(undone):
                return _staged(_kinds(undone), params, friction, fit_delta, sliding_speed,
                               prior_spread, lambda *_: None)[1]

            # stage (c) reads a lag as viscous friction: its σ2 bounds the lag (without
            # stage (c), σ2 is the prior's and bounds nothing)
            longest = viscous_lag_bound(staged) if "sliding" in stages else np.inf
            outcome, found, staged, free, note = _lag_hypothesis(
                records, kind_list, staged, free, (outcome, found), options, restage,
                longest, lag_refits)
            diagnostics += note
        diagnostics += found
        if _misfits(outcome):  # is it the regulator? asked at the best values there are
            best = staged if outcome is None else staged.with_values(
                feasible(outcome[2].as_dict(), staged))
            regulator, found = regulator_check(records, best, friction, chamber,
                                               pool.threads)
            diagnostics += found
        if outcome is None:  # a partial answer: the fit of the records the model follows
            outcome, found = _attempt(records, kind_list, staged, free,
                                      {**options, "partial": True})
            diagnostics += found
        if outcome is None:  # nothing left that output error can follow
            refine = False
        else:
            joint, input_noise, final_values, residuals = outcome
            if held:
                final_values, found = _covering_held(joint, final_values, held,
                                                     pool.threads)
                diagnostics += found
            if "position_lag" not in params and "position_lag" not in free:
                final_values, found = _covering_lag(joint, final_values, lag_refits)
                diagnostics += found
    joint_failed = False
    converged = False
    if refine:
        assert joint is not None  # refine is still True: the joint fit ran
        converged = bool(joint.success)
        misfit = [Path(r).name for r, fits in zip(residuals["record"], residuals["fits"],
                                                   strict=True) if not fits]
        lower, upper = joint.bounds
        at_bound = (np.isclose(final_values.values, lower, rtol=1e-6)
                    | np.isclose(final_values.values, upper, rtol=1e-6))
    else:
        final_values = _staged_estimates(stages, staged, free)
        joint_failed = any(d.stage == "joint" for d in diagnostics)
        residuals = _staged_checks(records, staged, friction, chamber, pool.threads)
        misfit = [Path(r).name for r, fits in zip(residuals["record"], residuals["fits"],
                                                   strict=True) if not fits]
        if misfit:
            diagnostics.append(Diagnostic(
                "error", "stages", f"the model at the staged values does not predict "
                f"{named_list(misfit)} (position error above {MISFIT_RATIO:g}× the noise): "
                "the stages' force balances hide what the motion shows", MISFIT_REMEDY))
        at_bound = np.zeros(len(final_values.names), bool)
    diagnostics += _presliding_check(records, kinds, staged)
    ci = final_values.interval(0.95)
    names = [n for n in final_values.names if "[" not in n]
    idx = [final_values.names.index(n) for n in names]
    half = (ci[idx, 1] - ci[idx, 0]) / 2
    caveat = ""
    estimate = final_values.as_dict()
    if "Fs" in estimate and "Fc" in estimate and estimate["Fs"] < estimate["Fc"]:
        diagnostics.append(Diagnostic(
            "error", "joint", f"the fit asks for Fs = {estimate['Fs']:.4g} N below Fc = "
            f"{estimate['Fc']:.4g} N: the records show no static friction above the "
            "Coulomb level, which LuGre cannot produce that way", "check the friction law "
            "(pneumact compare) and the slow ramps"))
        misfit = [*misfit, "the Stribeck curve (Fs < Fc)"]
    refused: dict[str, str] = {}
    trusted: list[str] = []
    if not refine and joint_failed:
        caveat = "the joint refinement could not run: staged values, no interval holds"
    elif misfit and refine and converged and len(misfit) == int((~residuals["fits"]).sum()):
        # only records misfit: judge each parameter by what those records do to it
        assert joint is not None
        fits = list(residuals["fits"])
        refit = (refit_without(joint, fits, max_evaluations)
                 if len(misfit) <= MISFIT_REFIT_SHARE * len(fits)
                 or _slow_end_only(joint.records, fits) else None)
        refused, moves = misfit_influence(joint, fits, final_values.stderr, refit)
        refused.update(_resting_on_misfits(kinds, residuals, refused))
        moves = {n: m for n, m in moves.items() if n not in refused}
        final_values = _with_moves(final_values, moves)
        ci = final_values.interval(0.95)
        half = (ci[idx, 1] - ci[idx, 0]) / 2
        trusted = list(moves)
    elif misfit:
        caveat = f"the model does not fit {named_list(misfit)}, so no interval holds"
    elif refine and not converged:
        caveat = "the joint fit did not converge, so no interval holds"
    judged = verdicts(names, final_values.values[idx], half, at_bound[idx], caveat)
    judged = [Verdict(v.parameter, POORLY, refused[v.parameter], MISFIT_REMEDY)
              if v.parameter in refused and v.verdict != NOT_IDENTIFIABLE else v
              for v in judged]
    no_interval: list[str] = []
    if refine:
        judged, no_interval = _stribeck_dip_check(kinds["ramp"], residuals, estimate,
                                                  judged, diagnostics)
        unfitted = _resting_on_misfits(kinds, residuals, {n: "" for n in held})
        unfitted.update(_undersampled(sensors, params, {**unfitted, **held}, estimate))
        judged = [Verdict(v.parameter, POORLY, unfitted[v.parameter], MISFIT_REMEDY)
                  if v.parameter in unfitted and v.identified else v for v in judged]
        no_interval += list(unfitted)
    final_values, judged, from_line = _spring_line(records, params, prior_spread,
                                                   final_values, judged)
    if held:  # shown at the prior's values, with no interval
        judged += [Verdict(n, "not identifiable", why_not, REMEDIES[n]) for n in held]
        final_values = _with_held(final_values, list(held), staged)
    diagnostics += _beyond_the_prior(final_values, params, prior_spread)
    when = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    from ..version import __version__

    names = [n for n in final_values.names if "[" not in n]
    idx = [final_values.names.index(n) for n in names]
    sources = {n: ("identified, joint refinement" if refine else
                   f"identified, stage {_stage_of(stages, n)}") for n in names}
    sources.update({n: "prior value, held: not identifiable" for n in held})
    sources.update({n: "identified, the sweep's spring line" for n in from_line})
    identified = with_estimates(
        params, Estimates(tuple(names), final_values.values[idx], final_values.stderr[idx],
                          final_values.covariance[np.ix_(idx, idx)], final_values.dof,
                          tuple(final_values.units[i] for i in idx)),
        sources, name or f"{params.name}-identified",
        {"identified": f"pneumact {__version__} identify_paper, {when}",
         "records": ", ".join(Path(r.source).name for r in records)})
    identified = _with_bench(identified, side, zero, sensors)
    step("done", 1.0)
    return PaperIdentification(stages, joint, final_values, judged, diagnostics, residuals,
                               identified, params, records, input_noise, staged,
                               {"friction": friction, "chamber": chamber,
                                "trusted": trusted + from_line, "no_interval": no_interval,
                                "joint_failed": joint_failed,
                                "pressure_side": side, "position_zero": zero,
                                "sensors": sensors,
                                "regulator": regulator})


def _check_unique_names(records: Sequence[Record]) -> None:
    """Records are told apart by their names (the fit's weights, the records left out):
    two of one name, as two rounds of one plan give, would be taken for one."""
    names = [Path(r.source).name for r in records]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataError(f"identify_paper: records = {', '.join(twice)} appear more than once; "
                        "each record needs a name of its own (a second round's tests end in "
                        "_round2: PaperIdentification.next_round)")


def _with_bench(identified, side, zero, sensors: pd.DataFrame):
    """The identified set with what the records say of the bench: the pressure and
    position sensors' offsets where they were taken off, the position resolution where
    the records show one."""
    from ..parameters import ParameterSet
    from ..parameters.parameter_set import ParameterInfo, number_text

    found: dict[str, tuple[float, str, str]] = {}
    if side.applied:
        found["pressure_offset"] = (side.offset, "bench: set-point/pressure pairs",
                                    f"± {side.offset_stderr:.3g} (standard error)")
    if zero.applied:
        found["position_offset"] = (zero.offset, "bench: the records at rest on the stop",
                                    f"± {zero.offset_stderr:.3g} (standard error)")
    step = float(sensors["position_resolution"].max()) if len(sensors) else 0.0
    if step > 0:
        found["position_resolution"] = (step, "bench: read from the records", "")
    if not found:
        return identified
    values, info = dict(identified.values), dict(identified.info)
    for name, (value, source, note) in found.items():
        values[name] = value
        info[name] = ParameterInfo(number_text(name, value), source, note)
    return ParameterSet(values, name=identified.name, description=identified.description,
                        provenance=identified.provenance, info=info)


def _spring_line(records: Sequence[Record], params, spread: float, estimates: Estimates,
                 judged: list[Verdict]) -> tuple[Estimates, list[Verdict], list[str]]:
    """F0 and k from the sweeps' spring line where the joint fit could not vouch for
    them and agrees with it (``signature.spring_line_check``): their values, covariance
    block (no correlation with the others kept) and verdicts replaced. Returns the
    estimates, the verdicts and the names replaced."""
    from .signature import signature_records, spring_line_check

    kinds = [record_kind(r) for r in records]
    sweeps = signature_records(records, kinds) if "sweep" in kinds else []
    line, vouched = spring_line_check(sweeps, params, spread, estimates, judged)
    if line is None:
        return estimates, judged, []
    values, cov = estimates.values.copy(), estimates.covariance.copy()
    names = [v.parameter for v in vouched]
    rows = [estimates.names.index(n) for n in names]
    source = [line.names.index(n) for n in names]
    values[rows] = line.values[source]
    cov[rows, :] = 0.0
    cov[:, rows] = 0.0
    cov[np.ix_(rows, rows)] = line.covariance[np.ix_(source, source)]
    replaced = Estimates(estimates.names, values, np.sqrt(np.diag(cov)), cov,
                         estimates.dof, estimates.units)
    by_name = {v.parameter: v for v in vouched}
    return replaced, [by_name.get(v.parameter, v) for v in judged], names


def _with_moves(estimates: Estimates, moves: dict[str, float]) -> Estimates:
    """``estimates`` with each move that leaving the misfit records out makes
    (``diagnostics.misfit_influence``) added to that estimate's variance."""
    cov = estimates.covariance.copy()
    for name, move in moves.items():
        j = estimates.names.index(name)
        cov[j, j] += move**2
    return with_covariance(estimates, cov)


def _beyond_the_prior(estimates: Estimates, prior, spread: float) -> list[Diagnostic]:
    """A warning for each estimate that left the prior's range (±``spread``): the
    campaign was designed for another actuator, and a second round designed from the
    estimates fits this one."""
    out = []
    for name, value in estimates.as_dict().items():
        if "[" in name or name not in prior or prior[name] == 0:
            continue
        off = value / prior[name] - 1.0
        if abs(off) > spread:
            out.append(Diagnostic(
                "warning", "prior", f"{name} = {value:.4g} is {100 * off:+.0f} % from the "
                f"prior's {prior[name]:.4g}, beyond its ±{100 * spread:.0f} %: the tests "
                "were designed for another actuator", "design a second round from these "
                "estimates: ident.next_round() (pneumact campaign --plan --params "
                "identified.toml --round 2)"))
    return out


def _with_held(estimates: Estimates, names: Sequence[str], params) -> Estimates:
    """``estimates`` and the parameters ``names`` held at their values in ``params``,
    with infinite variance (the records do not determine them)."""
    from ..parameters import catalogue

    n_old, n_new = len(estimates.names), len(estimates.names) + len(names)
    cov = np.full((n_new, n_new), np.inf)
    cov[:n_old, :n_old] = estimates.covariance
    return Estimates((*estimates.names, *names),
                     np.concatenate([estimates.values, [params[n] for n in names]]),
                     np.concatenate([estimates.stderr, np.full(len(names), np.inf)]),
                     cov, estimates.dof,
                     (*estimates.units, *(catalogue()[n].unit for n in names)))


def _stage_of(stages, name: str) -> str:
    for stage in stages.values():
        if name in stage.estimates.names:
            return stage.title.split()[0]
    return ""


def _staged_estimates(stages, staged, free: Sequence[str]) -> Estimates:
    """The stages' results as one (block-diagonal) set of the ``free`` parameters: the
    values the stages handed on (``staged``: an estimate a stage could not support, or
    an unphysical one, kept the prior's value and gets an infinite variance)."""
    from ..parameters import catalogue

    errors = {}
    for stage in stages.values():
        for j, n in enumerate(stage.estimates.names):
            if stage.estimates.values[j] == staged[n] if n in free else False:
                errors[n] = stage.estimates.stderr[j]
    values = np.array([staged[n] for n in free])
    stderr = np.array([errors.get(n, np.inf) for n in free])
    cov = np.diag(stderr**2)
    dof = min(s.estimates.dof for s in stages.values())
    return Estimates(tuple(free), values, stderr, cov, dof,
                     tuple(catalogue()[n].unit for n in free))


# --------------------------------------------------------------------------- a signature
@dataclass(eq=False)
class SignatureIdentification(PaperIdentification):
    """What one slow up-and-down loop (a valve signature) tells (``identify_signature``):
    F0, k, Fc (σ2 where the speed varies) with their verdicts, the others not
    identifiable from a signature with the test that would tell each, and the valve
    engineer's numbers (``to_pandas("valve")``: bench set, spring rate, friction band,
    dead band, with 95 % intervals)."""

    report_title = "Identification from a valve signature (one slow up-and-down loop)"
    figure_name = "signature"

    valve: pd.DataFrame = field(default_factory=pd.DataFrame)
    structure: float = 0.0

    @property
    def intervals_hold(self) -> bool:
        """The spring line with constant friction fits the branches."""
        return self.structure <= MISFIT_STRUCTURE

    @property
    def signature_ok(self) -> bool:
        """What a signature can tell (F0, k, Fc) is identified, and no error was found."""
        return all(v.identified for v in self.verdicts if v.parameter in ("F0", "k", "Fc")) \
            and not any(d.severity == "error" for d in self.diagnostics)

    def tables(self) -> dict[str, pd.DataFrame]:
        return {**super().tables(), "valve": self.valve}

    def writers(self, truth=None, call: str = "", partial: bool = True) -> dict:
        """``PaperIdentification.writers`` and valve_numbers.csv."""
        writers = super().writers(truth, call, partial)
        writers["valve_numbers.csv"] = lambda p: self.valve.to_csv(p)
        return writers

    def plot(self) -> Figure:
        """The signature as a valve engineer reads it: vacuum against travel, measured,
        with the spring line (the bench set); below it, zoomed, the measurement less the
        spring line, where the friction band shows, with the two branches the friction
        level puts either side; at the bottom the residual of the branches."""
        import matplotlib.pyplot as plt

        area, p_atm = self.initial["A_d"], self.initial["p_atm"]
        f0, k = self.estimates["F0"], self.estimates["k"]
        level = float(self.valve.loc["friction force on the branches", "value"]) / area
        fig, (ax, axb, axr) = plt.subplots(3, 1, sharex=True, figsize=(7.0, 7.5),
                                           gridspec_kw={"height_ratios": [2, 2, 1]})
        x = np.linspace(0.0, self.initial["x_max"], 50)
        for record in (r for r in self.records if record_kind(r) == "sweep"):
            position = record["position"]
            vacuum = p_atm - record[PRESSURE_SIGNAL]
            ax.plot(position * 1e3, vacuum * 1e-3, "k.", ms=1, alpha=0.4,
                    label=f"measured: {Path(record.source).name}")
            axb.plot(position * 1e3, (vacuum - (f0 + k * position) / area) * 1e-3, "k.",
                     ms=1, alpha=0.4)
        line = (f0 + k * x) / area
        ax.plot(x * 1e3, line * 1e-3, "C0-", lw=1.2, label="spring line (bench set)")
        ax.set_ylabel("vacuum p_atm − p [kPa]")
        ax.set_title(f"valve signature: bench set {line[0] * 1e-3:.4g}–{line[-1] * 1e-3:.4g}"
                     f" kPa, friction band {2 * level * 1e-3:.3g} kPa", fontsize=10)
        ax.legend(fontsize=8, loc="upper left")
        axb.axhline(0.0, color="C0", lw=1.2)
        for sign in (1, -1):
            axb.axhline(sign * level * 1e-3, color="C3", ls="--", lw=0.9)
        axb.set_ylim(-3 * level * 1e-3, 3 * level * 1e-3)
        axb.set_ylabel("less the spring line [kPa]")
        axb.set_title("zoomed: the friction band (branches: ± friction level / A_d)",
                      fontsize=9)
        data = self.stages["signature"].data
        axr.plot(data["x"], (data["measured"] - data["fitted"]) / area * 1e-3, "C3.", ms=1)
        axr.axhline(0.0, color="k", lw=0.6)
        axr.set_ylabel("residual [kPa]")
        axr.set_xlabel("position [mm]")
        for a in (ax, axb, axr):
            a.grid(True, alpha=0.3)
        tight_layout(fig)
        return fig

    def figures(self) -> dict[str, Callable[[], Figure]]:
        """The signature (``plot``): vacuum against travel with the fitted lines."""
        return {"stage_signature": self.plot}

    def extra_tables(self) -> dict[str, pd.DataFrame]:
        return {"The valve engineer's numbers, with 95 % intervals (SI; display: kPa, mm, "
                "N)": self.valve}


def identify_signature(records: Sequence[Record], params, *, prior_spread: float = 0.5,
                       name: str | None = None,
                       progress: ProgressCallback | None = None) -> SignatureIdentification:
    """Identify what a valve signature can tell (``identification.signature``): F0, k,
    Fc (σ2 where the speed varies) from the sweep records among ``records`` (slow
    pressure sweeps up and down; other records are named and not used), with the
    prior ``params`` (geometry, and rough friction values within ±``prior_spread``: they
    bound the Stribeck term the friction level may hold); Fs, vs, σ0 and σ1 stay at the
    prior's values, named as not identifiable from a signature with the test that would
    tell each; and the valve engineer's numbers (bench set, spring rate, friction band,
    dead band). A position sensor's offset is read where a sweep starts at rest on the
    lower stop, a pressure sensor's from a sweep that logged its regulator's set-point,
    and each is taken off (``faults.position_zero``, ``faults.pressure_side``; in
    ``bench_table()``)."""
    from ..io.records import as_records
    from ..parameters import as_parameter_set
    from ..version import __version__
    from .signature import (
        signature_fit,
        signature_records,
        signature_verdicts,
        valve_numbers,
    )

    records = as_records(records, "identify_signature")
    params = as_parameter_set(params, "identify_signature")
    if not 0 <= prior_spread < 1:
        raise ParameterError(f"identify_signature: prior_spread = {prior_spread}; must be "
                             "in [0, 1) (the prior's relative uncertainty)")
    check_progress(progress, "identify_signature")
    notify(progress, "signature", 0.0, 1.0)
    zero = position_zero(records, params, prior_spread)  # a sweep starts on the stop
    # a regulator's sweep logs set-point and pressure: a pressure sensor's offset moves
    # the spring line by offset·A_d (F0 wrong by 3-16 % at 0.5-2 kPa on the family)
    side = pressure_side(zero.records, params)
    records = side.records
    kinds = [record_kind(r) for r in records]
    sweeps = signature_records(records, kinds)
    diagnostics: list[Diagnostic] = list(zero.diagnostics) + list(side.diagnostics)
    lag = float(params["position_lag"]) if "position_lag" in params else 0.0
    if lag > 0:  # a stated lag: k·τ·|v| of friction on the branches, and transients
        sweeps = without_lag(sweeps, lag)
        diagnostics.append(Diagnostic(
            "note", "signature", f"the position sensor's stated lag of {lag * 1e3:.3g} ms "
            "(position_lag) is undone on the sweeps before the spring line is fitted"))
    unused = [Path(r.source).name for r, k in zip(records, kinds, strict=True) if k != "sweep"]
    if unused:
        diagnostics.append(Diagnostic(
            "note", "signature", f"{', '.join(unused)} not used: without ramps the "
            "friction curve below the sweep's speed is unknown, which the other stages need",
            "ramps at steady speeds (pneumact campaign --plan) for the full procedure"))
    fitted = signature_fit(sweeps, params, prior_spread)
    diagnostics += list(fitted.diagnostics)
    if not fitted.structure <= MISFIT_STRUCTURE:
        diagnostics.append(Diagnostic(
            "error", "signature", f"the spring line with constant friction does not fit the "
            f"branches (structure {fitted.structure:.3g}× noise)", MISFIT_REMEDY))
    names = [n for n in SPRING_AND_FRICTION if n in params]
    judged = signature_verdicts(fitted, names)
    est = fitted.estimates
    held = [n for n in names if n not in est.names]
    estimates = _with_held(est, held, params)
    order = [estimates.names.index(n) for n in names]
    estimates = Estimates(tuple(names), estimates.values[order], estimates.stderr[order],
                          estimates.covariance[np.ix_(order, order)], estimates.dof,
                          tuple(estimates.units[i] for i in order))
    when = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    sources = {n: "identified, signature" if n in est.names and
               np.isfinite(estimates.stderr[names.index(n)]) else
               "prior value, held: not identifiable from a signature" for n in names}
    identified = with_estimates(
        params, estimates, sources, name or f"{params.name}-identified",
        {"identified": f"pneumact {__version__} identify_signature, {when}",
         "records": ", ".join(Path(r.source).name for r in sweeps)})
    diagnostics += _beyond_the_prior(est, params, prior_spread)
    valve = valve_numbers(fitted, sweeps, params)
    notify(progress, "done", 1.0, 1.0)
    return SignatureIdentification(
        {"signature": fitted.stage}, None, estimates, judged, diagnostics, pd.DataFrame(),
        identified, params, list(records), None, None,
        {"friction": None, "chamber": None, "joint_failed": False, "position_zero": zero,
         "pressure_side": side},
        valve, fitted.structure)
