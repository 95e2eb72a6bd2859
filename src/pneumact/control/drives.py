"""Replay of a measured servo drive in its own closed loop (the EMPS benchmark).

``replay_drive(record, friction)`` rebuilds the drive of a closed-loop record — the
moving mass and friction identified by the inverse model (``inverse_friction``), under
the drive's sampled cascade controller — feeds it the record's position reference and
compares what it does with what the real drive did: position, velocity and motor force.
Nothing is fitted here; every number comes from the identification or the record.

What is modelled (EMPS: Janot, Gautier & Brunot 2019, ``shared/data/emps/README.md``):

* plant: a rigid mass ``m`` = the identified M, with Coulomb + viscous friction
  (``CoulombViscous``: Fc, σ2 = Fv, sign rounded over ``v_reg``) or the identified
  Stribeck map (``StribeckMap``); the inverse model's constant ``offset`` (a force the
  motor has to supply: F_motor = M·a + F_f(v) + offset) acts on the mass as the
  disturbance −offset;
* controller: the sampled P/P cascade u_k = kv·(kp·(r_k − x_k) − v̂_k), limited to
  ±``saturation`` V, held over one period Ts (zero-order hold, no computation delay),
  plant force gtau·u. Ts is the record's sample period: the drive logs one sample per
  controller tick;
* velocity estimate: the README's "2-tap FIR position filter" is modelled as the
  backward difference v̂_k = (x_k − x_{k−1})/Ts (taps [1, −1]/Ts), the controller's
  ``velocity_estimate="difference"``. On the EMPS records this law reproduces the
  recorded command vir from the recorded qm and qg to 0.05 V RMS (vir spans ±4 V);
  ``"measured"`` (the model's exact velocity, an ideal sensor) is there to compare;
* pulses (``DATA_EMPS_PULSES.mat``): the recorded ``pulses_N`` (0 or 5) enter as a
  signal *added to the controller output*, in volts — the recorded vir contains them.
  Evidence in the record: vir_k − kv·(kp·(qg_k − qm_k) − (qm_k − qm_{k−1})/Ts) equals
  1.014 × pulses_k (least squares; 0.056 V RMS left); at each rising edge the motor
  force jumps by +178 N ≈ 5 V·gtau in the same sample, then the loop pulls it back to
  the unpulsed level within ~35 ms while the carriage settles ≈ +130 µm ≈ 5/(kp·kv)
  further along — the P/P cascade's steady answer to a 5 V command offset. A 5 N force
  on the carriage could neither move vir within the sample nor shift the position by
  more than 5 N/(gtau·kv·kp) ≈ 4 µm. ``pulses="force"`` replays that rejected reading
  (an external force of pulses_N newtons along +x) for comparison.

Alignment: the controller samples x_k and computes u_k at t_k; the loop's output at a
sample time is the command held from that sample on (right-continuous, as a zero-order
hold), so the frame's simulated motor force at sample k is gtau·u_k. The measured
velocity is the central difference of the measured position after a zero-phase
Butterworth low-pass (order 4, ``velocity_cutoff`` Hz, as the inverse model's
processing); the simulated velocity is the simulated
position processed the same way (the model's exact velocity is ``velocity_model``).
The model starts where the record does: at the measured position and the measured
(filtered) velocity, its last sampled position one period behind at that velocity.

Limits: the plant is rigid and the drive ideal (no current-loop dynamics, no actuation
delay, no compliance). On the pulse record half of the squared force error lies in the
60 ms after the pulse edges (12 % of the samples): the real force decays more slowly
than the model's (174 vs 167 N one sample after a rising edge) and the carriage swings
further (19 ms after a rising edge 40 vs 34 µm past where it was, edge average). The
static friction map has no presliding or Stribeck memory: velocity reversals (|v| <
5 mm/s, 2 % of the samples) carry 11 % of the squared force error on DATA_EMPS.mat.
"""

from __future__ import annotations

import math
import os
import time as _time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import DataError, ParameterError
from ..io.records import Record
from ..io.report import NotebookDisplay
from ..plotting import tight_layout

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.signals import Signal
    from ..models.friction import FrictionModel
    from ..parameters.parameter_set import ParameterSet

__all__ = ["DriveReplay", "control_law_check", "drive_plant", "replay_drive"]

GAIN_NAMES = ("kp", "kv", "gtau")
PULSE_INPUTS = ("command", "force")
VELOCITY_CUTOFF = 50.0  # Hz: the inverse model's low-pass on the EMPS records
FILTER_ORDER = 4
#: largest deviation of a sample time from the uniform grid, in sample periods
UNIFORM_TOLERANCE = 0.01
ERROR_NAMES = ("position", "position_rms_mm", "tracking", "velocity", "force",
               "force_rms_N")


def _relative(measured: np.ndarray, simulated: np.ndarray) -> float:
    norm = float(np.linalg.norm(measured))
    return float(np.linalg.norm(measured - simulated) / norm) if norm > 0 else math.inf


@dataclass(eq=False)
class DriveReplay(NotebookDisplay):
    """One record replayed in closed loop.

    ``frame``: time, reference, position/velocity/force measured and simulated (SI)
    and the model's own velocity; ``errors``: relative errors ‖y − ŷ‖/‖y‖ of
    ``position``, ``velocity`` and ``force``, ``tracking`` = ‖x̂ − x‖/‖r − x‖ (the
    position error against the measured tracking error, the sharper measure: the
    position itself follows the reference), ``position_rms_mm`` and ``force_rms_N``;
    ``settings``: gains, limits, options, the friction estimates and the run's cost;
    ``parameters``: the plant's parameter set."""

    name: str
    frame: pd.DataFrame
    errors: dict[str, float]
    settings: dict[str, object]
    parameters: ParameterSet | None = None
    notes: list[str] = field(default_factory=list)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The frame (a copy); ``name="metrics"``: the errors (``metrics()``)."""
        if name == "metrics":
            return self.metrics()
        if name is not None:
            raise ParameterError(f"to_pandas: name = {name!r}; allowed: metrics")
        return self.frame.copy()

    def metrics(self) -> pd.DataFrame:
        """One row: the record and its errors."""
        e = self.errors
        return pd.DataFrame([{
            "record": self.name, "pulses": self.settings.get("pulses", "none"),
            "velocity_estimate": self.settings.get("velocity_estimate", ""),
            "position_relative_error": e["position"], "position_rms_mm": e["position_rms_mm"],
            "tracking_relative_error": e["tracking"], "velocity_relative_error": e["velocity"],
            "force_relative_error": e["force"], "force_rms_N": e["force_rms_N"]}])

    def plot(self) -> Figure:
        """Position, velocity and motor force, measured against simulated, and the
        position error (with the measured tracking error for scale)."""
        import matplotlib.pyplot as plt

        d = self.frame
        t = d["time"].to_numpy()
        fig, axes = plt.subplots(4, 1, figsize=(8.0, 9.5), sharex=True)
        ax = axes[0]
        ax.plot(t, d["reference"] * 1e3, color="0.6", lw=0.8, ls="--", label="reference")
        ax.plot(t, d["position_measured"] * 1e3, "k-", lw=0.8, label="measured")
        ax.plot(t, d["position_simulated"] * 1e3, "C0-", lw=0.8, label="simulated")
        ax.set_ylabel("position [mm]")
        ax.set_title(f"{self.name}: position {100 * self.errors['position']:.3g} %, "
                     f"velocity {100 * self.errors['velocity']:.3g} %, force "
                     f"{100 * self.errors['force']:.3g} % relative error", fontsize=9)
        axes[1].plot(t, d["velocity_measured"] * 1e3, "k-", lw=0.6, label="measured")
        axes[1].plot(t, d["velocity_simulated"] * 1e3, "C0-", lw=0.6, label="simulated")
        axes[1].set_ylabel("velocity [mm/s]")
        axes[2].plot(t, d["force_measured"], "k-", lw=0.5, label="measured gtau·vir")
        axes[2].plot(t, d["force_simulated"], "C0-", lw=0.5, label="simulated gtau·u")
        axes[2].set_ylabel("motor force [N]")
        tracking = d["reference"] - d["position_measured"]
        axes[3].plot(t, (d["position_simulated"] - d["position_measured"]) * 1e6, "C3-",
                     lw=0.6, label="simulated − measured position (measured tracking "
                                   f"error r − x: {1e6 * np.sqrt(np.mean(tracking**2)):.0f}"
                                   " µm RMS)")
        axes[3].set_ylabel("position error [µm]")
        axes[3].set_xlabel("time [s]")
        for a in axes:
            a.grid(True, alpha=0.3)
            a.legend(fontsize=7, loc="upper right")
        tight_layout(fig)
        return fig

    def report(self, *, call: str = "", title: str = ""):
        """The HTML report (``pneumact.io.report.Report``), not yet written."""
        from ..io.report import Report

        report = Report(title or f"Closed-loop replay of {self.name}", call=call,
                        parameters=self.parameters)
        report.text(
            "The identified drive (mass, friction, offset) under the drive's own sampled "
            "cascade controller follows the recorded position reference; nothing is "
            "fitted to this record. Relative error = ‖y − ŷ‖/‖y‖; tracking = ‖x̂ − x‖/"
            "‖r − x‖ (position error against the measured tracking error).")
        for note in self.notes:
            report.note(note)
        report.table(self.metrics(), "Errors", index=False)
        settings = pd.DataFrame({"value": [str(v) for v in self.settings.values()]},
                                index=list(self.settings))
        report.table(settings, "Settings of the replay")
        report.figure(self.plot(), "Measured and simulated position, velocity, motor "
                                   "force, and the position error")
        return report

    def write(self, out_dir: str | os.PathLike, *, call: str = "", title: str = ""
              ) -> list[Path]:
        """replay.csv (the frame), metrics.csv, replay.png and report.html, all or
        nothing (``pneumact.io.tables.write_files``)."""
        from ..io.tables import write_files
        from ..plotting import figure_writer

        report = self.report(call=call, title=title)
        return write_files(out_dir, {
            "replay.csv": lambda p: self.frame.to_csv(p, index=False),
            "metrics.csv": lambda p: self.metrics().to_csv(p, index=False),
            "replay.png": figure_writer(self.plot),
            "report.html": report.write})


# --------------------------------------------------------------------------- building
def drive_plant(friction, v_reg: float = 1e-4):
    """(rig, offset [N]) from an ``InverseFriction``: a ``FrictionRig`` with a force
    drive, mass M and the identified Coulomb + viscous (or Stribeck) friction, and the
    constant force the inverse model adds (the loop applies −offset to the mass).

    Refused with ``ParameterError``: an identification without the mass, or with
    per-direction friction (``asymmetric=True``: the rig's laws are symmetric). The
    Stribeck exponent is not recorded by ``inverse_friction``: ``options["delta"]``
    when present, else 2 (its default, as ``InverseFriction.predict`` assumes)."""
    from ..identification.inverse import InverseFriction
    from ..models.friction import CoulombViscous, StribeckMap
    from ..models.rig import FrictionRig
    from ..parameters import ParameterSet

    if not isinstance(friction, InverseFriction):
        raise ParameterError(f"replay_drive: friction = {type(friction).__name__}; give the "
                             "result of inverse_friction")
    est = friction.estimates.as_dict()
    source = friction.options.get("source") or "identification record"
    if friction.options.get("asymmetric"):
        raise ParameterError(
            f"replay_drive: the friction of {source} was identified per direction "
            "(asymmetric=True: Fc_pos, Fc_neg, Fv_pos, Fv_neg); the rig's friction laws "
            "are symmetric. Identify with asymmetric=False (Fc, Fv and an offset)")
    if "mass" not in est:
        raise ParameterError(f"replay_drive: the identification of {source} has no mass "
                             "(mass=False); a forward simulation needs it")
    values = {"m": est["mass"], "Fc": est["Fc"], "sigma2": est["Fv"], "v_reg": v_reg}
    if friction.model == "stribeck":
        values.update(Fs=est["Fs"], vs=est["vs"],
                      delta=float(friction.options.get("delta", 2.0)))
        law: FrictionModel = StribeckMap()
    elif friction.model == "coulomb-viscous":
        law = CoulombViscous()
    else:
        raise ParameterError(f"replay_drive: friction model {friction.model!r}; allowed: "
                             "coulomb-viscous, stribeck")
    try:
        params = ParameterSet.from_dict(values, name=f"inverse model of {source}")
    except ParameterError as exc:
        raise ParameterError(f"replay_drive: the {friction.model} friction identified on "
                             f"{source} cannot drive the rig: {exc}") from exc
    return FrictionRig(params, law, drive="force"), float(est.get("offset", 0.0))


def _gains(record: Record, gains: Mapping[str, float] | None) -> dict[str, float]:
    gains = dict(gains or {})
    unknown = sorted(set(gains) - set(GAIN_NAMES))
    if unknown:
        raise ParameterError(f"replay_drive: gains {unknown} unknown; allowed: "
                             f"{', '.join(GAIN_NAMES)}")
    out = {}
    for name in GAIN_NAMES:
        if name in gains:
            value = gains[name]
        elif name in record.meta:
            try:
                value = float(record.meta[name])
            except ValueError as exc:
                raise DataError(f"{record.source}: meta {name} = {record.meta[name]!r} is "
                                "not a number") from exc
        else:
            raise ParameterError(f"replay_drive: {record.source} has no gain {name!r} in "
                                 "its meta; give it in gains=")
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise ParameterError(f"replay_drive: gain {name} = {value!r}; must be a "
                                 "finite number > 0")
        out[name] = float(value)
    return out


def _sample_period(record: Record) -> float:
    t = np.asarray(record.time, dtype=float)
    if t.size < 3:
        raise DataError(f"{record.source}: {t.size} samples; a replay needs a record")
    period = (t[-1] - t[0]) / (t.size - 1)
    deviation = float(np.max(np.abs(t - (t[0] + period * np.arange(t.size)))))
    if not period > 0 or deviation > UNIFORM_TOLERANCE * period:
        raise DataError(f"{record.source}: samples are not uniform (a sample is "
                        f"{deviation:.3g} s off the {period:.6g} s grid); the sampled "
                        "controller runs at one rate: resample the record first")
    return float(period)


def control_law_check(record: Record, gains: Mapping[str, float] | None = None
                      ) -> dict[str, float]:
    """How well the modelled sampled law explains the record's own command.

    From the *measured* qm and qg alone: vir_k = force_k/gtau against
    kv·(kp·(qg_k − qm_k) − (qm_k − qm_{k−1})/Ts) for k ≥ 1. Returns ``law_rms_V`` (RMS
    of the difference) and ``vir_rms_V``; with pulses also ``pulse_gain`` and
    ``pulse_bias_V`` (least squares of the difference on pulses_k and 1) and
    ``law_rms_with_pulses_V`` (what is left): a gain of +1 says the pulses are volts
    added to the controller output and recorded in vir."""
    record.require(["position", "reference", "force"], "control_law_check")
    g = _gains(record, gains)
    period = _sample_period(record)
    q = np.asarray(record["position"], dtype=float)
    vir = np.asarray(record["force"], dtype=float)[1:] / g["gtau"]
    law = g["kv"] * (g["kp"] * (np.asarray(record["reference"], dtype=float)[1:] - q[1:])
                     - np.diff(q) / period)
    residual = vir - law
    out = {"law_rms_V": float(np.sqrt(np.mean(residual**2))),
           "vir_rms_V": float(np.sqrt(np.mean(vir**2)))}
    if "pulses" in record:
        pulses = np.asarray(record["pulses"], dtype=float)[1:]
        design = np.column_stack([pulses, np.ones_like(pulses)])
        coef, *_ = np.linalg.lstsq(design, residual, rcond=None)
        left = residual - design @ coef
        out.update(pulse_gain=float(coef[0]), pulse_bias_V=float(coef[1]),
                   law_rms_with_pulses_V=float(np.sqrt(np.mean(left**2))))
    return out


def _velocity(position: np.ndarray, period: float, cutoff: float) -> np.ndarray:
    from scipy.signal import butter, sosfiltfilt

    sos = butter(FILTER_ORDER, cutoff, fs=1.0 / period, output="sos")
    return np.gradient(sosfiltfilt(sos, position), period)


def _pulse_input(record: Record, pulses) -> str:
    if pulses is False or pulses is None:
        return "none"
    if pulses is True:
        return "command" if "pulses" in record else "none"
    if pulses not in PULSE_INPUTS:
        raise ParameterError(f"replay_drive: pulses = {pulses!r}; allowed: True, False, "
                             f"{', '.join(map(repr, PULSE_INPUTS))}")
    if "pulses" not in record:
        raise DataError(f"{record.source}: pulses = {pulses!r} but the record has no "
                        "pulses signal")
    return pulses


def replay_drive(record: Record, friction, *, gains: Mapping[str, float] | None = None,
                 saturation: float | None = 10.0, velocity_estimate: str = "difference",
                 pulses: bool | str = True, v_reg: float = 1e-4,
                 velocity_cutoff: float = VELOCITY_CUTOFF, solver=None) -> DriveReplay:
    """Simulate the identified drive in the record's closed loop (module docstring).

    ``record``: an EMPS-like record (``read_emps``): position, reference, force (the
    motor force gtau·vir) and, optionally, pulses, uniformly sampled at the controller's
    rate; gains ``kp`` [1/s], ``kv`` [V/(m/s)], ``gtau`` [N/V] in its meta.
    ``friction``: ``inverse_friction``'s result (mass, Coulomb + viscous or Stribeck,
    offset). ``gains``: overrides of kp, kv, gtau. ``saturation`` [V]: the output limit
    ±saturation (None: none). ``velocity_estimate``: ``"difference"`` (the drive's
    2-tap FIR, a backward difference) or ``"measured"``. ``pulses``: True applies the
    record's pulses where present as a command added to the controller output [V]
    (``"command"``, the reading the record supports), ``"force"`` as an external force
    [N] on the carriage along +x, False ignores them. ``v_reg`` [m/s]: the friction
    sign's rounding. ``velocity_cutoff`` [Hz]: the low-pass before the velocity's
    central difference. ``solver``: default ``Rodas4()``.
    """
    from ..core.assembly import assemble
    from ..core.signals import Constant, PiecewiseLinear
    from ..experiments.setpoints import SetpointProfile
    from ..models.controllers import Cascade
    from ..simulation.simulate import simulate
    from .loop import ClosedLoop

    record.require(["position", "reference", "force"], "replay_drive")
    g = _gains(record, gains)
    period = _sample_period(record)
    if not (isinstance(velocity_cutoff, int | float) and 0 < velocity_cutoff < 0.5 / period):
        raise ParameterError(f"replay_drive: velocity_cutoff = {velocity_cutoff!r} Hz; must "
                             f"be in (0, {0.5 / period:g}) Hz (the Nyquist frequency)")
    if saturation is None:
        limit = math.inf
    elif isinstance(saturation, int | float) and saturation > 0:
        limit = float(saturation)
    else:
        raise ParameterError(f"replay_drive: saturation = {saturation!r} V; must be > 0 "
                             "or None")
    mode = _pulse_input(record, pulses)
    rig, offset = drive_plant(friction, v_reg)
    controller = Cascade(kx=g["kp"], kv=g["kv"], ki=0.0, u_min=-limit, u_max=limit,
                         sample_time=period, velocity_estimate=velocity_estimate)

    q = np.asarray(record["position"], dtype=float)
    reference = np.asarray(record["reference"], dtype=float)
    measured_force = np.asarray(record["force"], dtype=float)
    n = q.size
    # the controller's clock: t_k = k·Ts from 0, one extra held sample for u_{n−1}
    grid = period * np.arange(n + 1)

    def held(values):
        values = np.asarray(values, dtype=float)
        return np.concatenate([values, values[-1:]])

    disturbance: Signal | None = Constant(-offset) if offset != 0.0 else None
    feedforward = None
    if mode == "command":
        feedforward = PiecewiseLinear(grid, held(record["pulses"]))
    elif mode == "force":
        disturbance = PiecewiseLinear(grid, held(record["pulses"]) - offset)
    loop = ClosedLoop(rig, controller, drive_gain=g["gtau"], disturbance=disturbance,
                      feedforward=feedforward)
    experiment = SetpointProfile(grid, held(reference), name=os.path.basename(record.source))

    if n <= 3 * (2 * FILTER_ORDER + 1):
        raise DataError(f"{record.source}: {n} samples are too few for the zero-phase "
                        "filter of the velocity")
    v_measured = _velocity(q, period, velocity_cutoff)
    names = assemble(loop).state_names
    y0 = np.zeros(len(names))
    start = {"position": q[0], "velocity": v_measured[0],
             "last_position": q[0] - v_measured[0] * period}
    for i, name in enumerate(names):
        y0[i] = start.get(name, 0.0)

    began = _time.perf_counter()
    result = simulate(loop, experiment, solver, t_eval=grid, y0=y0)
    wall = _time.perf_counter() - began
    x = result.signals["position"][:n]
    force = g["gtau"] * result.signals["command"][:n]
    v_simulated = _velocity(x, period, velocity_cutoff)
    frame = pd.DataFrame({
        "time": np.asarray(record.time, dtype=float), "reference": reference,
        "position_measured": q, "position_simulated": x,
        "velocity_measured": v_measured, "velocity_simulated": v_simulated,
        "velocity_model": result.signals["velocity"][:n],
        "force_measured": measured_force, "force_simulated": force})
    errors = {
        "position": _relative(q, x),
        "position_rms_mm": float(1e3 * np.sqrt(np.mean((x - q) ** 2))),
        "tracking": float(np.linalg.norm(x - q) / np.linalg.norm(reference - q)),
        "velocity": _relative(v_measured, v_simulated),
        "force": _relative(measured_force, force),
        "force_rms_N": float(np.sqrt(np.mean((force - measured_force) ** 2)))}
    est = friction.estimates.as_dict()
    settings = {
        "record": os.path.basename(record.source),
        "identified_on": friction.options.get("source", ""),
        "friction_model": friction.model, **g, "saturation_V": limit,
        "sample_time_s": period, "velocity_estimate": velocity_estimate, "pulses": mode,
        "velocity_cutoff_Hz": float(velocity_cutoff), "v_reg": v_reg,
        **{f"identified_{k}": float(v) for k, v in est.items()},
        "solver": result.meta.get("solver", ""), "solver_steps": result.meta.get("steps", ""),
        "simulation_wall_s": wall}
    check = control_law_check(record, g)
    settings.update({f"check_{k}": v for k, v in check.items()})
    if "pulse_gain" in check:
        explained = (f"to {check['law_rms_with_pulses_V']:.3g} V RMS once the pulses are "
                     f"added to it with the least-squares gain {check['pulse_gain']:.4g} "
                     f"(without them: {check['law_rms_V']:.3g} V RMS)")
    else:
        explained = f"to {check['law_rms_V']:.3g} V RMS"
    notes = [f"The sampled cascade law with the backward-difference velocity reproduces the "
             f"recorded command (vir: {check['vir_rms_V']:.3g} V RMS) from the recorded "
             f"position and reference {explained}."]
    if mode == "command":
        notes.append("The record's pulses are added to the controller output in volts "
                     "(the recorded command contains them).")
    elif mode == "force":
        notes.append("The pulses act as an external force [N] on the carriage along +x "
                     "(a reading the recorded command contradicts; kept for comparison).")
    return DriveReplay(os.path.basename(record.source), frame, errors, settings,
                       rig.params, notes)
