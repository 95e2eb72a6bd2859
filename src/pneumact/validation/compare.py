"""Which friction law do my records support? Each law fitted on training records, scored
on held-out ones.

``compare_friction_models(model, records, laws)`` puts each law into ``model`` (an
``Actuator`` or a ``FrictionRig``), fits the law's own parameters
(``FrictionModel.comparison_parameters``) to the training records with the general
``fit`` (finite differences for a law that refuses sensitivities, Latin-hypercube starts
for a law of many parameters), then simulates the held-out records with the estimates.
Per law: the held-out fit %, the loop measures (an actuator's pressure-position loops),
the whiteness of the held-out residuals, the parameter count, AIC and BIC on the training
records and the verdict on each estimate (``diagnostics.verdicts``).

**Within the noise.** Held-out squared errors of two laws differ by a loss differential
d_t = e_a(t)² − e_b(t)² whose mean is tested against zero with its long-run (HAC) variance,
as residuals of a dense record are correlated in time (the Diebold-Mariano test): a law
whose differential to the best has |z| < ``NOISE_Z`` cannot be told from it. The
recommendation is the law of fewest parameters among the best and those that cannot be
told from it, and the report says when more than one law is in that group ("cannot
tell"): records without what a law needs to show (presliding reversals for GMS, slow
sliding for a Stribeck dip) fit several laws equally well.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import time as _time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ..errors import ParameterError, PneumactError
from ..identification import FitResult, experiment_for, fit
from ..identification.arguments import fit_records
from ..identification.diagnostics import verdicts
from ..identification.estimates import long_run_variance
from ..io.records import PRESSURE_SIGNAL, Record
from ..io.report import ResultVocabulary
from ..models.actuator import CHAMBER_PRESSURE
from ..models.inputs import INPUT_SIGNALS
from ..options import Executor, Multistart, Optimizer
from ..plotting import tight_layout
from ..progress import ProgressCallback, notify, stop_threads
from .loops import loop_measures
from .metrics import autocorrelation, error_metrics

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..models.friction import FrictionModel

__all__ = ["DEFAULT_LAWS", "FrictionComparison", "compare_friction_models"]

#: the laws compared when none are named
DEFAULT_LAWS = ("lugre", "gms:4", "elasto-plastic", "dahl", "stribeck")
#: |z| of the loss differential below which two laws cannot be told apart (95 %, two-sided)
NOISE_Z = 1.96
#: Latin-hypercube starts ("auto") for a law of more free parameters than
MANY_PARAMETERS = 8
AUTO_STARTS = 4
#: the box every law's fit searches (and "auto" draws its starts in): the start ×/÷ this.
#: Over the catalogue's ranges, a law that does not suit the records runs away to the stiff
#: end (the elasto-plastic law on a static map's records: σ0 → 1e8 and 500 000 steps a
#: run, 190 s for one fit); an estimate that ends at the box's edge is flagged as such
SEARCH_BOX = 10.0
#: the steps a run of the comparison may take (default solver): a trial point where a law
#: chatters fails in a second instead of the default limit's minutes (a law that cannot
#: be fitted is reported with the reason; ordinary runs take a few thousand steps)
MAX_STEPS = 200_000


@dataclass(eq=False)
class LawScore:
    """One law: its fit on the training records and its predictions of the held-out ones
    (``error``: why it could not be fitted, then nothing else is set)."""

    label: str
    law: Any
    free: tuple[str, ...] = ()
    fit: FitResult | None = None
    predictions: list = field(default_factory=list)
    residuals: list = field(default_factory=list)
    seconds: float = 0.0
    error: str = ""


def _weighted_errors(records, predictions, signals, weights) -> list[np.ndarray]:
    """Per held-out record, the residuals of every signal, each over its weight's scale
    (the fit's: 1/std of the measured signal), one after the other."""
    return [np.concatenate([weights[s] * (pred[s] - rec[s]) for s in signals])
            for rec, pred in zip(records, predictions, strict=True)]


def loss_differential_z(errors_a: Sequence[np.ndarray], errors_b: Sequence[np.ndarray]
                        ) -> float:
    """z of mean(e_a² − e_b²) over records with the HAC variance of each record's
    differential (Diebold-Mariano): negative when ``a`` predicts better."""
    total, variance, n = 0.0, 0.0, 0
    for ea, eb in zip(errors_a, errors_b, strict=True):
        d = ea**2 - eb**2
        total += float(d.sum())
        variance += long_run_variance(d)
        n += d.size
    if n == 0:
        return 0.0
    if variance <= 0.0:
        return 0.0 if total == 0.0 else float(np.sign(total) * np.inf)
    return float(total / np.sqrt(variance))


def _whiteness(errors: Sequence[np.ndarray]) -> float:
    """The fraction of residual autocorrelations (lags 1..min(N/4, 200)) outside the
    ±1.96/√N band of white noise, over the held-out records: 0.05 for white residuals."""
    outside, lags = 0, 0
    for e in errors:
        acf, band = autocorrelation(e)
        outside += int(np.sum(np.abs(acf[1:]) > band))
        lags += acf.size - 1
    return outside / lags if lags else np.nan


def _loop_error(model, records, predictions, signal: str) -> float:
    """Mean relative error of the loop width in pressure over the held-out records (an
    actuator's pressure-position loops), NaN for a model without them."""
    if model.input_signal not in INPUT_SIGNALS.values() or signal != "position":  # no valve
        return np.nan
    errors = []
    for rec, pred in zip(records, predictions, strict=True):
        pressure = (rec[PRESSURE_SIGNAL] if PRESSURE_SIGNAL in rec
                    else pred[CHAMBER_PRESSURE])
        try:
            measured = loop_measures(rec.time, pressure, rec["position"])
            modelled = loop_measures(rec.time, pred[CHAMBER_PRESSURE], pred["position"])
        except PneumactError:
            continue
        width = measured["loop_width_pressure"]
        if np.isfinite(width) and width > 0:
            errors.append((modelled["loop_width_pressure"] - width) / width)
    return float(np.mean(errors)) if errors else np.nan


def _with_law(model, law):
    """``model`` with ``law`` as its friction, its set completed with the law's own
    parameters where it lacks them (``FrictionModel.matched_values``)."""
    params = model.params.replace(law.matched_values(model.params))
    return dataclasses.replace(model, friction=law, params=params)


def _free_parameters(law, model) -> tuple[str, ...]:
    """The law's comparison parameters that its starting set has non-zero (a zero is a
    term the set switches off: it stays off)."""
    return tuple(n for n in law.comparison_parameters() if model.params[n] != 0.0)


def _box(name: str, start: float, law) -> tuple[float, float]:
    """×/÷ ``SEARCH_BOX`` about ``start``, inside the catalogue's plausible range (the
    elasto-plastic z_ba_ratio at 0.999 makes α step from 0 to 1 within 0.1 % of z_ss: a
    run of millions of steps) and the law's ``comparison_ranges``, the start always
    inside."""
    from ..parameters import catalogue

    start = abs(start)
    low, high = start / SEARCH_BOX, start * SEARCH_BOX
    spec = catalogue().get(name)
    for limits in (spec.plausible if spec is not None else None,
                   law.comparison_ranges.get(name)):
        if limits is not None:
            low, high = max(low, min(limits[0], start)), min(high, max(limits[1], start))
    return low, high


def _search(multistart, model, free) -> tuple[Multistart, dict]:
    """The starts of one law's fit and the box it searches (``_box``)."""
    box = {n: _box(n, model.params[n], model.friction) for n in free}
    if multistart != "auto":
        return Multistart.of(multistart, "compare_friction_models"), box
    return Multistart(AUTO_STARTS if len(free) > MANY_PARAMETERS else 0), box


def _score_one(model, law, train, test, signals, multistart, solver, window, also, offsets,
               optimizer, smooth_input) -> LawScore:
    """Fit ``law`` on ``train``, predict ``test``; failures are the score's ``error``."""
    label = law.spec
    began = _time.perf_counter()
    try:
        own = _with_law(model, law)
        free = (*_free_parameters(law, own), *also)
        if own.sensitivity_refusal and optimizer.jacobian == "sensitivities":
            optimizer = dataclasses.replace(optimizer, jacobian="2-point")
        starts, box = _search(multistart, own, free)
        result = fit(own, train, list(free), signals=signals, optimizer=optimizer,
                     multistart=starts, bounds=box, executor=1,
                     solver=solver, window=window, offsets=offsets,
                     smooth_input=smooth_input)
        predictions = [_prediction(own, rec, solver, result, offsets, smooth_input)
                       for rec in test]
    except PneumactError as exc:
        return LawScore(label, law, seconds=_time.perf_counter() - began, error=str(exc))
    weights = {s: result.weight(0, s) for s in signals}
    return LawScore(label, law, free, result, predictions,
                    _weighted_errors(test, predictions, signals, weights),
                    _time.perf_counter() - began)


def _smooth(model, smooth_input: bool | None) -> bool:
    """Whether a record's input is rebuilt piecewise linear (``fit``'s ``smooth_input``);
    None: a pressure or a command, yes; a measured motion that drives a rig, no (its
    slope is the velocity the friction law sees: a smooth, coarsely sampled position
    passes for noisy, and its rebuild with few knots loses 5-7 % of the fit of the law
    that made it; a noisy one, as a laser's, needs the rebuild: its raw slope dithers
    the bristles)."""
    if smooth_input is not None:
        return bool(smooth_input)
    return model.input_signal not in ("position", "velocity")


def _prediction(model, record, solver, result: FitResult, offsets, smooth_input: bool):
    """The model's simulation of a held-out record at the estimates, each signal with a
    fitted sensor offset shifted by the training records' mean offset."""
    from ..simulation import simulate

    values = {n: v for n, v in result.values.items() if not n.startswith("offset_")}
    run = simulate(model, experiment_for(model, record, smooth=smooth_input), solver,
                   t_eval=record.time, values=values)
    if not offsets:
        return run
    shifted = {}
    for signal in offsets:
        mean = np.mean([v for n, v in result.values.items()
                        if n.startswith(f"offset_{signal}[")])
        shifted[signal] = run[signal] + mean
    return _Shifted(run, shifted)


@dataclass(frozen=True, eq=False)
class _Shifted:
    """A simulation whose signals in ``shifted`` read their offset values."""

    run: Any
    shifted: dict

    def __getitem__(self, name: str) -> np.ndarray:
        return self.shifted[name] if name in self.shifted else self.run[name]

    @property
    def units(self):
        return self.run.units

    def __getattr__(self, name: str):
        return getattr(self.run, name)


def _checked_signals(model, records, signals, also) -> tuple[str, ...]:
    """``signals`` as a tuple, once each, in every record with the model's input; ``also``
    parameters of the model: refused before any law is fitted (a law's own failure is its
    row in the table, a mistake of the call is not)."""
    from ..core.assembly import assemble

    signals = (signals,) if isinstance(signals, str) else tuple(signals)
    if not signals or len(set(signals)) != len(signals):
        raise ParameterError(f"compare_friction_models: signals = {list(signals)}; name each "
                             "measured signal once")
    for record in records:
        record.require([*signals, model.input_signal], "compare_friction_models")
    assemble(model).check_parameters(list(also), "compare_friction_models: also")
    return signals


def _split(records: list[Record], holdout) -> tuple[list[Record], list[Record], list[int]]:
    """(training, held-out, held-out indices): ``holdout`` indices, default the last
    record; one record is split in time (its first 2/3 train, all of it is predicted and
    scored after the split)."""
    n = len(records)
    if holdout is None:
        holdout = [n - 1] if n > 1 else []
    held = sorted({int(i) for i in holdout})
    bad = [i for i in held if not -n <= i < n]
    if bad:
        raise ParameterError(f"compare_friction_models: holdout = {bad[0]}: no such record "
                             f"(0 to {n - 1})")
    held = sorted({i % n for i in held})
    if n > 1 and len(held) == n:
        raise ParameterError("compare_friction_models: every record is held out; keep at "
                             "least one to fit on")
    if n == 1:
        return records, records, [0]
    return ([r for i, r in enumerate(records) if i not in held],
            [records[i] for i in held], held)


def compare_friction_models(model, records: Record | Sequence[Record],
                            laws: Sequence[str | FrictionModel] = DEFAULT_LAWS, *,
                            holdout: Sequence[int] | None = None,
                            signals: Sequence[str] = ("position",),
                            also: Sequence[str] = (), offsets: Sequence[str] = (),
                            multistart: Multistart | int | str = "auto",
                            optimizer: Optimizer | str | None = None,
                            smooth_input: bool | None = None,
                            executor: Executor | int | str | None = None, solver=None,
                            progress: ProgressCallback | None = None) -> FrictionComparison:
    """Fit each of ``laws`` (names as ``--friction`` gives them, "gms:4", or instances)
    in ``model`` on the training records and score it on the held-out ones (see the
    module docstring).

    ``holdout``: indices of the held-out records (default: the last; a single record is
    fitted on its first two thirds and scored on the rest); ``signals``: the measured
    signals the laws are fitted to and scored on ("friction" for a rig driven by a
    measured motion); ``also``: parameters fitted beside every law's own (a rig's moving
    mass ``m``); ``offsets``: signals with a sensor offset per training record (a
    held-out record is predicted with their mean); ``multistart``: starts per law
    ("auto": ``AUTO_STARTS`` for a law of more than ``MANY_PARAMETERS`` free
    parameters, GMS; each law searches ×/÷ ``SEARCH_BOX`` about its start, in the
    catalogue's plausible ranges); ``optimizer``: how every law's least squares runs (a
    law that refuses forward sensitivities gets a "2-point" Jacobian); ``smooth_input``:
    rebuild each record's input piecewise linear (``fit``'s; None: for a pressure or
    command, not for a measured motion, see ``_smooth``); ``executor``: the
    laws run on its threads (default every core) or its Dask scheduler. ``progress``
    gets stage "compare" (laws done of all).
    """
    from ..models.friction import friction_law

    records = fit_records(records)
    if not laws:
        raise ParameterError("compare_friction_models: laws = []; name at least two laws")
    chosen = [friction_law(spec) for spec in laws]
    labels = [law.spec for law in chosen]
    if len(set(labels)) != len(labels):
        raise ParameterError(f"compare_friction_models: a law is named twice in {labels}")
    signals = _checked_signals(model, records, signals, also)
    train, test, held = _split(records, holdout)
    window = None
    scored_from = None
    if len(records) == 1:
        rec = records[0]
        split = float(rec.time[0] + 2.0 / 3.0 * (rec.time[-1] - rec.time[0]))
        window, scored_from = (float(rec.time[0]), split), split
    executor = Executor.of(executor, "compare_friction_models")
    optimizer = Optimizer.of(optimizer)
    smooth = _smooth(model, smooth_input)
    jobs = [(model, law, train, test, signals, multistart, solver, window, tuple(also),
             tuple(offsets), optimizer, smooth) for law in chosen]
    scores = _run(jobs, executor, progress)
    if scored_from is not None:
        for score in scores:
            keep = [np.concatenate([(test[0].time >= scored_from)] * len(signals))]
            score.residuals = [e[k] for e, k in zip(score.residuals, keep, strict=False)]
    return FrictionComparison(model=model, scores=scores, train=train, test=test,
                              held_out=held, signals=signals, scored_from=scored_from)


def _run(jobs, executor: Executor, progress) -> list[LawScore]:
    """Each law's score, in the order of ``jobs``: on the executor's threads (a fit
    simulates in compiled code that releases the GIL) or its Dask scheduler."""
    if executor.scheduler is not None:
        from ..simulation.batch.engine import dask_client

        client, owned = dask_client(executor.scheduler)
        remote: list = []
        try:
            remote = client.map(_score_one, *zip(*jobs, strict=True), pure=False)
            gathered = client.gather(remote)
        except BaseException:  # Ctrl-C: the laws not begun on the workers are dropped
            client.cancel(remote)
            raise
        finally:
            if owned:
                client.close()
        notify(progress, "compare", len(jobs), len(jobs))
        return list(gathered)
    scores: list[LawScore | None] = [None] * len(jobs)
    with stop_threads(ThreadPoolExecutor(max_workers=max(1, min(executor.threads,
                                                                 len(jobs))))) as pool:
        futures = {pool.submit(_score_one, *job): k for k, job in enumerate(jobs)}
        for done, future in enumerate(as_completed(futures), start=1):
            scores[futures[future]] = future.result()
            notify(progress, "compare", done, len(jobs))
    return [score for score in scores if score is not None]


# --------------------------------------------------------------------------- the result
@dataclass(eq=False)
class FrictionComparison(ResultVocabulary):
    """The laws side by side: ``to_pandas()`` the comparison table (one row per law, best
    held-out prediction first), ``"estimates"`` each law's estimates with their verdicts,
    ``"held_out"`` the scores per held-out record; ``recommendation`` and ``reasons``;
    ``plot()`` the loops of every law over the held-out measurement."""

    report_title = "Which friction law do the records support?"
    figure_name = "loops"

    model: Any
    scores: list[LawScore]
    train: list[Record]
    test: list[Record]
    held_out: list[int]
    signals: tuple[str, ...]
    scored_from: float | None = None

    # -- the numbers ---------------------------------------------------------------------
    @property
    def fitted(self) -> list[LawScore]:
        return [s for s in self.scores if not s.error]

    def _held_out_cost(self, score: LawScore) -> float:
        n = sum(e.size for e in score.residuals)
        return float(sum(float(e @ e) for e in score.residuals) / max(n, 1))

    def ranking(self) -> list[LawScore]:
        """The fitted laws, best held-out prediction (least mean squared weighted error)
        first."""
        return sorted(self.fitted, key=self._held_out_cost)

    def z_against_best(self) -> dict[str, float]:
        """label -> z of its loss differential against the best law (0 for the best)."""
        ranked = self.ranking()
        if not ranked:
            return {}
        best = ranked[0]
        return {s.label: 0.0 if s is best else loss_differential_z(s.residuals, best.residuals)
                for s in ranked}

    def tied(self) -> list[LawScore]:
        """The best law and those that cannot be told from it (|z| < NOISE_Z)."""
        z = self.z_against_best()
        return [s for s in self.ranking() if abs(z[s.label]) < NOISE_Z]

    @property
    def recommended(self) -> LawScore | None:
        """The law of fewest parameters among the best and those within its noise."""
        tied = self.tied()
        return min(tied, key=lambda s: (len(s.free), self._held_out_cost(s))) if tied else None

    @property
    def cannot_tell(self) -> bool:
        """Whether the held-out records leave more than one law within the best's noise."""
        return len(self.tied()) > 1

    def _fit_percent(self, records, simulated, scored_from: float | None = None) -> float:
        """Mean fit % over ``records`` and the signals (after ``scored_from`` if given)."""
        values = []
        for rec, sim in zip(records, simulated, strict=True):
            mask = np.ones(rec.time.size, bool) if scored_from is None else \
                rec.time >= scored_from
            values += [error_metrics(rec[s][mask], sim[s][mask])["fit_percent"]
                       for s in self.signals]
        return float(np.mean(values))

    def _verdicts(self, score: LawScore) -> list:
        result = score.fit
        assert result is not None
        est = result.estimates
        ci = est.interval()
        half = (ci[:, 1] - ci[:, 0]) / 2.0
        lo, hi = result.bounds
        at_bound = [bool(len(lo) and (np.isclose(v, lo[j], rtol=1e-6)
                                      or np.isclose(v, hi[j], rtol=1e-6)))
                    for j, v in enumerate(est.values)]
        return verdicts(est.names, est.values, half, at_bound)

    def _table(self) -> pd.DataFrame:
        """One row per law, best held-out prediction first, failed laws last."""
        rows = []
        z = self.z_against_best()
        tied = {s.label for s in self.tied()}
        recommended = self.recommended
        for score in self.ranking():
            result = score.fit
            assert result is not None
            n_res = result.residuals.size
            ssr = float(result.residuals @ result.residuals)
            k = len(score.free)
            judged = self._verdicts(score)
            verdict = ("recommended" if score is recommended else
                       "best held-out prediction" if z[score.label] == 0.0 else
                       "cannot tell from the best" if score.label in tied else "worse")
            rows.append({
                "law": score.label, "parameters": k,
                "train_fit_%": self._fit_percent(result.records, [
                    {s: result.fitted(i, s) for s in self.signals}
                    for i in range(len(result.records))]),
                "held_out_fit_%": self._fit_percent(self.test, score.predictions,
                                                    self.scored_from),
                "held_out_mse": self._held_out_cost(score),
                "z_vs_best": z[score.label],
                "loop_width_error_%": 100 * _loop_error(self.model, self.test,
                                                        score.predictions, self.signals[0]),
                "residual_acf_outside_%": 100 * _whiteness(score.residuals),
                "aic": n_res * np.log(max(ssr, 1e-300) / n_res) + 2 * k,
                "bic": n_res * np.log(max(ssr, 1e-300) / n_res) + k * np.log(n_res),
                "identified": sum(v.identified for v in judged),
                "not_identified": ", ".join(v.parameter for v in judged if not v.identified),
                "verdict": verdict, "seconds": score.seconds, "error": ""})
        for score in self.scores:
            if score.error:
                rows.append({"law": score.label, "verdict": "failed", "error": score.error,
                             "seconds": score.seconds})
        frame = pd.DataFrame(rows)
        if "bic" in frame:
            frame.insert(frame.columns.get_loc("bic") + 1, "delta_bic",
                         frame["bic"] - frame["bic"].min())
        return frame

    def estimates(self) -> pd.DataFrame:
        """Every law's estimates with standard errors, intervals and verdicts (long)."""
        frames = []
        for score in self.fitted:
            assert score.fit is not None
            frame = score.fit.to_pandas().reset_index()
            judged = {v.parameter: v for v in self._verdicts(score)}
            frame["verdict"] = [judged[n].verdict for n in frame["parameter"]]
            frame["reason"] = [judged[n].reason for n in frame["parameter"]]
            frame.insert(0, "law", score.label)
            frames.append(frame)
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def held_out_scores(self) -> pd.DataFrame:
        """Per law and held-out record: RMS and fit % of each signal."""
        rows = []
        for score in self.fitted:
            for rec, pred in zip(self.test, score.predictions, strict=True):
                mask = np.ones(rec.time.size, bool) if self.scored_from is None else \
                    rec.time >= self.scored_from
                for s in self.signals:
                    m = error_metrics(rec[s][mask], pred[s][mask])
                    rows.append({"law": score.label, "record": os.path.basename(rec.source),
                                 "signal": s, "unit": rec.units.get(s, ""), "rms": m["rms"],
                                 "fit_%": m["fit_percent"]})
        return pd.DataFrame(rows)

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"comparison": self._table(), "estimates": self.estimates(),
                "held_out": self.held_out_scores()}

    # -- the words -----------------------------------------------------------------------
    @property
    def recommendation(self) -> str:
        best = self.recommended
        if best is None:
            return "No law could be fitted: see each law's error in the table."
        ranked = self.ranking()
        if self.cannot_tell:
            tied = [s.label for s in self.tied()]
            listed = ", ".join(tied[:-1]) + f" and {tied[-1]}"
            return (f"Cannot tell: the held-out records fit {listed} within their noise; "
                    f"the simplest, {best.label} ({len(best.free)} parameters), is "
                    "recommended.")
        if len(ranked) == 1:
            return f"{best.label} is the only law fitted: there is nothing to rank it against."
        runner = ranked[1].label
        return (f"{best.label} predicts the held-out records best, beyond the noise of the "
                f"next, {runner}.")

    def reasons(self) -> list[str]:
        """Why: the held-out errors, the tie, the parameters the records do not fix, the
        laws that failed."""
        table = self._table()
        lines = []
        fitted = table[table["verdict"] != "failed"]
        for _, row in fitted.iterrows():
            tail = f"; not identified: {row['not_identified']}" if row["not_identified"] else ""
            lines.append(f"{row['law']}: held-out fit {row['held_out_fit_%']:.1f} %, "
                         f"z = {row['z_vs_best']:+.2f} against the best, "
                         f"{int(row['parameters'])} parameters, ΔBIC "
                         f"{row['delta_bic']:.3g}{tail}")
        if self.cannot_tell:
            lines.append(f"|z| < {NOISE_Z} (the mean loss differential within its HAC "
                         "noise): the records do not discriminate these laws; records "
                         "with what the others need (small reversals for presliding "
                         "memory, slow sliding for the Stribeck dip) would.")
        for score in self.scores:
            if score.error:
                lines.append(f"{score.label} could not be fitted: {score.error}")
        return lines

    def report_text(self) -> str:
        held = ", ".join(os.path.basename(r.source) for r in self.test)
        split = (f" (fitted on its first two thirds, scored after t = {self.scored_from:g} s)"
                 if self.scored_from is not None else "")
        return (f"{len(self.scores)} laws fitted on {len(self.train)} record(s), scored on "
                f"{held}{split}. {self.recommendation}\n\n" + "\n".join(self.reasons()))

    # -- the figure ----------------------------------------------------------------------
    def figures(self) -> dict[str, Callable[[], Figure]]:
        """``loops``, ``loops-2``, ...: a figure per page of held-out records."""
        from ..plotting import page_name, record_pages

        return {page_name(self.figure_name, k): functools.partial(self.plot, page=k)
                for k in range(1, len(record_pages(self.test)) + 1)}

    def plot(self, page: int = 0) -> Figure:
        """Each held-out record's loop (the measured signal against the model's input):
        measured in black, every fitted law in its colour; every record (``page`` 0) or
        the ``page``-th page of ``PANELS_PER_PAGE`` records (from 1)."""
        from ..plotting import display_values, panel_grid, record_pages

        signal = self.signals[0]
        drive = self.model.input_signal
        shown = list(enumerate(self.test))
        if page:
            shown = record_pages(shown)[page - 1]
        fig, panels = panel_grid(len(shown), width=5.2, height=4.2)
        for (ax,), (j, rec) in zip(panels, shown, strict=True):
            x, x_label = display_values(rec, drive)
            y, y_label = display_values(rec, signal)
            ax.plot(x, y, "k", lw=1.6, label="measured")
            for k, score in enumerate(self.ranking()):
                ax.plot(x, display_values(score.predictions[j], signal)[0], color=f"C{k}",
                        lw=0.9, label=score.label)
            ax.set_xlabel(x_label)
            ax.set_ylabel(y_label)
            ax.set_title(os.path.basename(rec.source), fontsize=9)
            ax.grid(True, alpha=0.3)
        panels[0][0].legend(fontsize=7, loc="upper left")  # "best" scans every sample: slow
        tight_layout(fig)
        return fig


#: the presliding range a rig's start assumes (σ0 = Fs / it): a seal or a guide deflects
#: some tens of micrometres before it slides; the fit moves σ0 from there
PRESLIDING_GUESS = 5e-5


def friction_rig_for(records: Record | Sequence[Record], signal: str = "friction", *,
                     mass: float | None = None):
    """A ``FrictionRig`` driven by the records' measured position, with a starting set
    for a comparison: Fc, Fs, vs and σ2 from the static (inverse) Stribeck fit of the
    first record's ``signal`` ("friction", or "drive_force" = m·a + friction, then with the
    moving mass too unless ``mass`` is given), σ0 = Fs/``PRESLIDING_GUESS``, σ1 damping
    the bristles critically. A start to fit from, not an estimate."""
    import math

    from ..identification import inverse_friction
    from ..models import FrictionRig
    from ..parameters import ParameterSet

    first = fit_records(records)[0]
    with_inertia = signal == "drive_force"
    static = inverse_friction(first, "stribeck", force=signal,
                              mass=with_inertia and mass is None).estimates.as_dict()
    m = mass if mass is not None else static.get("mass", 1.0) if with_inertia else 1.0
    fs = max(abs(static["Fs"]), abs(static["Fc"]))
    sigma0 = fs / PRESLIDING_GUESS
    values = {"m": float(m), "Fc": abs(static["Fc"]), "Fs": fs, "vs": abs(static["vs"]),
              "sigma2": max(static["Fv"], 0.0), "sigma0": sigma0,
              "sigma1": 2.0 * math.sqrt(sigma0 * m), "delta": 2.0}
    params = ParameterSet(values, name="start-from-records",
                          description=f"a start from the static Stribeck fit of "
                                      f"{os.path.basename(first.source)}")
    return FrictionRig(params, drive="position")
