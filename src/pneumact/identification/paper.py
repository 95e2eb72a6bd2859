"""The paper's staged identification (section III.2, eqs. 9-13), in one call.

(a) spring: F0 and k (and the friction level) from the two branches of a quasi-static
    sweep, by linear least squares of (p_atm − p)·A_d = F0 + k·x + F·sgn(v);
(b) Fc and σ2 by linear least squares of eq. 13 over steady sliding at |v| ≥
    ``sliding_speed`` (≫ vs), with an offset and a slope in x that absorb the errors of
    stage (a) (0.1 % of k is 0.13 N at 10 mm, as much as σ2·v at 30 mm/s);
(c) Fs and vs (optionally δ) by nonlinear least squares of eq. 12 over the slower steady
    segments, within Fs ≥ Fc; the uncertainty of the stage-(b) values it holds is
    propagated into its standard errors (delta method);
(d) σ0 and σ1 by output-error least squares on the presliding records, with the model
    in the loop (forward-sensitivity Jacobian), after the approach to the stop.

Each stage reports estimates with standard errors conditional on the earlier stages
(their errors are not propagated), and its data with the fitted curve for a residual
plot. The result is a parameter set with per-value provenance that ``load_params``
reads back.
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from ..errors import DataError
from ..io.records import Record
from .bench import drive_force, kinematics, steady_segments
from .estimates import Estimates, covariance_from_jacobian, linear_least_squares

__all__ = ["PaperIdentification", "StageResult", "identify_paper", "record_kind",
           "with_estimates"]

STAGES = {
    "spring": "(a) spring: F0, k from the quasi-static sweep",
    "sliding": "(b) sliding friction: Fc, σ2 by eq. 13 (|v| ≫ vs)",
    "stribeck": "(c) Stribeck: Fs, vs by eq. 12 (lower velocities)",
    "presliding": "(d) presliding: σ0, σ1 by output error, model in the loop",
}


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


@dataclass(eq=False)
class StageResult:
    """One stage: estimates, the records used, and data with the fitted curve."""

    name: str
    estimates: Estimates
    records: tuple[str, ...]
    data: pd.DataFrame  # columns x, measured, fitted (+ stage-specific)
    xlabel: str
    ylabel: str
    extra: dict = field(default_factory=dict)

    @property
    def title(self) -> str:
        return STAGES[self.name]

    def plot(self):
        """Data and fitted curve (top), residuals (bottom), against the stage's x."""
        import matplotlib.pyplot as plt

        if "fit" in self.extra:
            return self.extra["fit"].plot_fit()
        fig, (ax, axr) = plt.subplots(2, 1, sharex=True, figsize=(6.5, 5.5),
                                      gridspec_kw={"height_ratios": [2, 1]})
        order = np.argsort(self.data["x"].to_numpy())
        d = self.data.iloc[order]
        ax.plot(d["x"], d["measured"], "k.", ms=3, label="from the records")
        ax.plot(d["x"], d["fitted"], "C0-", lw=1.2, label="fitted")
        axr.plot(d["x"], d["measured"] - d["fitted"], "C3.", ms=3)
        axr.axhline(0, color="k", lw=0.6)
        ax.set_ylabel(self.ylabel)
        axr.set_ylabel("residual")
        axr.set_xlabel(self.xlabel)
        ax.set_title(self.title, fontsize=10)
        ax.legend(fontsize=8)
        for a in (ax, axr):
            a.grid(True, alpha=0.3)
        if self.name == "stribeck":
            ax.set_xscale("symlog", linthresh=1e-1)
        fig.tight_layout()
        return fig


def with_estimates(params, stages: Sequence[StageResult], name: str,
                   provenance: dict[str, str]):
    """``params`` with each stage's estimates, each value's source naming its stage."""
    from ..parameters import ParameterSet
    from ..parameters.parameter_set import ParameterInfo, number_text

    values = dict(params.values)
    info = dict(params.info)
    for stage in stages:
        for j, pname in enumerate(stage.estimates.names):
            if pname not in values and pname not in params:
                continue
            value = float(stage.estimates.values[j])
            se = float(stage.estimates.stderr[j])
            values[pname] = value
            info[pname] = ParameterInfo(
                number_text(pname, value), f"identified, stage {stage.title.split()[0]}",
                f"± {se:.3g} (standard error); records: {', '.join(stage.records)}")
    return ParameterSet(values, name=name, description=f"identified from {params.name}",
                        provenance={**params.provenance, **provenance}, info=info)


@dataclass(eq=False)
class PaperIdentification:
    """The four stages and the identified parameter set."""

    stages: dict[str, StageResult]
    parameters: object
    initial: object
    records: list[Record]

    def table(self, truth=None) -> pd.DataFrame:
        """Every estimate: stage, value, standard error, 95 % interval, initial value
        (and the truth and error in % when ``truth``, a parameter set, is given)."""
        frames = []
        for stage in self.stages.values():
            t = stage.estimates.to_pandas()
            t.insert(0, "stage", stage.title.split()[0])
            frames.append(t[[n in self.initial for n in t.index]])
        table = pd.concat(frames)
        table["initial"] = [self.initial[n] for n in table.index]
        if truth is not None:
            table["truth"] = [truth[n] for n in table.index]
            table["error_%"] = 100 * (table["value"] - table["truth"]) / table["truth"]
            table["truth_in_ci95"] = (table["ci95_low"] <= table["truth"]) & \
                (table["truth"] <= table["ci95_high"])
        return table

    def writers(self, truth=None, call: str = "") -> dict:
        """File name -> writer: identified.toml, estimates.csv, stage_*.png, report.md,
        report.html."""
        from ..parameters import write_params
        from ..plotting import figure_writer

        writers = {"identified.toml": lambda p: write_params(self.parameters, p),
                   "estimates.csv": lambda p: self.table(truth).to_csv(p)}
        for name, stage in self.stages.items():
            writers[f"stage_{name}.png"] = figure_writer(stage.plot)
        writers["report.md"] = lambda p: Path(p).write_text(self.report(truth),
                                                            encoding="utf-8")
        writers["report.html"] = lambda p: self.html_report(truth, call).write(p)
        return writers

    def html_report(self, truth=None, call: str = ""):
        """The estimates, the records and each stage's figure as a self-contained HTML
        ``Report`` (parameter set: the identified one, with each value's provenance)."""
        from ..io.report import Report

        report = Report("Identification of the actuator (paper section III.2)", call=call,
                        parameters=self.parameters)
        report.text("Records: " + ", ".join(Path(r.source).name for r in self.records))
        report.table(self.table(truth), "Estimates, standard errors and 95 % intervals "
                     "(SI)" + (", against the true values" if truth is not None else ""))
        for stage in self.stages.values():
            report.heading(stage.title)
            report.figure(stage.plot(), stage.title)
        return report

    def write(self, out_dir: str | Path, truth=None, call: str = "") -> list[Path]:
        """Write every file of ``writers`` into ``out_dir``, all or none."""
        from ..io.tables import write_files

        return write_files(out_dir, self.writers(truth, call))

    def report(self, truth=None) -> str:
        """A short Markdown report: the records, the estimates table, the figures."""
        table = self.table(truth)
        lines = ["# Identification of the actuator (paper section III.2)", "",
                 f"Parameter set: `{self.parameters.name}`; "
                 f"{self.parameters.provenance.get('identified', '')}", "",
                 "Records: " + ", ".join(f"`{Path(r.source).name}`" for r in self.records),
                 "", _markdown(table), ""]
        for name, stage in self.stages.items():
            lines += [f"## {stage.title}", "", f"![{name}](stage_{name}.png)", ""]
        return "\n".join(lines)


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


# --------------------------------------------------------------------------- stages
def stage_spring(sweeps: Sequence[Record], params, min_speed=1e-4, margin=0.3e-3,
                 steady=0.8) -> StageResult:
    """(a): F0, k and the friction level from the moving parts of quasi-static sweeps:
    |v| > ``min_speed``, ``margin`` away from the rest stop and the turning point, and on
    each branch at least ``steady`` × its median speed (the break-away transient at the
    start of a branch has Stribeck friction, at small x on one branch and large x on the
    other, which would leak into k)."""
    xs, fs, signs = [], [], []
    for rec in sweeps:
        kin = kinematics(rec, 0.1)
        moving = (np.abs(kin.velocity) > min_speed) & (kin.position > margin) & \
            (kin.position < kin.position.max() - margin)
        speed = np.abs(kin.velocity)
        keep = np.zeros_like(moving)
        for sign in (1, -1):
            branch = moving & (np.sign(kin.velocity) == sign)
            if branch.any():
                keep |= branch & (speed >= steady * np.median(speed[branch]))
        moving = keep
        force = drive_force(kin.pressure, params) - params["m"] * kin.acceleration
        xs.append(kin.position[moving])
        fs.append(force[moving])
        signs.append(np.sign(kin.velocity[moving]))
    x, f, s = (np.concatenate(a) for a in (xs, fs, signs))
    if not (np.any(s > 0) and np.any(s < 0)):
        raise DataError("stage (a): the sweep records need both branches (increasing and "
                        "decreasing position) off the rest stop")
    est, res, _ = linear_least_squares(np.column_stack([np.ones_like(x), x, s]), f,
                                       ["F0", "k", "friction_level"], ["N", "N/m", "N"],
                                       "stage (a) spring", correlated=True)
    data = pd.DataFrame({"x": x * 1e3, "measured": f, "fitted": f - res, "branch": s})
    return StageResult("spring", est, tuple(r.source for r in sweeps), data,
                       "position [mm]", "drive force (p_atm − p)·A_d − m·a [N]")


def _segments(records, params) -> pd.DataFrame:
    frames = [steady_segments(r, params) for r in records]
    frames = [f for f in frames if len(f)]
    if not frames:
        raise DataError("stages (b, c): no steady sliding segment found in the records; "
                        "ramps need a steady part of at least 0.2 s")
    return pd.concat(frames, ignore_index=True)


def stage_sliding(segments: pd.DataFrame, sliding_speed: float) -> StageResult:
    """(b): Fc, σ2 (and an offset) from eq. 13 over |v| ≥ ``sliding_speed``."""
    fast = segments[np.abs(segments["velocity"]) >= sliding_speed]
    v, f = fast["velocity"].to_numpy(), fast["friction"].to_numpy()
    x = fast["position"].to_numpy()
    if np.sum(v > 0) < 1 or np.sum(v < 0) < 1 or len(v) < 5:
        raise DataError(f"stage (b): {len(v)} steady segments at |v| >= "
                        f"{sliding_speed * 1e3:g} mm/s; need at least 5, in both directions")
    design = np.column_stack([np.sign(v), v, np.ones_like(v), x])
    est, res, _ = linear_least_squares(design, f, ["Fc", "sigma2", "offset", "spring_error"],
                                       ["N", "N*s/m", "N", "N/m"], "stage (b) eq. 13")
    data = pd.DataFrame({"x": v * 1e3, "measured": f, "fitted": f - res,
                         "record": fast["record"].to_numpy()})
    return StageResult("sliding", est, tuple(dict.fromkeys(fast["record"])), data,
                       "velocity [mm/s]", "friction force [N]")


def stage_stribeck(segments: pd.DataFrame, sliding: StageResult, params,
                   sliding_speed: float, fit_delta: bool = False) -> StageResult:
    """(c): Fs, vs (and δ) by nonlinear least squares of eq. 12 below ``sliding_speed``,
    with Fc, σ2 and the offset of stage (b) held."""
    slow = segments[np.abs(segments["velocity"]) < sliding_speed]
    v, f = slow["velocity"].to_numpy(), slow["friction"].to_numpy()
    fc, s2, off, dk = (sliding.estimates[n] for n in ("Fc", "sigma2", "offset",
                                                      "spring_error"))
    x = slow["position"].to_numpy()
    n_par = 3 if fit_delta else 2
    if len(v) <= n_par + 1:
        raise DataError(f"stage (c): {len(v)} steady segments below "
                        f"{sliding_speed * 1e3:g} mm/s; need at least {n_par + 2}")
    y = np.sign(v) * (f - s2 * v - off - dk * x)  # = g(|v|)
    speed = np.abs(v)

    def model(q):
        fs, vs = q[0], np.exp(q[1])
        delta = q[2] if fit_delta else params["delta"]
        return fc + (fs - fc) * np.exp(-((speed / vs) ** delta))

    q0 = [max(params["Fs"], y.max()), np.log(params["vs"])] + ([params["delta"]]
                                                                if fit_delta else [])
    # Fs ≥ Fc (Fc + (Fs − Fc)·e^… ≥ Fc), vs within 1 µm/s … 1 m/s, δ within 0.3 … 5
    lower = [fc, np.log(1e-6)] + ([0.3] if fit_delta else [])
    upper = [10 * max(fc, y.max()), 0.0] + ([5.0] if fit_delta else [])
    q0 = np.clip(q0, np.nextafter(lower, np.inf), np.nextafter(upper, -np.inf))
    sol = least_squares(lambda q: model(q) - y, q0, bounds=(lower, upper), x_scale="jac")
    jac = sol.jac.copy()
    values = sol.x.copy()
    values[1] = np.exp(values[1])
    jac[:, 1] /= values[1]  # back from log vs to vs
    cov, dof = covariance_from_jacobian(jac, sol.fun, n_par, correlated=False)
    # the estimates of stage (b) are held here: add their uncertainty (delta method)
    sign = np.sign(v)
    decay = np.exp(-((speed / values[1]) ** (values[2] if fit_delta else params["delta"])))
    held = np.column_stack([1 - decay, speed, sign, sign * x])  # ∂r/∂(Fc, σ2, offset, dk)
    b_idx = [sliding.estimates.names.index(n)
             for n in ("Fc", "sigma2", "offset", "spring_error")]
    cov_b = sliding.estimates.covariance[np.ix_(b_idx, b_idx)]
    gain = -np.linalg.pinv(jac) @ held  # ∂θ_c/∂θ_b at the optimum
    cov = cov + gain @ cov_b @ gain.T
    names = ["Fs", "vs"] + (["delta"] if fit_delta else [])
    est = Estimates(tuple(names), values, np.sqrt(np.diag(cov)), cov, dof,
                    ("N", "m/s", "")[:n_par])
    fitted = np.sign(v) * model(sol.x) + s2 * v + off + dk * x
    data = pd.DataFrame({"x": v * 1e3, "measured": f, "fitted": fitted,
                         "record": slow["record"].to_numpy()})
    return StageResult("stribeck", est, tuple(dict.fromkeys(slow["record"])), data,
                       "velocity [mm/s]", "friction force [N]")


def _presliding_window(record: Record, speed: float = 1e-3) -> float:
    """Start of the presliding part: after the longest run of sliding (the approach)."""
    kin = kinematics(record, 0.02)
    moving = np.abs(kin.velocity) > speed
    edges = np.flatnonzero(np.diff(np.concatenate([[0], moving.astype(np.int8), [0]])))
    if edges.size == 0:
        return float(record.time[0])
    runs = list(zip(edges[::2], edges[1::2], strict=True))
    _i0, i1 = max(runs, key=lambda r: r[1] - r[0])
    return float(kin.time[min(i1, kin.time.size - 1)] + 0.05)


def stage_presliding(records: Sequence[Record], params, friction=None, solver=None
                     ) -> StageResult:
    """(d): σ0, σ1 by output error on the presliding part of each record (a sensor
    offset per record is fitted too: the stuck position remembers the approach)."""
    from ..models import Actuator, LuGre, PressureSource
    from .fit import fit

    model = Actuator(params, friction=friction or LuGre(), valve=PressureSource())
    starts = [_presliding_window(r) for r in records]
    cropped_end = min(r.time[-1] for r in records)
    result = fit(model, records, ["sigma0", "sigma1"], offsets=["position"],
                 window=(max(starts), cropped_end), solver=solver)
    keep = [n in ("sigma0", "sigma1") for n in result.estimates.names]
    est = result.estimates
    idx = np.flatnonzero(keep)
    sub = Estimates(tuple(est.names[i] for i in idx), est.values[idx], est.stderr[idx],
                    est.covariance[np.ix_(idx, idx)], est.dof,
                    tuple(est.units[i] for i in idx))
    rec, sim = result.records[0], result.simulated[0]  # the fitted window
    data = pd.DataFrame({"x": rec.time, "measured": rec["position"] * 1e3,
                         "fitted": sim["position"] * 1e3})
    return StageResult("presliding", sub, tuple(r.source for r in records), data,
                       "time [s]", "position [mm]", {"fit": result})


def identify_paper(records: Sequence[Record], params, *, sliding_speed: float = 5e-3,
                   fit_delta: bool = False, name: str | None = None,
                   progress=None) -> PaperIdentification:
    """Run stages (a)-(d) on bench ``records`` (sweeps, ramps, presliding tests; see
    ``record_kind``). ``params`` gives what is not identified (m, A_d, p_atm, δ) and the
    starting values of stage (d). Returns the stages and the identified parameter set."""
    from ..io.records import as_records
    from ..parameters import as_parameter_set

    records = as_records(records, "identify_paper")
    params = as_parameter_set(params, "identify_paper")
    kinds = {"sweep": [], "ramp": [], "presliding": []}
    for rec in records:
        kinds[record_kind(rec)].append(rec)
    missing = [k for k, v in kinds.items() if not v]
    if missing:
        raise DataError(f"identify_paper: no {', '.join(missing)} record among "
                        f"{', '.join(Path(r.source).name for r in records)}")
    step = progress or (lambda label: None)
    step("spring")
    spring = stage_spring(kinds["sweep"], params)
    current = params.replace(F0=spring.estimates["F0"], k=spring.estimates["k"])
    step("sliding")
    segments = _segments(kinds["sweep"] + kinds["ramp"], current)
    sliding = stage_sliding(segments, sliding_speed)
    step("stribeck")
    stribeck = stage_stribeck(segments, sliding, current, sliding_speed, fit_delta)
    updates = {"Fc": sliding.estimates["Fc"], "sigma2": sliding.estimates["sigma2"],
               **stribeck.estimates.as_dict()}
    current = current.replace(updates)
    step("presliding")
    presliding = stage_presliding(kinds["presliding"], current)
    stages = {"spring": spring, "sliding": sliding, "stribeck": stribeck,
              "presliding": presliding}
    when = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    from .. import __version__

    identified = with_estimates(params, list(stages.values()),
                                name or f"{params.name}-identified",
                                {"identified": f"pneumact {__version__} identify_paper, "
                                               f"{when}",
                                 "records": ", ".join(Path(r.source).name for r in records)})
    return PaperIdentification(stages, identified, params, records)
