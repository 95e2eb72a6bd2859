"""Metrics of a closed-loop position run: step response, error integrals, control
effort, limit cycles (hunting) and stick phases.

``loop_metrics(result)`` reads a Result (or a DataFrame with the columns ``time``,
``position``, ``position_setpoint`` and, optionally, ``velocity`` and ``command``) and returns a
frozen ``LoopMetrics`` in SI units. Pure numpy (peaks: ``scipy.signal.find_peaks``).

Definitions (x: position, r: set-point, e = r − x, u: command, v: velocity; samples are
joined by straight lines, so every crossing time below is linearly interpolated):

* the **step** goes from ``start`` (default x(t_step)) to ``target`` (default the last
  set-point value); ``t_step`` defaults to the first sample at which the set-point differs
  from its initial value by more than 1e-9 of its largest magnitude (round-off of the
  kernel's output is not a step), t0 if it never does. That is exact for right-continuous
  records (pneumact's signals, a sampled controller's outputs, a logged r(t_k)); a loop
  without jumps (continuous controller) reports the left value at a breakpoint, so its
  step is found one sample late: pass ``t_step`` to be sample-exact.
  p(t) = (x − start)/(target − start) is the progress, 0 → 1 for a step up and a step
  down alike.
* **rise_time**: first time p reaches 0.9 minus first time p reaches 0.1, both searched
  from t_step on [s]; NaN if p never reaches 0.9.
* **settling_time**: the last time |x − target| > band·|step|, minus t_step [s]; 0 if the
  position never leaves the band after t_step; NaN if it is outside at the end.
* **overshoot**: 100·max(0, max over t ≥ t_step of (x − target)·sign(step))/|step| [%].
  The three step metrics are NaN when the step is zero.
* **steady_state_error**: target − (time average of x over the evaluation window) [m].
* **iae**, **ise**: ∫|e| dt and ∫e² dt over the whole record (trapezoidal rule: a
  set-point jump between two samples counts as a straight line across that interval).
* **control_effort**: ∫(u − u(t0))² dt over the whole record: the effort spent away from
  the initial (holding) command, in (command unit)²·s; NaN without a command signal.
* **command_variation**: Σ|u[k+1] − u[k]|, the total variation of the command.
* **limit_cycle_amplitude**: half the peak-to-peak of x over the evaluation window [m]
  (0 for a still position; a slow creep also gives a non-zero value, it is
  ``hunting`` that says whether it is a limit cycle).
* **limit_cycle_period**: mean interval between successive maxima of x in the window,
  maxima being peaks of prominence ≥ half the window's peak-to-peak [s]; NaN with fewer
  than two maxima, or when the peak-to-peak is below 1e-9 of the position scale
  (round-off, not motion).
* **hunting**: limit_cycle_amplitude > band·|step| and limit_cycle_period finite: the
  position keeps oscillating, over at least one full cycle at the end of the record, by
  more than the settling band.
* **stick phases**: maximal intervals with |v| ≤ stick_speed (default 1e-3·max|v| over
  the record; the velocity is np.gradient(x, t) when the data has none), counted from
  the first arrival in the band (the first time p reaches 1 − band after t_step), or from
  t_step when the position never arrives (or the step is zero). A phase in progress at
  that time or at the end of the record is cut there; phases shorter than ``min_stick``
  (default 1e-3 of the record's duration) are dropped, so a velocity reversal, which
  passes |v| ≤ stick_speed only for an instant, is not a stick. **stick_time** is their
  total duration [s], **stick_count** their number, **mean_stick_duration** their mean
  [s] (NaN if none).
* the **evaluation window** is the last ``window`` seconds of the record. Default: the
  last 10 % of the duration, widened to 2.5 periods when the second half of the record
  after t_step oscillates (so that a slow limit cycle, like the Canudas 1995 hunting with
  its ~24 s period in 100 s, has two maxima in the window), but never beyond that
  second half.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import DataError
from ..io.report import ResultVocabulary
from ..plotting import tight_layout

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

__all__ = ["LoopMetrics", "loop_metrics", "step_metric_gradients", "step_metrics"]

#: default evaluation window: this fraction of the record's duration (at the end)
WINDOW_FRACTION = 0.1
#: ... widened to this many oscillation periods when the position oscillates
WINDOW_PERIODS = 2.5
#: default stick speed: this fraction of the largest |velocity| of the record
STICK_SPEED_FRACTION = 1e-3
#: default shortest stick phase: this fraction of the record's duration
MIN_STICK_FRACTION = 1e-3
#: maxima of a limit cycle have a prominence of at least this fraction of the peak-to-peak
PEAK_PROMINENCE = 0.5
#: a peak-to-peak below this fraction of the position scale is round-off, not a cycle
ROUND_OFF = 1e-9
#: the rise-time levels, fractions of the step
RISE_LEVELS = (0.1, 0.9)

_REQUIRED = ("position", "position_setpoint")

# name: (unit, description); "{x}" is the position's unit, "{u}" the command's
_DESCRIPTIONS: dict[str, tuple[str, str]] = {
    "rise_time": ("s", "10 % to 90 % of the step"),
    "settling_time": ("s", "from t_step to the last time outside ±band·|step| of the target"),
    "overshoot": ("%", "largest excursion beyond the target, % of the step"),
    "steady_state_error": ("{x}", "target − mean position over the evaluation window"),
    "iae": ("{x}*s", "∫|set-point − position| dt"),
    "ise": ("{x}^2*s", "∫(set-point − position)² dt"),
    "control_effort": ("{u}^2*s", "∫(command − initial command)² dt"),
    "command_variation": ("{u}", "total variation of the command, Σ|Δu|"),
    "limit_cycle_amplitude": ("{x}", "half the peak-to-peak of position in the window"),
    "limit_cycle_period": ("s", "mean interval between maxima of position in the window"),
    "hunting": ("", "limit cycle larger than the settling band"),
    "stick_time": ("s", "time with |v| ≤ stick_speed after the first arrival in the band"),
    "stick_count": ("", "number of stick phases after the first arrival in the band"),
    "mean_stick_duration": ("s", "stick_time / stick_count"),
    "t_step": ("s", "time of the step"),
    "start": ("{x}", "position the step starts from"),
    "target": ("{x}", "position the step goes to"),
    "band": ("", "settling band, fraction of |step|"),
    "stick_speed": ("{x}/s", "speed below which the plant sticks"),
    "window": ("s", "evaluation window at the end of the record"),
    "min_stick": ("s", "shortest stick phase counted"),
}


#: the settings the metrics were measured with (rows of ``LoopMetrics.to_pandas`` after
#: the metrics)
_SETTINGS = ("t_step", "start", "target", "band", "stick_speed", "window", "min_stick")


@dataclass(frozen=True)
class LoopMetrics(ResultVocabulary):
    """Metrics of one closed-loop run, SI (see the module docstring for the
    definitions), with the settings they were measured with (``t_step`` ...
    ``min_stick``). ``position_unit`` and ``command_unit`` name the signals' units.

    ``to_pandas()``: metric, value, unit, description; ``plot()``: the metrics that are
    numbers, a panel per unit; ``write(folder)``: metrics.csv, the figure and
    report.html."""

    report_title = "Closed-loop metrics"
    figure_name = "metrics"

    rise_time: float
    settling_time: float
    overshoot: float
    steady_state_error: float
    iae: float
    ise: float
    control_effort: float
    command_variation: float
    limit_cycle_amplitude: float
    limit_cycle_period: float
    hunting: bool
    stick_time: float
    stick_count: int
    mean_stick_duration: float
    t_step: float
    start: float
    target: float
    band: float
    stick_speed: float
    window: float
    min_stick: float
    position_unit: str = "m"
    command_unit: str = ""

    @property
    def step(self) -> float:
        """target − start."""
        return self.target - self.start

    @property
    def band_width(self) -> float:
        """Half-width of the settling band, band·|step| (position unit)."""
        return self.band * abs(self.step)

    def as_dict(self) -> dict[str, Any]:
        """Metric and setting name -> value (float, or bool/int for hunting/stick_count)."""
        return {name: getattr(self, name) for name in _DESCRIPTIONS}

    def units(self) -> dict[str, str]:
        """Metric and setting name -> unit."""
        x, u = self.position_unit, self.command_unit
        out = {}
        for name, (unit, _) in _DESCRIPTIONS.items():
            if "{u}" in unit and u == "":  # a command of unknown unit
                unit = ""
            elif "{u}" in unit and u == "1":  # dimensionless: (1)²·s is s
                unit = unit.replace("{u}^2*", "").replace("{u}", "1")
            out[name] = unit.replace("{x}", x).replace("{u}", u)
        return out

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"metrics": self.to_pandas()}

    def report_text(self) -> str:
        return self.summary()

    def plot(self) -> Figure:
        """The metrics with a finite value (not the settings), as bars, a panel per
        unit (s, the position's unit, ...)."""
        import matplotlib.pyplot as plt

        frame = self.to_pandas()
        metrics = frame[~frame["metric"].isin(_SETTINGS)]
        values = metrics["value"].map(lambda v: float(v) if not isinstance(v, bool) else
                                      math.nan)
        shown = metrics.assign(value=values)[np.isfinite(values)]
        groups = list(shown.groupby("unit", sort=False))
        fig, axes = plt.subplots(1, max(1, len(groups)), squeeze=False,
                                 figsize=(3.4 * max(1, len(groups)), 3.6))
        for ax, (unit, rows) in zip(axes[0], groups, strict=False):
            ax.barh(rows["metric"], rows["value"], color="C0")
            ax.set_xlabel(f"[{unit}]" if unit else "[1]")
            ax.invert_yaxis()
            ax.grid(True, axis="x", alpha=0.3)
        fig.suptitle(self.summary(), fontsize=8)
        tight_layout(fig)
        return fig

    def to_pandas(self, name: str | None = None):
        """A DataFrame with the columns metric, value, unit, description (one row per
        metric, then the settings)."""
        import pandas as pd

        if name not in (None, "metrics"):
            raise DataError(f"to_pandas: name = {name!r}; allowed: metrics")

        units = self.units()
        rows = [(name, value, units[name], _DESCRIPTIONS[name][1])
                for name, value in self.as_dict().items()]
        frame = pd.DataFrame(rows, columns=["metric", "value", "unit", "description"])
        frame["value"] = pd.Series([row[1] for row in rows], dtype=object)
        return frame

    def summary(self) -> str:
        """One line of the key metrics, for a title."""
        def g(value: float, unit: str, scale: float = 1.0) -> str:
            return "n/a" if not math.isfinite(value) else f"{value * scale:.3g} {unit}"

        x_scale, x_unit = (1e3, "mm") if self.position_unit == "m" else (1.0, self.position_unit)
        parts = [f"rise {g(self.rise_time, 's')}", f"settling {g(self.settling_time, 's')}",
                 f"overshoot {g(self.overshoot, '%')}",
                 f"e_ss {g(self.steady_state_error, x_unit, x_scale)}"]
        if self.hunting:
            parts.append(f"hunting ±{g(self.limit_cycle_amplitude, x_unit, x_scale)}, "
                         f"period {g(self.limit_cycle_period, 's')}")
        if self.stick_count:
            parts.append(f"{self.stick_count} sticks, {g(self.stick_time, 's')}")
        return ", ".join(parts)


# --------------------------------------------------------------------------- reading


def _read(result: Any) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, str]]:
    """(time, signals, units) of a Result or DataFrame; DataError if not usable."""
    try:
        import pandas as pd
    except ImportError:  # pragma: no cover - pandas is a dependency
        pd = None
    if pd is not None and isinstance(result, pd.DataFrame):
        columns = {str(c): c for c in result.columns}
        if "time" in columns:
            time = result[columns["time"]].to_numpy()
        elif result.index.name == "time":
            time = result.index.to_numpy()
        else:
            raise DataError("loop_metrics: the DataFrame has no column 'time' (nor an index "
                            f"named 'time'); columns: {', '.join(columns) or '(none)'}")
        signals = {name: result[c].to_numpy() for name, c in columns.items() if name != "time"}
        units = dict(result.attrs.get("units") or {})
    elif hasattr(result, "time") and isinstance(getattr(result, "signals", None), dict):
        time, signals = result.time, dict(result.signals)
        units = dict(getattr(result, "units", None) or {})
    else:
        raise DataError(f"loop_metrics: result = {type(result).__name__}; allowed: a pneumact "
                        "Result or a pandas DataFrame with columns time, position, "
                        "position_setpoint")
    missing = [name for name in _REQUIRED if name not in signals]
    if missing:
        raise DataError(f"loop_metrics: the data has no {' and no '.join(map(repr, missing))} "
                        f"signal; needed: {', '.join(_REQUIRED)}; available: "
                        f"{', '.join(signals) or '(none)'}")
    time = _floats("time", time)
    if time.size < 2:
        raise DataError(f"loop_metrics: time has {time.size} sample(s); need at least 2")
    if not np.all(np.diff(time) > 0):
        k = int(np.argmin(np.diff(time)))
        raise DataError(f"loop_metrics: time must increase strictly; time[{k + 1}] = "
                        f"{float(time[k + 1])!r} s after time[{k}] = {float(time[k])!r} s")
    out: dict[str, np.ndarray] = {}
    for name in ("position", "position_setpoint", "velocity", "command"):
        if name in signals:
            out[name] = _floats(name, signals[name])
            if out[name].shape != time.shape:
                raise DataError(f"loop_metrics: {name} has {out[name].size} samples, time "
                                f"{time.size}; they must match")
    return time, out, units


def _floats(name: str, values: Any) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise DataError(f"loop_metrics: {name} is not numeric; allowed: finite numbers") from None
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise DataError(f"loop_metrics: {name}[{bad[0]}] = {float(array[bad[0]])!r}; allowed: "
                        f"finite numbers ({bad.size} non-finite sample(s))")
    return array


def _option(name: str, value: Any, unit: str, *, low: float | None = None,
            high: float | None = None, low_open: bool = True, allowed: str = "") -> float:
    """A finite float in (low, high], or a DataError naming it."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    ok = math.isfinite(number)
    if ok and low is not None:
        ok = number > low if low_open else number >= low
    if ok and high is not None:
        ok = number <= high
    if not ok:
        raise DataError(f"loop_metrics: {name} = {value!r}{' ' + unit if unit else ''}; "
                        f"allowed: {allowed or 'a finite number'}")
    return number


# --------------------------------------------------------------------------- helpers


def _integral(t: np.ndarray, y: np.ndarray) -> float:
    return float(np.trapezoid(y, t)) if t.size > 1 else 0.0


def _from(t: np.ndarray, y: np.ndarray, t_from: float) -> tuple[np.ndarray, np.ndarray]:
    """The samples at and after ``t_from``, starting with the interpolated y(t_from)."""
    keep = t > t_from
    return (np.concatenate([[t_from], t[keep]]),
            np.concatenate([[np.interp(t_from, t, y)], y[keep]]))


def _first_reach(t: np.ndarray, p: np.ndarray, level: float) -> float:
    """First time p reaches ``level`` (from below), interpolated; NaN if never."""
    hits = np.flatnonzero(p >= level)
    if hits.size == 0:
        return math.nan
    k = int(hits[0])
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (level - p[k - 1]) / (p[k] - p[k - 1]) * (t[k] - t[k - 1]))


def _rise_times(t: np.ndarray, x: np.ndarray, t_step: float, start: float,
                target: float) -> tuple[float, float]:
    """(time at 10 %, time at 90 % of the step), absolute; NaN where not reached."""
    step = target - start
    if step == 0:
        return math.nan, math.nan
    ts, xs = _from(t, x, t_step)
    p = (xs - start) / step
    return _first_reach(ts, p, RISE_LEVELS[0]), _first_reach(ts, p, RISE_LEVELS[1])


def _settling(ts: np.ndarray, xs: np.ndarray, target: float, tol: float) -> float:
    """Last time |x − target| > tol (absolute); ts[0] if never; NaN if outside at the end."""
    outside = np.abs(xs - target) > tol
    if outside[-1]:
        return math.nan
    if not outside.any():
        return float(ts[0])
    k = int(np.flatnonzero(outside)[-1])
    edge = target + math.copysign(tol, xs[k] - target)
    return float(ts[k] + (edge - xs[k]) / (xs[k + 1] - xs[k]) * (ts[k + 1] - ts[k]))


def _period(t: np.ndarray, x: np.ndarray, floor: float) -> float:
    """Mean interval between successive prominent maxima of x; NaN if fewer than two."""
    from scipy.signal import find_peaks

    ptp = float(np.ptp(x)) if x.size else 0.0
    if x.size < 3 or ptp <= floor:
        return math.nan
    peaks, _ = find_peaks(x, prominence=PEAK_PROMINENCE * ptp)
    if peaks.size < 2:
        return math.nan
    return float((t[peaks[-1]] - t[peaks[0]]) / (peaks.size - 1))


def _stick_phases(t: np.ndarray, speed: np.ndarray, threshold: float) -> list[tuple[float, float]]:
    """(begin, end) of each maximal run of samples with speed ≤ threshold, the ends
    interpolated where the speed crosses the threshold."""
    stuck = speed <= threshold
    if not stuck.any():
        return []
    change = np.flatnonzero(np.diff(stuck.astype(np.int8)))
    begins = list(change[~stuck[change]] + 1)  # first stuck sample of a run
    ends = list(change[stuck[change]])  # last stuck sample of a run
    if stuck[0]:
        begins.insert(0, 0)
    if stuck[-1]:
        ends.append(t.size - 1)

    def crossing(i: int, j: int) -> float:  # between samples i and j, one on each side
        a, b = speed[i], speed[j]
        return float(t[i] + (threshold - a) / (b - a) * (t[j] - t[i])) if a != b else float(t[i])

    phases = []
    for i, j in zip(begins, ends, strict=True):
        begin = float(t[0]) if i == 0 else crossing(i - 1, i)
        end = float(t[-1]) if j == t.size - 1 else crossing(j, j + 1)
        phases.append((begin, end))
    return phases


# --------------------------------------------------------------------------- metrics


def loop_metrics(result: Any, *, start: float | None = None, target: float | None = None,
                 t_step: float | None = None, band: float = 0.02,
                 stick_speed: float | None = None, window: float | None = None,
                 min_stick: float | None = None) -> LoopMetrics:
    """Step-response, error, effort, limit-cycle and stick metrics of a closed-loop run.

    ``result``: a pneumact Result, or a DataFrame with the columns (or index) ``time``
    [s], ``position`` [m], ``position_setpoint`` [m] and optionally ``velocity`` [m/s] and
    ``command``. ``start``/``target`` [m]: the step (default: the position at
    ``t_step`` / the last set-point value); ``t_step`` [s]: default the first sample
    at which the set-point departs from its first value (else the first time); ``band``:
    settling band as a fraction of |step| (0 < band ≤ 1); ``stick_speed`` [m/s]: default
    1e-3·max|v|; ``window`` [s]: evaluation window at the end of the record (default
    10 % of the duration, widened to 2.5 periods of an oscillation); ``min_stick`` [s]:
    shortest stick phase counted (default 1e-3 of the duration). The definitions are in
    this module's docstring. A record that never reaches the target gives NaN rise and
    settling times, not an error.
    """
    time, sig, units = _read(result)
    x, r = sig["position"], sig["position_setpoint"]
    t0, t_end = float(time[0]), float(time[-1])
    duration = t_end - t0

    # -- the step
    if t_step is None:
        changed = np.flatnonzero(np.abs(r - r[0]) > ROUND_OFF * float(np.max(np.abs(r))))
        t_step = float(time[changed[0]]) if changed.size else t0
    else:
        t_step = _option("t_step", t_step, "s", low=t0, high=t_end, low_open=False,
                         allowed=f"a time in [{t0:g}, {t_end:g}) s, within the record")
        if t_step == t_end:
            raise DataError(f"loop_metrics: t_step = {t_step!r} s; allowed: a time in "
                            f"[{t0:g}, {t_end:g}) s, within the record")
    start = (float(np.interp(t_step, time, x)) if start is None
             else _option("start", start, "m"))
    target = float(r[-1]) if target is None else _option("target", target, "m")
    band = _option("band", band, "", low=0.0, high=1.0,
                   allowed="a fraction of the step, 0 < band ≤ 1")
    step = target - start
    tol = band * abs(step)

    # -- step response
    ts, xs = _from(time, x, t_step)
    if step != 0:
        t10, t90 = _rise_times(time, x, t_step, start, target)
        rise_time = t90 - t10
        settling_time = _settling(ts, xs, target, tol) - t_step
        beyond = float(np.max((xs - target) * math.copysign(1.0, step)))
        overshoot = 100.0 * max(0.0, beyond) / abs(step)
        arrival = _first_reach(ts, (xs - start) / step, 1.0 - band)
    else:
        rise_time = settling_time = overshoot = arrival = math.nan

    # -- error integrals and control effort
    e = r - x
    iae, ise = _integral(time, np.abs(e)), _integral(time, e * e)
    u = sig.get("command")
    if u is not None:
        control_effort = _integral(time, (u - u[0]) ** 2)
        command_variation = float(np.sum(np.abs(np.diff(u))))
    else:
        control_effort = command_variation = math.nan

    # -- evaluation window, steady state and limit cycle
    floor = ROUND_OFF * max(float(np.max(np.abs(x))), abs(step))
    if window is None:
        window = WINDOW_FRACTION * duration
        t_mid = t_step + 0.5 * (t_end - t_step)
        tail_t, tail_x = _from(time, x, t_mid)
        tail_period = _period(tail_t, tail_x, floor)
        if math.isfinite(tail_period):
            window = max(window, min(WINDOW_PERIODS * tail_period, t_end - t_mid))
    else:
        window = _option("window", window, "s", low=0.0, high=duration,
                         allowed=f"a duration in (0, {duration:g}] s, the record's length")
    wt, wx = _from(time, x, t_end - window)
    steady_state_error = target - _integral(wt, wx) / (wt[-1] - wt[0])
    amplitude = 0.5 * float(np.ptp(wx))
    period = _period(wt, wx, floor)
    hunting = bool(amplitude > tol and math.isfinite(period))

    # -- stick phases
    v = sig.get("velocity")
    if v is None:
        v = np.gradient(x, time)
    speed = np.abs(v)
    if stick_speed is None:
        stick_speed = STICK_SPEED_FRACTION * float(np.max(speed))
    else:
        stick_speed = _option("stick_speed", stick_speed, "m/s", low=0.0, low_open=False,
                              allowed="a speed ≥ 0")
    if min_stick is None:
        min_stick = MIN_STICK_FRACTION * duration
    else:
        min_stick = _option("min_stick", min_stick, "s", low=0.0, low_open=False,
                            allowed="a duration ≥ 0")
    t_count = arrival if math.isfinite(arrival) else t_step
    durations = []
    for begin, end in _stick_phases(time, speed, stick_speed):
        begin = max(begin, t_count)
        if end > begin and end - begin >= min_stick:
            durations.append(end - begin)
    stick_time = float(np.sum(durations)) if durations else 0.0
    stick_count = len(durations)
    mean_stick = stick_time / stick_count if stick_count else math.nan

    return LoopMetrics(
        rise_time=float(rise_time), settling_time=float(settling_time),
        overshoot=float(overshoot), steady_state_error=float(steady_state_error),
        iae=iae, ise=ise, control_effort=float(control_effort),
        command_variation=float(command_variation), limit_cycle_amplitude=amplitude,
        limit_cycle_period=period, hunting=hunting, stick_time=stick_time,
        stick_count=stick_count, mean_stick_duration=float(mean_stick), t_step=float(t_step),
        start=float(start), target=float(target), band=float(band),
        stick_speed=float(stick_speed), window=float(window), min_stick=float(min_stick),
        position_unit=str(units.get("position", "m")) or "m",
        command_unit=str(units.get("command", "")) if u is not None else "")


def _rows_from(t: np.ndarray, y: np.ndarray, t_from: float) -> tuple[np.ndarray, np.ndarray]:
    """``_from`` for every row of ``y`` (columns on the shared times ``t``)."""
    i = int(np.clip(np.searchsorted(t, t_from, side="right") - 1, 0, t.size - 2))
    w = (t_from - t[i]) / (t[i + 1] - t[i])
    first = y[:, i] * (1.0 - w) + y[:, i + 1] * w
    keep = t > t_from
    return (np.concatenate([[t_from], t[keep]]),
            np.concatenate([first[:, None], y[:, keep]], axis=1))


def _rows_first_reach(t: np.ndarray, p: np.ndarray, level: float) -> np.ndarray:
    hits = p >= level
    k = np.argmax(hits, axis=1)
    rows = np.arange(p.shape[0])
    before = np.maximum(k - 1, 0)
    p0, p1 = p[rows, before], p[rows, k]
    with np.errstate(invalid="ignore", divide="ignore"):
        at = t[before] + (level - p0) / (p1 - p0) * (t[k] - t[before])
    at = np.where(k == 0, t[0], at)
    return np.where(hits.any(axis=1), at, math.nan)


def _rows_settling(ts: np.ndarray, xs: np.ndarray, target: float, tol: float) -> np.ndarray:
    outside = np.abs(xs - target) > tol
    n = xs.shape[1]
    k = n - 1 - np.argmax(outside[:, ::-1], axis=1)  # the last sample outside
    rows = np.arange(xs.shape[0])
    after = np.minimum(k + 1, n - 1)
    x0, x1 = xs[rows, k], xs[rows, after]
    edge = target + np.copysign(tol, x0 - target)
    with np.errstate(invalid="ignore", divide="ignore"):
        at = ts[k] + (edge - x0) / (x1 - x0) * (ts[after] - ts[k])
    at = np.where(outside.any(axis=1), at, ts[0])
    return np.where(outside[:, -1], math.nan, at)


def step_metrics(time: Any, position: Any, setpoint: Any, command: Any = None, *,
                 t_step: float, start: float, target: float, tol: float,
                 window: float) -> dict[str, np.ndarray]:
    """``loop_metrics``' step, error, effort and limit-cycle metrics of many runs at once:
    rows of ``position`` (and ``command``) on the shared ``time``, one ``setpoint``, the
    step (``t_step``, ``start``, ``target``), the settling band ``tol`` [m] (absolute)
    and the evaluation ``window`` [s] given. What a tuner measures thousands of times;
    the definitions are ``loop_metrics``' (a test holds the two together)."""
    t = np.asarray(time, dtype=float)
    x = np.atleast_2d(np.asarray(position, dtype=float))
    r = np.asarray(setpoint, dtype=float)
    step = target - start
    ts, xs = _rows_from(t, x, t_step)
    p = (xs - start) / step
    rise = _rows_first_reach(ts, p, RISE_LEVELS[1]) - _rows_first_reach(ts, p, RISE_LEVELS[0])
    beyond = np.max((xs - target) * math.copysign(1.0, step), axis=1)
    wt, wx = _rows_from(t, x, t[-1] - window)
    result = {
        "rise_time": rise,
        "settling_time": _rows_settling(ts, xs, target, tol) - t_step,
        "overshoot": 100.0 * np.maximum(beyond, 0.0) / abs(step),
        "steady_state_error": target - np.trapezoid(wx, wt, axis=1) / (wt[-1] - wt[0]),
        "limit_cycle_amplitude": 0.5 * np.ptp(wx, axis=1),
        "iae": np.trapezoid(np.abs(r[None, :] - x), t, axis=1),
    }
    if command is not None:
        u = np.atleast_2d(np.asarray(command, dtype=float))
        result["control_effort"] = np.trapezoid((u - u[:, :1]) ** 2, t, axis=1)
        result["command_variation"] = np.sum(np.abs(np.diff(u, axis=1)), axis=1)
    return result


def step_metric_gradients(time: Any, position: Any, setpoint: Any, sensitivity: Any, *,
                          t_step: float, start: float, target: float, tol: float,
                          window: float) -> dict[str, np.ndarray]:
    """The derivatives of one run's ``step_metrics`` (rise and settling time, overshoot,
    steady-state error, limit-cycle amplitude, IAE) along parameters, from the position's
    sensitivity (n_time × P, ``simulate_sensitivities``): the exact derivative of the
    discrete definitions where they are differentiable (a settling time moves with the
    crossing it interpolates; an overshoot with its peak sample), NaN where the metric
    is (never settles). What a gradient step of the tuner follows; checked against
    central differences of whole runs."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    s = np.asarray(sensitivity, dtype=float).T  # P × n_time
    n_par = s.shape[0]
    step = target - start
    ts, xs = _rows_from(t, x[None, :], t_step)
    _, ss = _rows_from(t, s, t_step)
    xs = xs[0]
    sign = math.copysign(1.0, step)
    beyond = (xs - target) * sign
    peak = int(np.argmax(beyond))
    wt, wx = _rows_from(t, x[None, :], t[-1] - window)
    _, ws = _rows_from(t, s, t[-1] - window)
    wx = wx[0]
    return {
        "rise_time": (_crossing_gradient(ts, (xs - start) / step, ss / step,
                                         RISE_LEVELS[1])
                      - _crossing_gradient(ts, (xs - start) / step, ss / step,
                                           RISE_LEVELS[0])),
        "settling_time": _settling_gradient(ts, xs, ss, target, tol),
        "overshoot": (100.0 * sign * ss[:, peak] / abs(step) if beyond[peak] > 0
                      else np.zeros(n_par)),
        "steady_state_error": -np.trapezoid(ws, wt, axis=1) / (wt[-1] - wt[0]),
        "limit_cycle_amplitude": 0.5 * (ws[:, int(np.argmax(wx))] - ws[:, int(np.argmin(wx))]),
        "iae": np.trapezoid(np.sign(x - np.asarray(setpoint, dtype=float))[None, :] * s, t,
                            axis=1),
    }


def _interpolated_gradient(dt: float, edge: float, x0: float, x1: float, s0: np.ndarray,
                           s1: np.ndarray) -> np.ndarray:
    """∂/∂θ of t0 + (edge − x0)/(x1 − x0)·dt, the time a line between samples reaches edge."""
    return dt * (-s0 * (x1 - x0) - (edge - x0) * (s1 - s0)) / (x1 - x0) ** 2


def _crossing_gradient(t: np.ndarray, p: np.ndarray, sp: np.ndarray, level: float
                       ) -> np.ndarray:
    """∂/∂θ of ``_rows_first_reach`` for one row ``p`` with sensitivity rows ``sp``."""
    hits = np.flatnonzero(p >= level)
    if not hits.size:
        return np.full(sp.shape[0], math.nan)
    k = int(hits[0])
    if k == 0:
        return np.zeros(sp.shape[0])
    return _interpolated_gradient(t[k] - t[k - 1], level, p[k - 1], p[k], sp[:, k - 1],
                                  sp[:, k])


def _settling_gradient(ts: np.ndarray, xs: np.ndarray, ss: np.ndarray, target: float,
                       tol: float) -> np.ndarray:
    """∂/∂θ of ``_rows_settling`` for one row."""
    outside = np.flatnonzero(np.abs(xs - target) > tol)
    if not outside.size:
        return np.zeros(ss.shape[0])
    k = int(outside[-1])
    if k == xs.size - 1:
        return np.full(ss.shape[0], math.nan)
    edge = target + math.copysign(tol, xs[k] - target)
    return _interpolated_gradient(ts[k + 1] - ts[k], edge, xs[k], xs[k + 1], ss[:, k],
                                  ss[:, k + 1])
