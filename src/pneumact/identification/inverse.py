"""Friction from measured motion and force: the inverse model (IDIM-LS).

When the force on the moving part is measured (a drive's current, a load cell), the
friction law follows from F = M·a + F_f(v) (+ offset) without any simulation: filter the
position and force with a zero-phase low-pass (scipy.signal), differentiate, decimate,
then solve linear least squares for Coulomb + viscous friction (optionally per
direction) and nonlinear least squares for a Stribeck map, with standard errors, the
condition number of the regression and the relative force error ‖F − F̂‖/‖F‖.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from ..errors import DataError, ParameterError
from ..io.records import Record
from ..io.report import ResultVocabulary
from ..plotting import tight_layout
from .estimates import Estimates, covariance_from_jacobian, linear_least_squares

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["InverseFriction", "inverse_friction"]

#: the laws of the inverse model (named as ``--friction`` names the simulated laws)
MODELS = ("coulomb-viscous", "stribeck")
#: a record moves when its position range exceeds this many times its sensor noise
MOTION_NOISE_MULTIPLE = 20.0
#: a regression whose column-scaled design is worse conditioned cannot separate its terms
MAX_CONDITION = 1e8
#: the heaviest moving mass an estimate may give [kg] (the catalogue's hard limit of m)
MAX_MASS = 1e5
#: an estimate below zero by more than this many standard errors is impossible
IMPOSSIBLE_SIGMAS = 2.0


def position_noise(position: np.ndarray) -> float:
    """The position sensor's noise (std) from the second differences, robustly (MAD):
    a smooth motion barely changes them, white noise of std s gives std s·sqrt(6)."""
    second = np.diff(position, 2)
    if second.size == 0:
        return 0.0
    mad = float(np.median(np.abs(second - np.median(second))))
    return 1.4826 * mad / np.sqrt(6.0)


def _refuse_still(record: Record) -> None:
    """Refuse a record whose position never leaves its noise: nothing to regress on."""
    position = record["position"]
    travel, noise = float(np.ptp(position)), position_noise(position)
    if travel <= MOTION_NOISE_MULTIPLE * noise:
        raise DataError(
            f"{record.source}: the record does not move: its position spans "
            f"{travel * 1e3:.3g} mm, within {MOTION_NOISE_MULTIPLE:g} times its noise "
            f"({noise * 1e3:.2g} mm); the inverse model needs motion back and forth at "
            "several speeds (the regressors sign(v), v and a are not excited)")


def _refuse_impossible(est: Estimates, cond: float, source: str) -> None:
    """Refuse estimates that no real friction can have: a badly conditioned regression,
    a negative mass, Coulomb or viscous force (beyond their errors), an absurd mass."""
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise DataError(f"{source}: the regressors are not excited: condition number "
                        f"{cond:.3g} (above {MAX_CONDITION:g}), so the terms "
                        f"{', '.join(est.names)} cannot be told apart; the record needs "
                        "motion in both directions at several speeds")
    values, errors = est.as_dict(), dict(zip(est.names, est.stderr, strict=True))
    wrong = []
    for name, value in values.items():
        if name.startswith(("Fc", "Fv", "Fs", "mass")) and value < 0 and not (
                -value <= IMPOSSIBLE_SIGMAS * errors[name]):
            wrong.append(f"{name} = {value:.3g} (a negative "
                         f"{'mass' if name == 'mass' else 'friction force'} cannot be)")
    if values.get("mass", 0.0) > MAX_MASS:
        wrong.append(f"mass = {values['mass']:.3g} kg (above {MAX_MASS:g} kg)")
    if wrong:
        raise DataError(f"{source}: physically impossible estimates: {'; '.join(wrong)}; "
                        "the record does not excite the inverse model (check that it "
                        "moves back and forth at several speeds, the force's sign and "
                        "units, and mass=False where the force is already the friction)")


@dataclass(frozen=True)
class _Motion:
    time: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    force: np.ndarray


def _motion(time, position, force, cutoff, decimate) -> _Motion:
    dt = np.diff(time)
    if np.ptp(dt) > 0.05 * np.mean(dt):  # jittery clock: resample on the median step
        step = float(np.median(dt))
        grid = np.arange(time[0], time[-1], step)
        position, force, time = (np.interp(grid, time, position),
                                 np.interp(grid, time, force), grid)
    fs = 1.0 / float(np.mean(np.diff(time)))
    if cutoff is not None:
        if not 0 < cutoff < fs / 2:
            raise ParameterError(f"inverse_friction: cutoff = {cutoff} Hz; must be in "
                                 f"(0, {fs / 2:g}) Hz (the Nyquist frequency)")
        from scipy.signal import butter, sosfiltfilt  # here: a 0.9 s import

        sos = butter(4, cutoff, fs=fs, output="sos")
        position, force = sosfiltfilt(sos, position), sosfiltfilt(sos, force)
    velocity = np.gradient(position, time)
    acceleration = np.gradient(velocity, time)
    keep = slice(None, None, max(1, int(decimate)))
    return _Motion(time[keep], velocity[keep], acceleration[keep], force[keep])


@dataclass(eq=False)
class InverseFriction(ResultVocabulary):
    """Estimates of the inverse model, with its fit quality and the data it used.

    ``to_pandas()``: the estimates (``"data"``: the processed motion and forces);
    ``plot()``: force against velocity and time; ``write(folder)``: both tables, the
    figure and report.html."""

    report_title = "Inverse friction model"
    figure_name = "inverse_model"

    model: str
    estimates: Estimates
    condition_number: float
    relative_force_error: float
    data: pd.DataFrame
    options: dict

    def predict(self, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
        """The force the identified model needs for this motion [N]."""
        return _predict(self.model, self.estimates.as_dict(), np.asarray(velocity),
                        np.asarray(acceleration), self.options["asymmetric"])

    def prediction(self, record: Record, values: dict[str, float] | None = None
                   ) -> pd.DataFrame:
        """time, velocity, measured and predicted force on another record, processed as
        the identification record was (filter, decimation, minimum speed); ``values``
        replaces the estimates (e.g. interpolated between operating points)."""
        force_name = self.options["force"]
        record.require(["position", force_name], "inverse-model validation")
        m = _motion(record.time, record["position"], record[force_name],
                    self.options["cutoff"], self.options["decimate"])
        used = np.abs(m.velocity) >= self.options["min_speed"]
        params = {**self.estimates.as_dict(), **(values or {})}
        predicted = _predict(self.model, params, m.velocity[used], m.acceleration[used],
                             self.options["asymmetric"])
        return pd.DataFrame({"time": m.time[used], "velocity": m.velocity[used],
                             "measured": m.force[used], "predicted": predicted})

    def friction_of(self, record: Record) -> Record:
        """``record`` with its ``friction`` = force − M·a − offset [N] (the identified mass
        and offset; a from the position filtered as the identification's, not decimated):
        the friction a simulated law is compared with where the force carries inertia."""
        force_name = self.options["force"]
        record.require(["position", force_name], "the friction of a record")
        m = _motion(record.time, record["position"], record[force_name],
                    self.options["cutoff"], 1)
        values = self.estimates.as_dict()
        friction = m.force - values.get("mass", 0.0) * m.acceleration - values.get("offset",
                                                                                   0.0)
        position = np.interp(m.time, record.time, record["position"])
        return Record.from_arrays(m.time, {"position": position, "friction": friction},
                                  {"position": "m", "friction": "N"}, record.source,
                                  dict(record.meta))

    def validate(self, record: Record) -> float:
        """Relative force error ‖F − F̂‖/‖F‖ on another record (same processing)."""
        frame = self.prediction(record)
        return float(np.linalg.norm(frame["measured"] - frame["predicted"]) /
                     np.linalg.norm(frame["measured"]))

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"estimates": self.estimates.to_pandas(), "data": self.data}

    def report_text(self) -> str:
        return (f"{self.model} friction from the motion's inverse model: relative force "
                f"error {100 * self.relative_force_error:.2f} %, condition number "
                f"{self.condition_number:.3g}.")

    def plot(self) -> Figure:
        """Force against velocity (data and model), and the force over time."""
        import matplotlib.pyplot as plt

        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6))
        d = self.data
        friction = d["force"] - self.estimates.as_dict().get("mass", 0.0) * d["acceleration"]
        ax1.plot(d["velocity"] * 1e3, friction, "k.", ms=1.5, label="measured F − M·a")
        order = np.argsort(d["velocity"].to_numpy())
        model = d["predicted"] - self.estimates.as_dict().get("mass", 0.0) * d["acceleration"]
        ax1.plot(d["velocity"].to_numpy()[order] * 1e3, model.to_numpy()[order], "C0-",
                 label=f"{self.model} model")
        ax1.set_xlabel("velocity [mm/s]")
        ax1.set_ylabel("friction force [N]")
        ax1.legend(fontsize=8)
        ax2.plot(d["time"], d["force"], "k-", lw=0.6, label="measured force")
        ax2.plot(d["time"], d["predicted"], "C0-", lw=0.8, label="inverse model")
        ax2.set_xlabel("time [s]")
        ax2.set_ylabel("force [N]")
        ax2.legend(fontsize=8)
        for a in (ax1, ax2):
            a.grid(True, alpha=0.3)
        ax1.set_title(f"relative force error {100 * self.relative_force_error:.1f} %, "
                      f"condition number {self.condition_number:.3g}", fontsize=9)
        tight_layout(fig)
        return fig


def _columns(v, a, mass, offset, asymmetric):
    cols, names, units = [], [], []
    if mass:
        cols.append(a)
        names.append("mass")
        units.append("kg")
    if asymmetric:
        cols += [(v > 0).astype(float), -(v < 0).astype(float), v * (v > 0), v * (v < 0)]
        names += ["Fc_pos", "Fc_neg", "Fv_pos", "Fv_neg"]
        units += ["N", "N", "N*s/m", "N*s/m"]
    else:
        cols += [np.sign(v), v]
        names += ["Fc", "Fv"]
        units += ["N", "N*s/m"]
    if offset:
        cols.append(np.ones_like(v))
        names.append("offset")
        units.append("N")
    return np.column_stack(cols), names, units


def _predict(model, p, v, a, asymmetric):
    force = p.get("mass", 0.0) * a + p.get("offset", 0.0)
    if asymmetric:
        fc = np.where(v > 0, p["Fc_pos"], -p["Fc_neg"])
        fv = np.where(v > 0, p["Fv_pos"], p["Fv_neg"])
        force = force + np.where(v != 0, fc, 0.0) + fv * v
    else:
        force = force + p["Fc"] * np.sign(v) + p["Fv"] * v
    if model == "stribeck":
        force = force + np.sign(v) * (p["Fs"] - p["Fc"]) * np.exp(-(np.abs(v) / p["vs"]) **
                                                                p.get("delta", 2.0))
    return force


def inverse_friction(record: Record, friction: str = "coulomb-viscous", *, force: str = "force",
                     mass: bool = True, offset: bool | None = None, asymmetric: bool = False,
                     cutoff: float | None = None, decimate: int = 1,
                     min_speed: float | None = None, delta: float = 2.0) -> InverseFriction:
    """Identify friction from ``record``'s position and ``force`` (or ``friction``).

    ``mass`` estimates the moving mass (the force then includes M·a; leave it out when
    the force is already the friction); ``cutoff`` [Hz] is the zero-phase Butterworth
    low-pass (order 4) applied to position and force before differentiation (default:
    none); ``decimate`` keeps every n-th sample after filtering; samples slower than
    ``min_speed`` (default 1 % of the fastest) are left out, where the sign of v is noise.
    ``friction="stribeck"`` adds Fs and vs (exponent ``delta``) by nonlinear least squares.
    ``offset`` (a constant force) is fitted by default, except with ``asymmetric``: then
    the Coulomb levels per direction already hold it (1(v>0) + 1(v<0) = 1 on every
    moving sample, so offset and the two levels are one regressor too many).
    A record whose position stays within its noise, a regression that cannot separate
    its terms and estimates no friction can have (a negative mass, Coulomb or viscous
    force beyond their errors, a mass above 1e5 kg) raise a DataError.
    """
    if offset is None:
        offset = not asymmetric
    if offset and asymmetric:
        raise ParameterError("inverse_friction: offset=True with asymmetric=True: the "
                             "offset is the mean of the two Coulomb levels; fit one or "
                             "the other")
    model = friction
    if model not in MODELS:
        raise ParameterError(f"inverse_friction: friction = {model!r}; allowed: "
                             f"{', '.join(MODELS)}")
    if model == "stribeck" and asymmetric:
        raise ParameterError("inverse_friction: the Stribeck model is symmetric; use "
                             "asymmetric=False")
    record.require(["position", force], "the inverse friction model")
    _refuse_still(record)
    m = _motion(record.time, record["position"], record[force], cutoff, decimate)
    speed_floor = 0.01 * np.max(np.abs(m.velocity)) if min_speed is None else min_speed
    used = np.abs(m.velocity) >= speed_floor
    if used.sum() < 10:
        raise DataError(f"{record.source}: only {used.sum()} samples move faster than "
                        f"{speed_floor:.3g} m/s; the inverse model needs motion")
    v, a, f = m.velocity[used], m.acceleration[used], m.force[used]
    design, names, units = _columns(v, a, mass, offset, asymmetric)
    est, res, cond = linear_least_squares(design, f, names, units,
                                          f"inverse model of {record.source}",
                                          correlated=True)
    if model == "stribeck":
        est, res = _stribeck(est, v, a, f, delta)
    _refuse_impossible(est, cond, record.source)
    predicted = f - res
    data = pd.DataFrame({"time": m.time[used], "velocity": v, "acceleration": a, "force": f,
                         "predicted": predicted})
    options = {"cutoff": cutoff, "decimate": decimate, "min_speed": speed_floor,
               "asymmetric": asymmetric, "force": force,
               "source": os.path.basename(record.source)}
    return InverseFriction(model, est, cond, float(np.linalg.norm(res) / np.linalg.norm(f)),
                           data, options)


def _stribeck(linear: Estimates, v, a, f, delta):
    """Fs and vs on top of the linear estimates, all refined by nonlinear least squares."""
    p0 = linear.as_dict()
    names = [*list(linear.names), "Fs", "vs"]
    speed = np.abs(v)
    start = [p0[n] for n in linear.names] + [1.2 * p0["Fc"], np.log(np.median(speed) / 5)]

    def residual(q):
        p = dict(zip(names, q, strict=True))
        p["vs"] = np.exp(p["vs"])
        p["delta"] = delta
        return _predict("stribeck", p, v, a, False) - f

    sol = least_squares(residual, start, x_scale="jac")
    values = sol.x.copy()
    values[-1] = np.exp(values[-1])
    jac = sol.jac.copy()
    jac[:, -1] /= values[-1]
    cov, dof = covariance_from_jacobian(jac, sol.fun, len(names))
    units = (*tuple(linear.units), "N", "m/s")
    return Estimates(tuple(names), values, np.sqrt(np.diag(cov)), cov, dof, units), -sol.fun
