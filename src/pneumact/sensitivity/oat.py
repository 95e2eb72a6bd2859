"""The paper's one-at-a-time study (eq. 15, Figs. 3 and 5): each parameter varied by
given amounts with the others nominal, the runs overlaid, the feature changes ranked."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..io.report import ResultVocabulary
from ..models.actuator import CHAMBER_PRESSURE
from ..options import Executor
from ..plotting import tight_layout

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["PAPER_VARIATIONS", "FrictionCurves", "OneAtATime", "friction_velocity",
           "one_at_a_time"]

#: The amounts of the paper's Fig. 5 a-f (fractions, applied in both directions); vs is
#: varied "around its nominal value": ±50 % here.
PAPER_VARIATIONS = {"sigma0": 0.50, "sigma1": 0.68, "sigma2": 0.90, "Fs": 0.16,
                    "Fc": 0.1536, "vs": 0.50}
#: the signals kept of each run, by the model's ``summary_kind``: an actuator's loops, a
#: cylinder's or a rig's positions (their motion has no pressure to draw against)
LOOP_SIGNALS = {"hysteresis": (CHAMBER_PRESSURE, "position"), "motion": ("position",)}
DEFAULT_FEATURES = ("loop_width_pressure", "loop_width_position", "loop_area",
                    "breakaway_pressure")


@dataclass(eq=False)
class OneAtATime(ResultVocabulary):
    """Runs of the study: ``runs`` (parameter, change, value, features, Δ vs nominal,
    RMS position change), the position and pressure of every run for the loop plots.

    ``to_pandas()``: the runs; ``plot()``: the loops (``plot_loops``); ``write(folder)``:
    runs.csv, loops.png and report.html."""

    report_title = "One-at-a-time sensitivity (paper eq. 15)"
    figure_name = "loops"

    runs: pd.DataFrame
    signals: dict[str, np.ndarray]
    time: np.ndarray
    features: tuple[str, ...]

    def ranking(self, feature: str = "rms_position_change") -> pd.Series:
        """Largest |change| of ``feature`` per parameter, most influential first."""
        column = feature if feature == "rms_position_change" else f"delta_{feature}"
        varied = self.runs[self.runs["parameter"] != "nominal"]
        return varied.groupby("parameter")[column].apply(lambda c: c.abs().max()) \
            .sort_values(ascending=False)

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"runs": self.runs}

    def plot(self, zoom: bool = False) -> Figure:
        """The loops of every run (``plot_loops``)."""
        return self.plot_loops(zoom)

    def plot_loops(self, zoom: bool = False) -> Figure:
        """Applied pressure [kPa] against position [mm], one panel per parameter (Fig. 5; a
        model whose summary is a motion, a cylinder: position over time);
        with ``zoom`` a row per parameter: the whole loop, the break-away (where the
        diaphragm leaves rest), the middle of the stroke (the loop's width in position on
        its own scale) and the low-pressure reversal, where σ0, σ1 and vs act."""
        params = [p for p in dict.fromkeys(self.runs["parameter"]) if p != "nominal"]
        loops = CHAMBER_PRESSURE in self.signals
        if zoom and not loops:
            raise ParameterError("plot_loops: zoom = True zooms into pressure-position loops; "
                                 "this study's model has none (its runs are positions over "
                                 "time): use zoom = False")
        if zoom:
            return self._plot_zoomed(params)
        fig, axes = _panels(len(params))
        for ax, name in zip(axes.ravel(), params, strict=False):
            self._draw(ax, name)
            _label(ax, "pressure [kPa abs]" if loops else "time [s]", "position [mm]")
        return _finish(fig, axes, len(params))

    def _draw(self, ax, name: str, window=None) -> None:
        """The nominal loop and the runs varying ``name`` (kPa, mm); within ``window``
        ((p_lo, p_hi) kPa) the position axis is fitted to the curves."""
        nominal = int(np.flatnonzero(self.runs["parameter"] == "nominal")[0])
        x = self.signals["position"] * 1e3
        # a model without a pressure-position loop (a cylinder): its positions over time
        p = (self.signals[CHAMBER_PRESSURE] * 1e-3 if CHAMBER_PRESSURE in self.signals
             else np.broadcast_to(self.time, x.shape))
        rows = [nominal, *np.flatnonzero(self.runs["parameter"] == name)]
        for i in rows:
            label = "nominal" if i == nominal else \
                f"{name} {self.runs['change_%'].iloc[i]:+.3g} %"
            ax.plot(p[i], x[i], "k-" if i == nominal else "-",
                    lw=1.2 if i == nominal else 0.9, label=label)
        if window is not None:
            inside = (p[rows] >= window[0]) & (p[rows] <= window[1])
            shown = x[rows][inside]
            if shown.size:
                pad = 0.08 * (np.ptp(shown) or 1e-3)
                ax.set_ylim(shown.min() - pad, shown.max() + pad)
            ax.set_xlim(*window)

    def _plot_zoomed(self, params: list[str]):
        from ..core.features import hysteresis_summary

        nominal = int(np.flatnonzero(self.runs["parameter"] == "nominal")[0])
        p, x = self.signals[CHAMBER_PRESSURE][nominal], self.signals["position"][nominal]
        summary = hysteresis_summary(self.time, p, x)
        width = summary["loop_width_pressure"] * 1e-3
        breakaway = summary["breakaway_pressure"] * 1e-3
        turn = float(p.min()) * 1e-3
        middle = float(np.interp(0.5 * x.max(), x[: int(np.argmax(x)) + 1],
                                 p[: int(np.argmax(x)) + 1])) * 1e-3
        windows = {"whole loop": None,
                   "at break-away": (breakaway - 0.8 * width, breakaway + 0.8 * width),
                   "mid-stroke": (middle - 1.5 * width, middle + 1.5 * width),
                   "at the reversal": (turn - 0.1 * width, turn + 1.3 * width)}
        if not np.isfinite(width) or not np.isfinite(breakaway):
            windows = {"whole loop": None}
        return _zoomed_grid(self._draw, params, windows, "pressure [kPa abs]",
                            "position [mm]")


def _zoomed_grid(draw, params: list[str], windows: dict, xlabel: str, ylabel: str):
    """A figure with a row per varied parameter and a column per window (title ->
    x-range, None for all), each panel drawn by ``draw(ax, name, window)``."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(params), len(windows), squeeze=False,
                             figsize=(3.9 * len(windows), 2.9 * len(params)))
    for row, name in zip(axes, params, strict=True):
        for ax, (title, window) in zip(row, windows.items(), strict=True):
            draw(ax, name, window)
            ax.set_title(f"{name}: {title}", fontsize=9)
            ax.grid(True, alpha=0.3)
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel(ylabel, fontsize=8)
            ax.tick_params(labelsize=7)
        row[0].legend(fontsize=7)
    tight_layout(fig)
    return fig


def _panels(n: int):
    """A grid of up to three columns of panels, one per parameter."""
    import matplotlib.pyplot as plt

    cols = min(3, n)
    rows = -(-n // cols)
    return plt.subplots(rows, cols, squeeze=False, figsize=(4.3 * cols, 3.4 * rows))


def _label(ax, xlabel: str, ylabel: str) -> None:
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)


def _finish(fig, axes, n: int):
    """Hide the unused panels, tighten, return the figure."""
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    tight_layout(fig)
    return fig


def one_at_a_time(model, experiment, variations: Mapping[str, object] | None = None, *,
                  features: Sequence[str] = DEFAULT_FEATURES,
                  executor: Executor | int | str | None = None,
                  solver=None) -> OneAtATime:
    """Vary each parameter of ``variations`` (fractions, "N%" strings, or lists of them;
    default ``PAPER_VARIATIONS``, both directions) with the others nominal, on the batch
    engine (``executor``: where it runs); the nominal run comes first. ``features``: the
    paper's loop features by default (an actuator's); a model whose summary is a motion
    (a cylinder) has ``core.features.MOTION_FEATURES`` instead (``travel``, ...)."""
    from ..simulation.batch import simulate_batch
    from ..simulation.simulate import check_model
    from .problem import parse_variation

    check_model(model, "one_at_a_time")
    params = model.params
    variations = PAPER_VARIATIONS if variations is None else variations
    rows: list[dict[str, float]] = [{}]
    labels = [("nominal", 0.0, np.nan)]
    for name, spec in variations.items():
        if name not in params:
            raise ParameterError(f"one_at_a_time: {name!r} is not a parameter of the model's "
                                 "set")
        nominal = params[name]
        amounts = spec if isinstance(spec, (list, tuple)) and not _is_pair(spec) else [spec]
        for amount in amounts:
            low, high = parse_variation(name, amount, nominal)
            for value in dict.fromkeys((low, high)):
                change = 100 * (value - nominal) / nominal if nominal else np.nan
                rows.append({name: value})
                labels.append((name, change, value))
    names = list(dict.fromkeys(n for r in rows for n in r))
    table = pd.DataFrame([{n: r.get(n, params[n]) for n in names} for r in rows])
    if table.empty or not names:
        table = pd.DataFrame({"Fc": [params["Fc"]]})
    batch = simulate_batch(model, experiment, table, features=list(features),
                           signals=list(LOOP_SIGNALS[model.summary_kind]),
                           executor=executor, solver=solver)
    runs = pd.DataFrame(labels, columns=["parameter", "change_%", "value"])
    for feature in features:
        values = batch.table[feature].to_numpy(float)
        runs[feature] = values
        runs[f"delta_{feature}"] = values - values[0]
    x = batch.signals["position"]
    runs["rms_position_change"] = np.sqrt(np.mean((x - x[0]) ** 2, axis=1))
    runs["status"] = batch.table["status"].to_numpy()
    assert batch.time is not None  # a batch's result has its output grid
    return OneAtATime(runs, dict(batch.signals), batch.time, tuple(features))


def _is_pair(spec) -> bool:
    return len(spec) == 2 and all(isinstance(v, (int, float)) for v in spec) and \
        not isinstance(spec, list)


@dataclass(eq=False)
class FrictionCurves(ResultVocabulary):
    """Friction against velocity of a prescribed-velocity run, per parameter variation
    (the paper's Fig. 3): ``curves[parameter]`` is a list of (label, velocity, friction).

    ``to_pandas()``: the curves, long (parameter, variation, velocity, friction);
    ``plot()``: a panel per parameter; ``write(folder)``: curves.csv, the figure and
    report.html."""

    report_title = "Friction against velocity per parameter variation (paper Fig. 3)"
    figure_name = "friction_velocity"

    def tables(self) -> dict[str, pd.DataFrame]:
        frames = [pd.DataFrame({"parameter": name, "variation": label, "velocity": v,
                                "friction": f})
                  for name, entries in self.curves.items() for label, v, f in entries]
        return {"curves": pd.concat(frames, ignore_index=True)}

    curves: dict[str, list[tuple[str, np.ndarray, np.ndarray]]]
    vs: float = float("nan")

    def plot(self, zoom: bool = False) -> Figure:
        """One panel per parameter; with ``zoom`` a row per parameter: the whole curve,
        low speeds (|v| ≤ 4·vs: presliding and the Stribeck drop, where σ0, σ1 and vs
        act) and the fastest 20 % (the sliding level, where Fc, Fs and σ2 act)."""
        params = list(self.curves)
        if zoom:
            return self._plot_zoomed(params)
        fig, axes = _panels(len(params))
        for ax, name in zip(axes.ravel(), params, strict=False):
            self._draw(ax, name)
            _label(ax, "velocity [mm/s]", "friction [N]")
        return _finish(fig, axes, len(params))

    def _draw(self, ax, name: str, window=None) -> None:
        shown = []
        for label, v, f in self.curves[name]:
            ax.plot(v * 1e3, f, lw=1.2 if label == "nominal" else 0.9,
                    color="k" if label == "nominal" else None, label=label)
            if window is not None:
                shown.append(f[(v * 1e3 >= window[0]) & (v * 1e3 <= window[1])])
        if window is not None:
            values = np.concatenate(shown)
            if values.size:
                # at least 10 % of the friction level: curves that coincide stay flat
                # instead of spreading round-off over the panel
                span = max(np.ptp(values), 0.1 * float(np.max(np.abs(values))), 1e-9)
                middle = 0.5 * (values.min() + values.max())
                ax.set_ylim(middle - 0.58 * span, middle + 0.58 * span)
            ax.set_xlim(*window)

    def _plot_zoomed(self, params: list[str]):
        top = max(float(np.max(v)) for entries in self.curves.values()
                  for _, v, _ in entries) * 1e3
        windows: dict[str, tuple[float, float] | None] = {"whole curve": None}
        if np.isfinite(self.vs):
            windows["|v| ≤ 4·vs"] = (-4e3 * self.vs, 4e3 * self.vs)
        windows["fastest 20 %"] = (0.8 * top, top)
        return _zoomed_grid(self._draw, params, windows, "velocity [mm/s]", "friction [N]")


def friction_velocity(params, variations: Mapping[str, object] | None = None, *,
                      friction=None, amplitude: float = 5e-3, period: float = 2.0,
                      cycles: int = 2) -> FrictionCurves:
    """Fig. 3: the friction law driven by a velocity sine of ``amplitude`` [m/s] (the
    last of ``cycles`` periods kept, so the bristles have settled), for the nominal set
    and each parameter at its low and high value (default ``PAPER_VARIATIONS``)."""
    from ..experiments import Experiment, Sine
    from ..models import FrictionRig, LuGre
    from ..simulation import simulate
    from .problem import parse_variation

    friction = LuGre() if friction is None else friction
    rig = FrictionRig(params, friction=friction, drive="velocity")
    t_end = period * cycles
    experiment = Experiment(Sine(amplitude, 1.0 / period), "velocity", t_end,
                            n_points=2001 * cycles)
    nominal = simulate(rig, experiment)
    keep = nominal.time >= t_end - period
    curves = {}
    for name, spec in (PAPER_VARIATIONS if variations is None else variations).items():
        low, high = parse_variation(name, spec, params[name])
        entries = [("nominal", nominal["drive_velocity"][keep], nominal["friction"][keep])]
        for value in (low, high):
            run = simulate(rig, experiment, values={name: value})
            change = 100 * (value - params[name]) / params[name]
            entries.append((f"{name} {change:+.3g} %", run["drive_velocity"][keep],
                            run["friction"][keep]))
        curves[name] = entries
    return FrictionCurves(curves, float(params["vs"]) if "vs" in params else float("nan"))
