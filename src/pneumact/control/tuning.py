"""Controller synthesis on the nonlinear loop, robust to the identified uncertainty.

``tune(loop, specs)`` finds the controller's gains (parameters of its block, varied by
name on the batch engine) that meet ``specs`` on reference moves (``default_moves``):

1. **global**: a scrambled Sobol design of ``n_global`` gain vectors in a log box around
   the loop's gains (×/÷ ``spread``), every one run on every move and on the design
   samples in one batch per move (all cores, or Dask);
2. **local**: Nelder-Mead in log-gain space from the best (the metrics are not smooth:
   settling times jump as the response crosses the band's edge, so a gradient method
   stalls), each evaluation one batch over the design samples;
3. **robust**: with uncertainty samples (an identification's ``Estimates``, or a table
   of parameter values), the design is checked on all of them; while fewer than
   ``specs.fraction`` meet the specs, the worst failing samples join the design set and
   the local search runs again (a scenario design), at most ``rounds`` times.

Each candidate's cost: 10 × the ``fraction``-quantile over samples of the summed spec
violations (each relative to its limit, capped at 4), plus their mean, plus 0.01 × the
normalised IAE (among designs that meet the specs, the faster one). A run that fails
counts as every spec violated to the cap.
"""

from __future__ import annotations

import math
import os
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ..errors import ParameterError, SolverError
from ..io.report import ResultVocabulary
from ..plotting import tight_layout
from ..progress import ProgressCallback, check_progress, notify
from .loop import ClosedLoop
from .metrics import step_metrics
from .specs import Move, Specs, default_moves

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..models.controllers import Controller

__all__ = ["TuningResult", "draw_samples", "evaluate_design", "load_gains", "tune",
           "write_gains"]

#: a violation counts at most this much (a failed run: every spec at this)
CAP = 4.0
#: the weights of the cost: the quantile over samples, the mean, the speed
QUANTILE_WEIGHT, PERFORMANCE_WEIGHT = 10.0, 0.01
#: gains left alone unless asked for: structure, not tuning knobs
NOT_TUNED = ("velocity_ff", "tracking_time", "filter_time", "ff_fc", "ff_fs",
             "dither_amplitude", "dither_frequency", "obs_gain")
#: the design samples the global search and the first local search use
FIRST_DESIGN = 4
#: samples added to the design set per robust round
ADDED_PER_ROUND = 4
GAINS_FORMAT = "pneumact-gains/1"
#: each spec's column in the metrics table (the error's absolute value)
SPEC_METRICS = {"settling": "settling_time", "rise": "rise_time", "overshoot": "overshoot",
                "error": "abs_steady_state_error", "effort": "control_effort",
                "variation": "command_variation", "hunting": "limit_cycle_amplitude"}
#: a parameter drives the failures when the failing samples' mean rank is in this tail
DRIVER_TAIL = 0.25


def draw_samples(estimates, n: int, seed: int = 0, *,
                 base: Mapping[str, float] | None = None) -> pd.DataFrame:
    """``n`` parameter sets from an identification's ``Estimates`` (normal with their
    covariance, truncated to the sets the model accepts: one with Fs < Fc, against the
    other drawn values or ``base``'s, is drawn again), one row each: the uncertainty a
    robust design must hold over."""
    from ..identification.uncertainty import parameter_draws

    return parameter_draws(estimates, n, seed, what="tune: uncertainty samples", base=base)


# --------------------------------------------------------------------------- evaluation
@dataclass(eq=False)
class _Evaluator:
    """Runs candidates (rows of gains) on every move and sample; keeps what it ran."""

    loop: ClosedLoop
    specs: Specs
    moves: tuple[Move, ...]
    names: tuple[str, ...]
    samples: pd.DataFrame  # one row per sample (plant parameters), the nominal first
    biases: np.ndarray  # samples × moves: the holding input at each move's start
    executor: Any
    progress: ProgressCallback | None
    margin: float = 0.0
    budget: int = 1  # candidates the search expects to try (the progress's total)
    runs: int = 0
    history: list[tuple[float, ...]] = field(default_factory=list)

    def metrics(self, gains: np.ndarray, which: np.ndarray) -> list[dict[str, np.ndarray]]:
        """Per move: step_metrics of every (candidate, sample) row, candidate-major, and
        'ok' (the run finished)."""
        from ..simulation.batch import simulate_batch

        n_c, n_s = gains.shape[0], which.size
        out = []
        for m, move in enumerate(self.moves):
            table = pd.DataFrame(np.repeat(gains, n_s, axis=0), columns=list(self.names))
            plant = self.samples.iloc[which].reset_index(drop=True)
            for name in plant.columns:
                table[name] = np.tile(plant[name].to_numpy(), n_c)
            table["bias"] = np.tile(self.biases[which, m], n_c)
            experiment = move.experiment()
            batch = simulate_batch(self.loop, experiment, table, features=(),
                                   signals=["position", "command", "position_setpoint"],
                                   executor=self.executor)
            self.runs += len(table)
            ok = (batch.table["status"] == "ok").to_numpy()
            assert batch.time is not None  # a batch's result has its output grid
            x = np.nan_to_num(batch.signals["position"], nan=move.start)
            u = np.nan_to_num(batch.signals["command"], nan=0.0)
            r = batch.signals["position_setpoint"][int(np.argmax(ok))] if ok.any() else (
                np.full(batch.time.size, move.stop))
            found = step_metrics(batch.time, x, r, u, t_step=move.t_ref, start=move.start,
                                 target=move.stop, tol=move.tolerance(self.specs),
                                 window=move.window())
            found["ok"] = ok
            out.append(found)
        return out

    def violations(self, found: list[dict[str, np.ndarray]], margin: float = 0.0
                   ) -> np.ndarray:
        """Rows × moves × specs: each spec's violation (0: met) of the limits tightened
        by ``margin`` (a fraction), capped."""
        specs = self.specs
        limits = {n: v * (1.0 - margin) for n, v in specs.limits().items()}
        columns = []
        for move, metrics in zip(self.moves, found, strict=True):
            per = []
            for name, limit in limits.items():
                if name == "rise" and move.duration > 0:
                    per.append(np.zeros_like(metrics["iae"]))
                    continue
                value = {"settling": metrics["settling_time"], "rise": metrics["rise_time"],
                         "overshoot": metrics["overshoot"],
                         "error": np.abs(metrics["steady_state_error"]),
                         "effort": metrics.get("control_effort"),
                         "variation": metrics.get("command_variation")}[name]
                scale = limit if limit > 0 else 1.0  # overshoot 0 %: per % over
                per.append(np.where(np.isfinite(value), value / scale - (limit > 0), CAP))
            if specs.no_hunting:
                band = move.tolerance(specs) * (1.0 - margin)
                per.append(metrics["limit_cycle_amplitude"] / band - 1.0)
            v = np.clip(np.stack(per, axis=-1), 0.0, CAP)
            v[~metrics["ok"]] = CAP
            columns.append(v)
        return np.stack(columns, axis=1)

    def spec_names(self) -> list[str]:
        return [*self.specs.limits(), *(["hunting"] if self.specs.no_hunting else [])]

    def performance(self, found: list[dict[str, np.ndarray]]) -> np.ndarray:
        """Rows: the IAE of each move over |step| × its duration, summed over moves."""
        return sum((np.where(m["ok"], m["iae"], np.nan) / (abs(mv.size) * mv.t_end)
                    for mv, m in zip(self.moves, found, strict=True)), start=np.zeros(1))

    def cost_and_gradient(self, gains: np.ndarray, which: np.ndarray
                          ) -> tuple[float, np.ndarray] | None:
        """One candidate's cost over the samples ``which`` and its gradient along the
        gains (SI), from forward sensitivities through the controller (one run per sample
        and move); None where a run fails or a violated metric has no derivative."""
        from ..simulation.forward_sensitivity import simulate_sensitivities
        from .metrics import step_metric_gradients

        values = dict(zip(self.names, map(float, gains), strict=True))
        n_s, n_p = which.size, len(self.names)
        found, slopes = [], []
        for m, move in enumerate(self.moves):
            experiment = move.experiment()
            kw = {"t_step": move.t_ref, "start": move.start, "target": move.stop,
                  "tol": move.tolerance(self.specs), "window": move.window()}
            rows, grads = [], []
            for s in which:
                plant = {k: float(v) for k, v in self.samples.iloc[s].items()}
                try:
                    run = simulate_sensitivities(
                        self.loop, experiment, list(self.names),
                        values={**values, **plant, "bias": float(self.biases[s, m])})
                except SolverError:
                    return None
                self.runs += 1
                r = run.result
                args = (r.time, r["position"], r["position_setpoint"])
                rows.append(step_metrics(*args, **kw))
                grads.append(step_metric_gradients(*args, run["position"], **kw))
            found.append({k: np.concatenate([row[k] for row in rows]) for k in rows[0]}
                         | {"ok": np.ones(n_s, dtype=bool)})
            slopes.append({k: np.stack([g[k] for g in grads]) for k in grads[0]})
        per_sample = np.zeros(n_s)
        gradient = np.zeros((n_s, n_p))
        for move, metrics, slope in zip(self.moves, found, slopes, strict=True):
            for value, d_value, scale, offset in self._terms(move, metrics, slope):
                v = value / scale - offset
                active = (v > 0) & (v < CAP)
                if np.any(~np.isfinite(d_value[active])) or np.any(~np.isfinite(v)):
                    return None
                per_sample += np.clip(v, 0.0, CAP)
                gradient += np.where(active[:, None], d_value / scale, 0.0)
        speed = sum(m["iae"] / (abs(mv.size) * mv.t_end) for mv, m in
                    zip(self.moves, found, strict=True))
        d_speed = sum(g["iae"] / (abs(mv.size) * mv.t_end) for mv, g in
                      zip(self.moves, slopes, strict=True))
        q = int(np.argsort(per_sample, kind="stable")[
            math.ceil(self.specs.fraction * (n_s - 1))])
        cost = (QUANTILE_WEIGHT * per_sample[q] + per_sample.mean()
                + PERFORMANCE_WEIGHT * float(np.mean(speed)))
        grad = (QUANTILE_WEIGHT * gradient[q] + gradient.mean(axis=0)
                + PERFORMANCE_WEIGHT * np.mean(d_speed, axis=0))
        return float(cost), grad

    def _terms(self, move: Move, metrics: dict[str, np.ndarray], slope: dict[str, np.ndarray]):
        """(value, ∂value/∂gains, scale, offset) per spec of one move: violation =
        clip(value/scale − offset, 0, CAP), as ``violations`` with the margin."""
        limits = {n: v * (1.0 - self.margin) for n, v in self.specs.limits().items()}
        keys = {"settling": "settling_time", "rise": "rise_time", "overshoot": "overshoot",
                "error": "steady_state_error"}
        for name, limit in limits.items():
            if name not in keys:
                raise ParameterError(f"tune: polish follows gradients of {', '.join(keys)} "
                                     f"and hunting; not of the {name!r} spec")
            if name == "rise" and move.duration > 0:
                continue
            value, d_value = metrics[keys[name]], slope[keys[name]]
            if name == "error":
                value, d_value = np.abs(value), np.sign(value)[:, None] * d_value
            yield value, d_value, (limit if limit > 0 else 1.0), float(limit > 0)
        if self.specs.no_hunting:
            band = move.tolerance(self.specs) * (1.0 - self.margin)
            yield (metrics["limit_cycle_amplitude"], slope["limit_cycle_amplitude"], band,
                   1.0)

    def cost(self, gains: np.ndarray, which: np.ndarray) -> np.ndarray:
        """The cost of each candidate (rows of gains) over the samples ``which``."""
        found = self.metrics(gains, which)
        per_sample = self.violations(found, self.margin).sum(axis=(1, 2)).reshape(
            gains.shape[0], -1)
        speed = np.nan_to_num(self.performance(found), nan=CAP).reshape(gains.shape[0], -1)
        q = np.quantile(per_sample, self.specs.fraction, axis=1, method="higher")
        costs = (QUANTILE_WEIGHT * q + per_sample.mean(axis=1)
                 + PERFORMANCE_WEIGHT * speed.mean(axis=1))
        for g, c in zip(gains, costs, strict=True):
            self.history.append((*map(float, g), float(c), float(which.size)))
        done = len(self.history)
        notify(self.progress, "tune", done, max(self.budget, done + 1))
        return costs


# --------------------------------------------------------------------------- the result
@dataclass(eq=False)
class TuningResult(ResultVocabulary):
    """A tuned controller and how it does on every move and uncertainty sample.

    ``controller`` / ``loop``: the tuned ones; ``gains``: name -> SI value (``units``);
    ``met``: the share of samples meeting every spec (``specs.fraction`` asked).
    ``to_pandas()``: the gains (SI and datasheet units); ``"metrics"``: every (sample,
    move) run's metrics and violations; ``"spread"``: each metric's nominal, median, 5 %
    / 95 % and worst value per move against its limit; ``"history"``: every candidate
    tried. ``plot()``: each move's responses (nominal, all samples, the worst drawn
    bold). ``write(folder)``: the tables, the figure, report.html and ``gains.toml``
    (``pneumact control step --gains-file``)."""

    inline_figure = False  # plot() simulates every move: not for a display

    report_title = "Controller tuning"
    figure_name = "tuning"

    loop: ClosedLoop
    specs: Specs
    moves: tuple[Move, ...]
    gains: dict[str, float]
    units: dict[str, str]
    metrics_table: pd.DataFrame
    history_table: pd.DataFrame
    samples: pd.DataFrame
    biases: np.ndarray
    met: float
    worst: int
    seconds: float
    runs: int
    start_gains: dict[str, float]

    @property
    def controller(self) -> Controller:
        return self.loop.controller

    @property
    def meets_specs(self) -> bool:
        return bool(self.met >= self.specs.fraction)

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"gains": self.gains_table(), "spread": self.spread_table(),
                "failing": self.failing_table(), "metrics": self.metrics_table,
                "history": self.history_table}

    def failing_table(self) -> pd.DataFrame:
        """The samples that miss a spec: their plant parameters and what they miss, in
        words ("step up: settling 0.311 s > 0.3 s"), the worst first."""
        frame = self.metrics_table
        missed: dict[int, list[str]] = {}
        for row in frame[~frame["meets_specs"]].itertuples(index=False):
            for spec in self._spec_metrics():
                if getattr(row, f"violates_{spec}") > 0:
                    missed.setdefault(int(row.sample), []).append(
                        f"{row.move}: {self._missed(spec, row)}")
        per_sample = frame.groupby("sample")[[c for c in frame if c.startswith(
            "violates_")]].sum().sum(axis=1)
        order = sorted(missed, key=lambda s: -float(per_sample[s]))
        table = self.samples.iloc[order].copy() if len(self.samples.columns) else (
            pd.DataFrame(index=order))
        table.insert(0, "sample", order)
        table["misses"] = ["; ".join(missed[s]) for s in order]
        return table.reset_index(drop=True)

    def _spec_metrics(self) -> dict[str, str]:
        specs = [*self.specs.limits(), *(["hunting"] if self.specs.no_hunting else [])]
        return {spec: SPEC_METRICS[spec] for spec in specs}

    def _missed(self, spec: str, row) -> str:
        if not row.ok:
            return "run failed"
        value = getattr(row, self._spec_metrics()[spec])
        if spec == "hunting":
            return f"hunts ({_shown('hunting', value)} limit cycle)"
        if not math.isfinite(value):
            return f"{spec}: never within the band" if spec in ("settling", "rise") else (
                f"{spec}: not measured")
        limit = self.specs.limits()[spec]
        return f"{spec} {_shown(spec, value)} > {_shown(spec, limit)}"

    def feasibility(self) -> str:
        """One statement of what the design holds: that it meets the specs on the asked
        share of the samples, or, if not, which (move, spec) pairs miss on how many
        samples and what limits these gains do hold on the asked share (the search found
        none better; a search is no proof that none exists)."""
        n, fraction = len(self.samples), self.specs.fraction
        if self.meets_specs:
            return (f"Meets every spec on {100 * self.met:.0f} % of the {n} samples "
                    f"({100 * fraction:.0f} % asked).")
        spec_of = {metric: spec for spec, metric in self._spec_metrics().items()}
        spread = self.spread_table()
        short = spread[spread["share_met"] < 1.0].sort_values("share_met")
        misses = [f"{r.move} {spec_of[r.metric]} on {round((1 - r.share_met) * n)}"
                  for r in short.itertuples()]
        holds = [f"{r.move} {spec_of[r.metric]} ≤ {_shown(spec_of[r.metric], r.at_fraction)}"
                 if math.isfinite(r.at_fraction) else
                 f"{r.move} {spec_of[r.metric]} at no limit (runs never within the band)"
                 for r in short.itertuples() if r.at_fraction > r.limit]
        text = (f"Does NOT meet the specs on {100 * fraction:.0f} % of the {n} samples: "
                f"{100 * self.met:.0f} % meet all of them. Missed: {', '.join(misses)} "
                "samples (failing.csv lists them).")
        if holds:
            text += (f" With these gains, {100 * fraction:.0f} % of the samples hold "
                     f"{', '.join(holds)}: loosen those limits, narrow the uncertainty, or "
                     "ask for a smaller fraction.")
        else:
            text += (f" Each spec alone holds on {100 * fraction:.0f} % of the samples; "
                     "they miss on different ones.")
        drivers = self._drivers()
        if drivers:
            text += f" The failing samples have {', '.join(drivers)}."
        return text

    def _drivers(self) -> list[str]:
        """The uncertain parameters whose failing samples sit in one tail (their mean
        rank among all samples below 25 % or above 75 %)."""
        failing = self.failing_table()["sample"].to_numpy()
        if not failing.size or failing.size == len(self.samples):
            return []
        found = []
        for name in self.samples.columns:
            ranks = self.samples[name].rank(pct=True).to_numpy()[failing]
            mean = float(np.mean(ranks))
            if mean > 1 - DRIVER_TAIL or mean < DRIVER_TAIL:
                found.append(f"{'high' if mean > 0.5 else 'low'} {name} (mean rank "
                             f"{100 * mean:.0f} %)")
        return found

    def gains_table(self) -> pd.DataFrame:
        """Each gain: SI value and unit, the start, and the datasheet form (per mm, kPa or
        %; Ti = Kp/Ki, Td = Kd/Kp)."""
        rows = []
        for name, value in self.gains.items():
            shown, unit = datasheet(name, value, self.units[name])
            rows.append((name, value, self.units[name], self.start_gains.get(name, math.nan),
                         shown, unit))
        kp, ki, kd = (self.gains.get(n) for n in ("kp", "ki", "kd"))
        if kp and ki:
            rows.append(("Ti = Kp/Ki", kp / ki, "s", math.nan, kp / ki, "s"))
        if kp and kd:
            rows.append(("Td = Kd/Kp", kd / kp, "s", math.nan, kd / kp, "s"))
        return pd.DataFrame(rows, columns=["gain", "value", "unit", "start",
                                           "datasheet value", "datasheet unit"])

    def spread_table(self) -> pd.DataFrame:
        """Per move and metric: nominal, median, 5 % and 95 % quantiles, the worst, the
        limit, and the share of samples within it."""
        frame = self.metrics_table
        rows = []
        limits = {**self.specs.limits(), "hunting": 0.0}
        names = SPEC_METRICS
        for move in self.moves:
            runs = frame[frame["move"] == move.label]
            for spec in self.specs.limits() | ({"hunting": 0.0} if self.specs.no_hunting
                                               else {}):
                values = runs[names[spec]].to_numpy(dtype=float)
                finite = values[np.isfinite(values)]
                met = 1.0 - float(np.mean(runs[f"violates_{spec}"] > 0))
                rows.append((move.label, names[spec], float(values[0]),
                             *(np.quantile(finite, [0.5, 0.05, 0.95]) if finite.size
                               else [math.nan] * 3),
                             float(np.max(finite)) if finite.size else math.nan,
                             _at_fraction(values, self.specs.fraction),
                             limits[spec] if spec != "hunting" else move.tolerance(self.specs),
                             met))
        return pd.DataFrame(rows, columns=["move", "metric", "nominal", "median", "q05", "q95",
                                           "worst", "at_fraction", "limit", "share_met"])

    def report_text(self) -> str:
        n = len(self.samples)
        return (f"{self.loop.describe()}: {type(self.controller).__name__} tuned for "
                f"{self.specs.describe()} on {len(self.moves)} moves "
                f"({', '.join(m.label for m in self.moves)}) over {n} plant "
                f"{'sample' if n == 1 else 'samples'} (the nominal first). "
                f"{self.feasibility()} The worst sample is #{self.worst}; {self.runs} "
                f"closed-loop runs in {self.seconds:.1f} s.")

    def plot(self) -> Figure:
        """Each move: the nominal response, every sample's (thin) and the worst (bold)."""
        from ..plotting import panel_grid
        from ..simulation import simulate

        fig, panels = panel_grid(len(self.moves), width=3.6, height=3.4)
        for (ax,), (m, move) in zip(panels, enumerate(self.moves), strict=True):
            experiment = move.experiment()
            for s in _drawn(len(self.samples), self.worst):
                values = {**self.samples.iloc[s].to_dict(), "bias": self.biases[s, m]}
                run = simulate(self.loop, experiment, values=values)
                style = ({"color": "C3", "lw": 1.8, "label": f"worst (#{s})"}
                         if s == self.worst else
                         {"color": "C0", "lw": 1.6, "label": "nominal"} if s == 0 else
                         {"color": "0.6", "lw": 0.6})
                ax.plot(run.time, 1e3 * run["position"], **style)
            ax.plot(run.time, 1e3 * run["position_setpoint"], "k--", lw=0.8, label="set-point")
            ax.set_title(move.label, fontsize=9)
            ax.set_xlabel("time [s]")
            ax.set_ylabel("position [mm]")
            ax.grid(True, alpha=0.3)
        panels[0][0].legend(fontsize=7, loc="lower right")
        tight_layout(fig)
        return fig

    def write(self, out_dir: str | os.PathLike, *, call: str = "") -> list[Path]:
        """The tables, the figure, report.html and gains.toml, all or nothing."""
        import functools

        from ..io.report import figure_png, table_writer
        from ..io.tables import write_files
        from ..plotting import PNG_DPI

        png = figure_png(self.plot(), dpi=PNG_DPI)
        writers: dict[str, Any] = {"gains.toml": self.write_gains}
        writers.update({f"{n}.csv": table_writer(f) for n, f in self.tables().items()})
        writers[f"{self.figure_name}.png"] = functools.partial(_write_bytes, png)
        writers["report.html"] = self.report(call, png).write
        return write_files(out_dir, writers)

    def write_gains(self, path: str | os.PathLike) -> Path:
        """The tuned controller as a TOML file ``load_gains`` and ``pneumact control step
        --gains`` read."""
        return write_gains(self.controller, path, self.units, self.specs.describe())


def _shown(spec: str, value: float) -> str:
    """A metric's value with its unit, as a statement shows it ("never" past any)."""
    if not math.isfinite(value):
        return "never within the band" if spec in ("settling", "rise") else "beyond any"
    if spec in ("settling", "rise"):
        return f"{value:.3g} s"
    if spec == "overshoot":
        return f"{value:.3g} %"
    if spec in ("error", "hunting"):
        return f"{1e6 * value:.3g} µm" if abs(value) < 1e-3 else f"{1e3 * value:.3g} mm"
    return f"{value:.3g}"


def _at_fraction(values: np.ndarray, fraction: float) -> float:
    """The value ``fraction`` of the samples stay within (a failed run: beyond any)."""
    return float(np.quantile(np.where(np.isfinite(values), values, np.inf), fraction,
                             method="higher"))


def _write_bytes(data: bytes, path: Path) -> None:
    path.write_bytes(data)


def _drawn(n: int, worst: int, most: int = 30) -> list[int]:
    """The samples drawn: up to ``most``, the nominal and the worst always."""
    keep = list(range(min(n, most)))
    if worst not in keep:
        keep.append(worst)
    return keep


def datasheet(name: str, value: float, unit: str) -> tuple[float, str]:
    """A gain in the units a controller datasheet uses: per mm of error, kPa for Pa, %
    for a command of 0..1 (SI otherwise)."""
    scale, shown = 1.0, unit
    if unit.endswith("/m") or "/(m*" in unit or unit.endswith("*s/m"):
        scale, shown = 1e-3, unit.replace("/m", "/mm").replace("/(m*", "/(mm*")
    if shown.startswith("Pa"):
        scale, shown = scale * 1e-3, "k" + shown
    elif shown.startswith(("1/", "s/")) and name not in ("kx",):
        scale, shown = scale * 100.0, "%" + shown[1:] if shown.startswith("1/") else (
            "%*" + shown)
    return value * scale, shown


# --------------------------------------------------------------------------- gains files
def write_gains(controller: Controller, path: str | os.PathLike,
                units: Mapping[str, str] | None = None, note: str = "") -> Path:
    """``controller`` as a gains file (TOML: its type and options, the gains in SI with
    their units), written atomically."""
    from ..files import atomic_write
    from ..models.controllers import PID

    lines = [f'format = "{GAINS_FORMAT}"', f'controller = "{type(controller).__name__}"']
    if note:
        lines.append(f'specs = "{note}"')
    options: dict[str, object] = {"anti_windup": controller.anti_windup,
                                  "velocity_estimate": controller.velocity_estimate}
    if isinstance(controller, PID):
        options["derivative"] = controller.derivative
    for limit in ("u_min", "u_max", "sample_time"):
        value = getattr(controller, limit)
        if value is not None and math.isfinite(value):
            options[limit] = float(value)
    lines.append("\n[options]")
    lines += [f"{k} = {_toml(v)}" for k, v in options.items()]
    lines.append("\n[gains]  # SI")
    gains = controller.parameters()
    lines += [f"{k} = {v!r}" for k, v in gains.items()]
    if units:
        lines.append("\n[units]")
        lines += [f'{k} = "{units[k]}"' for k in gains if k in units]
    target = Path(path)
    with atomic_write(target) as staged:
        staged.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return target


def _toml(value: object) -> str:
    return f'"{value}"' if isinstance(value, str) else repr(value)


#: the tables and keys of a gains file
GAINS_FILE_KEYS = ("format", "controller", "specs", "options", "gains", "units")
#: the gains each controller takes when it is made (the others are set afterwards)
_MADE_WITH = {"PID": ("kp", "ki", "kd", "kdp"), "Cascade": ("kx", "kv", "ki")}


def load_gains(path: str | os.PathLike, command_unit: str | None = None) -> Controller:
    """The controller a gains file (``TuningResult.write_gains``) describes. Gains are SI
    unless a ``[units]`` table gives theirs (``kp = "kPa/mm"``), then converted; with
    ``command_unit`` (the plant's input unit: ``ClosedLoop.command_unit``) each given unit
    must measure what the gain does. A file without ``[gains]``, an unknown table, option
    or gain, or a unit that is not one is refused naming it."""
    import dataclasses
    import tomllib

    from ..errors import DataError
    from ..models.controllers import PID, Cascade

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataError(f"gains file {path}: not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise DataError(f"gains file {path}: not TOML ({exc})") from None
    if data.get("format") != GAINS_FORMAT:
        raise DataError(f"gains file {path}: format = {data.get('format')!r}; expected "
                        f"{GAINS_FORMAT!r} (written by pneumact control tune)")
    kinds = {"PID": PID, "Cascade": Cascade}
    name = str(data.get("controller"))
    kind = kinds.get(name)
    if kind is None:
        raise DataError(f"gains file {path}: controller = {data.get('controller')!r}; "
                        f"allowed: {', '.join(kinds)}")
    unknown = [k for k in data if k not in GAINS_FILE_KEYS]
    if unknown and not data.get("gains"):
        raise DataError(f"gains file {path}: no [gains] table ({', '.join(unknown)} stands "
                        "outside one); write the gains under a [gains] line")
    if unknown:
        raise DataError(f"gains file {path}: unknown {', '.join(unknown)}; a gains file has "
                        f"{', '.join(GAINS_FILE_KEYS)}")
    options, gains, units = (data.get(t, {}) for t in ("options", "gains", "units"))
    for table, value in (("options", options), ("gains", gains), ("units", units)):
        if not isinstance(value, dict):
            raise DataError(f"gains file {path}: {table} = {value!r} must be a table "
                            f"([{table}])")
    if not gains:
        raise DataError(f"gains file {path}: no [gains] table: give the gains of the "
                        f"{name} ({', '.join(_MADE_WITH[name])}), SI or with a [units] table")
    made_with = _MADE_WITH[name]
    allowed_options = [f.name for f in dataclasses.fields(kind)
                       if f.init and f.name not in (*made_with, "compensation")]
    bad = [k for k in options if k not in allowed_options]
    if bad:
        raise DataError(f"gains file {path}: [options] {', '.join(bad)} is not an option of "
                        f"a {name}; its options: {', '.join(allowed_options)}")
    # the controller's structure (a PID's filter_time only with a derivative term)
    probe = kind(**options, **{n: 1.0 for n in made_with if n != "kd" or gains.get("kd")})
    known = list(dict.fromkeys([*made_with, *probe.parameters()]))
    bad = [k for k in gains if k not in known]
    if bad:
        raise DataError(f"gains file {path}: [gains] {', '.join(bad)} is not a gain of a "
                        f"{name} (controller = \"{name}\"); its gains: {', '.join(known)}")
    bad = [k for k in units if k not in gains]
    if bad:
        raise DataError(f"gains file {path}: [units] names {', '.join(bad)}, which [gains] "
                        "does not give")
    expected = probe.parameter_units(command_unit) if command_unit is not None else {}
    values = {k: _gain_in_si(path, k, v, units.get(k), expected.get(k))
              for k, v in gains.items()}
    base = kind(**options, **{n: values[n] for n in made_with if n in values})
    rest = {n: v for n, v in values.items() if n in base.parameters()}
    return base.with_parameters(**rest)


def _gain_in_si(path: Path, name: str, value: object, unit: object,
                expected: str | None) -> float:
    """A gain of a gains file in SI: ``value`` in ``unit`` (None: SI already), which must
    have the dimension of ``expected`` when that is known."""
    from ..errors import DataError
    from ..io.quantities import unit_registry

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DataError(f"gains file {path}: [gains] {name} = {value!r}: must be a number")
    if unit is None:
        return float(value)
    import re

    registry = unit_registry()
    # a number in a unit is the drive gain of the controller's command unit ("(N/35.3)/m"
    # for the EMPS drive): gains are in command units, so only the unit's prefixes and
    # units convert ("kPa/mm" -> 1e6 Pa/m)
    plain = re.sub(r"(?<=[/(])\s*\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", "1", str(unit))
    try:
        quantity = float(value) * registry.parse_expression(plain)
    except Exception:
        raise DataError(f"gains file {path}: [units] {name} = \"{unit}\" is not a unit "
                        "(e.g. \"kPa/mm\")") from None
    if expected is not None and quantity.dimensionality != registry.parse_expression(
            expected).dimensionality:
        raise DataError(f"gains file {path}: [units] {name} = \"{unit}\" does not measure "
                        f"{name} (its SI unit is {expected})")
    return float(quantity.to_base_units().magnitude)


# --------------------------------------------------------------------------- tuning
def _tuned_names(loop: ClosedLoop, gains: Sequence[str] | None) -> tuple[str, ...]:
    own = loop.gains
    if gains is None:
        return tuple(n for n in own if n not in NOT_TUNED)
    unknown = [n for n in gains if n not in own]
    if unknown:
        raise ParameterError(f"tune: gains {unknown} are not parameters of "
                             f"{loop.describe()}; its parameters: {', '.join(own)}")
    if not gains:
        raise ParameterError("tune: gains = (); name at least one gain to tune")
    return tuple(gains)


def _start_loop(loop: ClosedLoop, names: Sequence[str]) -> ClosedLoop:
    """The loop with the structure to tune: a PID asked to tune kd keeps a filtered
    derivative on the measurement (``PID(kd=0)`` has none)."""
    import dataclasses

    from ..models.controllers import PID

    controller = loop.controller
    if isinstance(controller, PID) and "kd" in names and controller.derivative == "none":
        kd = 0.002 * controller.kp  # Td = 2 ms
        controller = dataclasses.replace(controller, kd=kd, derivative="measurement")
        loop = dataclasses.replace(loop, controller=controller)
    return loop


def _box(loop: ClosedLoop, names: Sequence[str], bounds: Mapping[str, tuple[float, float]]
         | None, spread: float) -> np.ndarray:
    """names × (low, high), log10 of the gains."""
    own = loop.gains
    rows = []
    for name in names:
        if bounds and name in bounds:
            lo, hi = map(float, bounds[name])
        else:
            start = own[name] if own[name] > 0 else 1.0
            lo, hi = start / spread, start * spread
        if not 0 < lo < hi:
            raise ParameterError(f"tune: bounds[{name!r}] = ({lo:g}, {hi:g}); need "
                                 "0 < low < high")
        rows.append((math.log10(lo), math.log10(hi)))
    return np.array(rows)


def _samples(loop: ClosedLoop, uncertainty, n: int, seed: int) -> pd.DataFrame:
    """The nominal plant (first row) and ``n`` draws of the uncertainty."""
    if uncertainty is None:
        return pd.DataFrame(index=[0])
    if isinstance(uncertainty, pd.DataFrame):
        table = uncertainty.reset_index(drop=True)
        if len(table) == 0:
            raise ParameterError("tune: the uncertainty table has no rows")
    else:
        estimates = getattr(uncertainty, "estimates", uncertainty)
        if not hasattr(estimates, "covariance"):
            raise ParameterError(
                f"tune: uncertainty = {type(uncertainty).__name__}; give an identification "
                "result or its Estimates, or a DataFrame of parameter samples")
        table = draw_samples(estimates, n, seed, base=loop.params.values)
    from ..core.assembly import assemble
    from ..parameters.validation import row_problems

    assemble(loop).check_parameters(list(table.columns), "uncertainty column")
    problems = row_problems(loop.params.values, list(table.columns),
                            table.to_numpy(dtype=float))
    bad = [(i, p) for i, p in enumerate(problems) if p is not None]
    if bad:
        raise ParameterError(
            f"tune: {len(bad)} of {len(table)} uncertainty samples are not valid parameter "
            f"sets (the first, row {bad[0][0]}: {bad[0][1].removeprefix('invalid parameters: ')}"
            "); a robust design holds over plants that can exist: drop or redraw them")
    nominal = {c: float(loop.params[c]) for c in table.columns}
    return pd.concat([pd.DataFrame([nominal]), table], ignore_index=True)


def _holding(loop: ClosedLoop, samples: pd.DataFrame, moves: Sequence[Move]) -> np.ndarray:
    """samples × moves: the controller output that holds each sample at each move's start."""
    biases = np.empty((len(samples), len(moves)))
    for s in range(len(samples)):
        values = {k: float(v) for k, v in samples.iloc[s].items()} or None
        cache: dict[float, float] = {}
        for m, move in enumerate(moves):
            if move.start not in cache:
                cache[move.start] = loop.holding_input(move.start, values=values)
            biases[s, m] = cache[move.start]
    return biases


def tune(loop: ClosedLoop, specs: Specs | str, *, moves: Sequence[Move] | None = None,
         gains: Sequence[str] | None = None,
         bounds: Mapping[str, tuple[float, float]] | None = None, spread: float = 30.0,
         uncertainty=None, samples: int = 50, n_global: int = 64,
         max_evaluations: int = 40, rounds: int = 2, margin: float = 0.05, seed: int = 0,
         polish: int = 0, executor=None,
         progress: ProgressCallback | None = None) -> TuningResult:
    """Gains of ``loop``'s controller that meet ``specs`` on the nonlinear model (see the
    module docstring). ``moves``: the reference moves (default ``default_moves``);
    ``gains``: the names tuned (default every gain but filter, tracking and feed-forward
    ones); ``bounds``: name -> (low, high) (default the loop's value ×/÷ ``spread``);
    ``uncertainty``: an identification result, its ``Estimates`` or a DataFrame of
    plant parameter samples; ``samples``: how many to draw from estimates;
    ``margin``: the search aims at limits this much tighter (a fraction), so that
    samples it did not see meet the real ones; ``polish``: iterations of a gradient
    search (L-BFGS-B along the cost's gradient from forward sensitivities through the
    controller) after each local search, kept only where it lowers the cost (0: none);
    ``executor``: where the batches run (see ``simulate_batch``)."""
    import dataclasses

    from scipy.optimize import minimize
    from scipy.stats import qmc

    from ..checks import check_type

    check_type("loop", loop, ClosedLoop, where="tune", what="a control.ClosedLoop")
    check_progress(progress, "tune")
    specs = Specs.of(specs)
    for name, value, low in (("samples", samples, 1), ("n_global", n_global, 0), ("seed", seed, 0),
                             ("max_evaluations", max_evaluations, 0), ("rounds", rounds, 0),
                             ("polish", polish, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise ParameterError(f"tune: {name} = {value!r}; must be an integer ≥ {low}")
    if not (isinstance(margin, int | float) and 0 <= margin < 1):
        raise ParameterError(f"tune: margin = {margin!r}; must be in [0, 1)")
    if not (isinstance(spread, int | float) and spread > 1):
        raise ParameterError(f"tune: spread = {spread!r}; must be a number > 1")
    if polish and loop.sensitivity_refusal is not None:
        raise ParameterError(f"tune: polish = {polish}; {loop.describe()} carries no forward "
                             f"sensitivities ({loop.sensitivity_refusal}): use polish = 0")
    unsupported = set(specs.limits()) - {"settling", "rise", "overshoot", "error"}
    if polish and unsupported:
        raise ParameterError(f"tune: polish = {polish} follows the gradients of settling, "
                             f"rise, overshoot, error and hunting; not of {sorted(unsupported)}"
                             ": use polish = 0")
    started = _time.perf_counter()
    loop = _start_loop(loop, () if gains is None else tuple(gains))
    names = _tuned_names(loop, gains)
    moves = tuple(default_moves(loop, specs) if moves is None else moves)
    if not moves or not all(isinstance(m, Move) for m in moves):
        raise ParameterError("tune: moves must be a non-empty sequence of Move")
    box = _box(loop, names, bounds, spread)
    table = _samples(loop, uncertainty, samples, seed)
    biases = _holding(loop, table, moves)
    budget = n_global + 1 + max_evaluations + rounds * (max(max_evaluations // 2, 1) + 1)
    evaluator = _Evaluator(loop, specs, moves, names, table, biases, executor, progress,
                           margin, budget)
    start = np.clip(np.log10([max(loop.gains[n], 1e-300) for n in names]), box[:, 0],
                    box[:, 1])

    def gains_of(logs: np.ndarray) -> np.ndarray:
        return 10.0 ** np.clip(np.atleast_2d(logs), box[:, 0], box[:, 1])

    n_all = len(table)
    design = np.arange(min(n_all, 1 + FIRST_DESIGN))
    candidates = np.atleast_2d(start)
    if n_global:
        sobol = qmc.Sobol(len(names), scramble=True, seed=seed).random(n_global)
        candidates = np.vstack([start, box[:, 0] + sobol * (box[:, 1] - box[:, 0])])
    costs = evaluator.cost(gains_of(candidates), design)
    best = candidates[int(np.argmin(costs))]
    for round_ in range(rounds + 1):
        if max_evaluations:
            found = minimize(_scalar_cost, best, args=(evaluator, gains_of, design),
                             method="Nelder-Mead",
                             options={"maxfev": max_evaluations if round_ == 0
                                      else max(max_evaluations // 2, 1),
                                      "xatol": 1e-3, "fatol": 1e-4, "initial_simplex":
                                      _simplex(best, box)})
            best = np.clip(found.x, box[:, 0], box[:, 1])
        if polish:
            best = _polish(evaluator, best, box, design, polish)
        if n_all == 1 or round_ == rounds:
            break
        per_sample = _per_sample(evaluator, gains_of(best), np.arange(n_all))
        if np.mean(per_sample == 0) >= specs.fraction:
            break
        failing = [int(s) for s in np.argsort(-per_sample) if per_sample[s] > 0
                   and s not in design][:ADDED_PER_ROUND]
        if not failing:
            break
        design = np.concatenate([design, failing])
    tuned = dict(zip(names, map(float, gains_of(best)[0]), strict=True))
    controller = loop.controller.with_parameters(**tuned)
    final = dataclasses.replace(loop, controller=controller)
    evaluator.loop = final
    found_all = evaluator.metrics(gains_of(best), np.arange(n_all))
    violations = evaluator.violations(found_all)
    per_sample = violations.sum(axis=(1, 2))
    metrics_table = _metrics_table(moves, found_all, violations, evaluator.spec_names())
    history = pd.DataFrame(evaluator.history, columns=[*names, "cost", "samples"])
    notify(progress, "tune", len(history), len(history))
    return TuningResult(final, specs, moves, final.gains, final.gain_units, metrics_table,
                        history, table, biases, float(np.mean(per_sample == 0)),
                        int(np.argmax(per_sample)) if per_sample.max() > 0 else 0,
                        _time.perf_counter() - started, evaluator.runs,
                        {n: float(v) for n, v in loop.gains.items()})


def _polish(evaluator: _Evaluator, best: np.ndarray, box: np.ndarray, design: np.ndarray,
            iterations: int) -> np.ndarray:
    """L-BFGS-B in log-gain space from ``best`` along the sensitivities' gradient of the
    cost over the design samples, where some of them miss a spec (where all meet them,
    only the speed term is left, and following its gradient trades the slack unseen
    samples need for speed); its end point where the (batch) cost is lower."""
    from scipy.optimize import minimize

    if not np.any(_per_sample(evaluator, 10.0 ** best[None, :], design) > 0):
        return best

    def cost_and_slope(z: np.ndarray) -> tuple[float, np.ndarray]:
        gains = 10.0 ** np.clip(z, box[:, 0], box[:, 1])
        found = evaluator.cost_and_gradient(gains, design)
        if found is None:
            return math.inf, np.zeros_like(z)
        return found[0], found[1] * gains * math.log(10.0)

    result = minimize(cost_and_slope, best, jac=True, method="L-BFGS-B",
                      bounds=list(map(tuple, box)), options={"maxiter": iterations})
    end = np.clip(result.x, box[:, 0], box[:, 1])
    before, after = evaluator.cost(10.0 ** np.vstack([best, end]), design)
    return end if after < before else best


def _scalar_cost(z: np.ndarray, evaluator: _Evaluator, gains_of, design: np.ndarray) -> float:
    return float(evaluator.cost(gains_of(z), design)[0])


def evaluate_design(loop: ClosedLoop, specs: Specs | str, *,
                    moves: Sequence[Move] | None = None, uncertainty=None, samples: int = 50,
                    seed: int = 0, executor=None) -> TuningResult:
    """How ``loop`` as it is meets ``specs`` on the moves and the uncertainty samples
    (the result of a tuning that moves nothing): check a design on samples it was not
    tuned on, or the gains a user already has."""
    return tune(loop, specs, moves=moves, uncertainty=uncertainty, samples=samples,
                n_global=0, max_evaluations=0, rounds=0, margin=0.0, seed=seed,
                executor=executor, spread=1.0 + 1e-9)


def _simplex(best: np.ndarray, box: np.ndarray) -> np.ndarray:
    """A starting simplex of a tenth of the box's width along each gain."""
    d = best.size
    simplex = np.repeat(best[None, :], d + 1, axis=0)
    width = 0.1 * (box[:, 1] - box[:, 0])
    for i in range(d):
        step = width[i] if best[i] + width[i] <= box[i, 1] else -width[i]
        simplex[i + 1, i] += step
    return simplex


def _per_sample(evaluator: _Evaluator, gains: np.ndarray, which: np.ndarray) -> np.ndarray:
    return evaluator.violations(evaluator.metrics(gains, which), evaluator.margin).sum(
        axis=(1, 2))


def _metrics_table(moves, found, violations, spec_names) -> pd.DataFrame:
    frames = []
    for m, (move, metrics) in enumerate(zip(moves, found, strict=True)):
        frame = pd.DataFrame({"sample": np.arange(metrics["iae"].size), "move": move.label,
                              "ok": metrics["ok"]})
        for key in ("rise_time", "settling_time", "overshoot", "steady_state_error",
                    "limit_cycle_amplitude", "iae", "control_effort", "command_variation"):
            frame[key] = metrics[key]
        frame["abs_steady_state_error"] = np.abs(metrics["steady_state_error"])
        for k, spec in enumerate(spec_names):
            frame[f"violates_{spec}"] = violations[:, m, k]
        frame["meets_specs"] = violations[:, m, :].sum(axis=1) == 0
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)
