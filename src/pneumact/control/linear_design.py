"""A PID designed the classical way: on the linearised plant, with python-control.

``linear_design(loop, specs)`` is what an engineer does without pneumact's nonlinear
tuning: linearise the plant at the operating point, translate the specs into a loop
shape, place the PID there and check the linear closed loop. It is the baseline that
``compare_designs`` runs on the nonlinear model to show where friction breaks it.

1. **Plant**: ``linearise`` at the input that holds ``at`` (default mid-stroke), by
   default in steady sliding at the speed of a 20 %-of-stroke step done within the
   settling spec (an engineer's model of the motion; ``regime="presliding"`` gives the
   bristle-stiff rest instead). The loop's controller sees P(s) = action · drive_gain ·
   G(s), G the plant's Δx/Δinput.
2. **Loop shape** from the specs (second-order rules): damping ζ from the overshoot
   (ζ = 1 for none), phase margin PM = atan(2ζ/√(√(1+4ζ⁴) − 2ζ²)), crossover
   ω_c = ω_n·√(√(1+4ζ⁴) − 2ζ²) with ω_n = 4/(ζ·T_s) (T_s the settling spec).
3. **PID at the crossover** (frequency-response design, Åström & Hägglund): with
   T_i = 4·T_d (then 10, 25, 60 T_d: slower integral action; then a PD), the gains put
   L(jω_c) = C(jω_c)·P(jω_c) at −180° + PM with |L| = 1; the derivative acts on the
   measurement through a filter T_f = T_d/10, as the loop's
   ``PID(derivative="measurement")`` does. Where the plant lags less than that asks (a
   regulator-fed chamber well below its resonances), the PID lags 80° (mostly integral
   action) and the margin is larger than asked.
4. **Check with python-control**: the closed loop y/r = P·(K_p + K_i/s)/(1 + P·C) built
   with ``control.feedback``, its ``step_info`` (overshoot, settling into the specs'
   band) and ``stability_margins``. Crossovers from ω_c/30 to 10·ω_c are tried for each
   T_i/T_d; of those whose linear step meets the specs, the one nearest ω_c with the
   fastest integral action is kept (else the fastest settling within the overshoot
   spec): the design the linear model promises.

python-control is optional (``pip install 'pneumact[control]'``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..io.report import ResultVocabulary
from ..models.controllers import PID
from ..plotting import tight_layout
from .linear import LinearPlant, linearise
from .loop import ClosedLoop
from .specs import Specs

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["LinearDesign", "linear_design"]

#: the T_i / T_d tried: Ziegler-Nichols' 4 first, then slower integral action, then none
#: (a PD: a plant with an integrator of its own, e.g. a rig without a spring, overshoots
#: 20-35 % under a PID placed by its phase margin)
TI_OVER_TD = (4.0, 10.0, 25.0, 60.0, math.inf)
#: T_d / T_f: the derivative filter's time constant
FILTER_RATIO = 10.0
#: the most phase lag [deg] the PID adds at the crossover (beyond it Kp would vanish)
MOST_LAG = 80.0
#: the crossovers tried, relative to the specs' ω_c
CROSSOVER_RANGE = (1.0 / 30.0, 10.0)
CROSSOVER_CANDIDATES = 41
#: defaults where the specs leave a number out
DEFAULT_OVERSHOOT = 5.0  # %
DEFAULT_SETTLING = 0.4  # s
#: the linear step is simulated over this many settling specs
STEP_HORIZON = 6.0


@dataclass(eq=False)
class LinearDesign(ResultVocabulary):
    """A PID designed on the linearised plant (see the module docstring).

    ``loop``: the loop with the designed gains (the input loop's limits and options);
    ``plant``: the ``LinearPlant``; ``crossover`` [rad/s] and ``phase_margin`` [deg] as
    designed; ``predicted``: the linear closed loop's step metrics (overshoot [%],
    settling and rise time [s], gain and phase margins) and whether they meet the
    specs. ``to_pandas()``: the gains; ``"predicted"``: the linear metrics against the
    limits; ``"candidates"``: every crossover tried. ``plot()``: the open loop's Bode
    plot and the linear step."""

    report_title = "Linear PID design (python-control)"
    figure_name = "linear_design"

    loop: ClosedLoop
    plant: LinearPlant
    specs: Specs
    crossover: float
    phase_margin: float
    predicted: dict[str, float]
    candidates: pd.DataFrame
    sign: float

    @property
    def controller(self) -> PID:
        controller = self.loop.controller
        assert isinstance(controller, PID)  # linear_design builds a PID
        return controller

    @property
    def gains(self) -> dict[str, float]:
        return self.loop.gains

    @property
    def meets_specs(self) -> bool:
        """Whether the *linear* closed loop meets the overshoot and settling specs."""
        return bool(self.predicted["meets_specs"])

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"gains": self.gains_table(), "predicted": self.predicted_table(),
                "candidates": self.candidates}

    def gains_table(self) -> pd.DataFrame:
        units = self.loop.gain_units
        c = self.controller
        rows = [(n, c.parameters()[n], units[n]) for n in ("kp", "ki", "kd", "filter_time")]
        rows += [("Ti = Kp/Ki", c.kp / c.ki if c.ki else math.inf, "s"),
                 ("Td = Kd/Kp", c.kd / c.kp, "s")]
        return pd.DataFrame(rows, columns=["gain", "value", "unit"])

    def predicted_table(self) -> pd.DataFrame:
        limits = _limits(self.specs)
        rows = [("crossover", self.crossover, "rad/s", math.nan),
                ("phase margin (designed)", self.phase_margin, "deg", math.nan),
                ("phase margin", self.predicted["phase_margin"], "deg", math.nan),
                ("gain margin", self.predicted["gain_margin"], "1", math.nan),
                ("overshoot", self.predicted["overshoot"], "%", limits["overshoot"]),
                ("settling time", self.predicted["settling_time"], "s", limits["settling"]),
                ("rise time", self.predicted["rise_time"], "s",
                 self.specs.rise if self.specs.rise is not None else math.nan)]
        return pd.DataFrame(rows, columns=["metric", "linear model", "unit", "limit"])

    def report_text(self) -> str:
        verdict = "meets" if self.meets_specs else "does NOT meet"
        return (f"{self.plant.statement} PID placed at the crossover "
                f"{self.crossover:.3g} rad/s with {self.phase_margin:.0f}° phase margin; on "
                f"the linear model it {verdict} the overshoot and settling specs "
                f"({self.predicted['overshoot']:.3g} %, {self.predicted['settling_time']:.3g} "
                "s). Run it on the nonlinear model with compare_designs.")

    def closed_loop(self):
        """The linear closed loop y/r (a python-control system)."""
        return self._loops()[0]

    def _loops(self):
        """(y/r, the open loop L) of the designed gains on the linear plant."""
        c = self.controller
        return _closed_loop(_scaled_plant(self.plant, self.sign), c.kp, c.ki, c.kd,
                            c.filter_time)

    def plot(self) -> Figure:
        """Left: |L(jω)| and its phase (the crossover marked); right: the linear step."""
        import control
        import matplotlib.pyplot as plt

        response, open_loop = self._loops()
        omega = self.crossover * np.logspace(-2, 2, 400)
        fr = control.frequency_response(open_loop, omega)
        gain = np.abs(np.asarray(fr.complex).ravel())
        phase = np.degrees(np.unwrap(np.angle(np.asarray(fr.complex).ravel())))
        fig, axes = plt.subplots(1, 3, figsize=(11, 3.4))
        axes[0].loglog(omega, gain)
        axes[0].axhline(1.0, color="0.5", lw=0.8)
        axes[1].semilogx(omega, phase)
        axes[1].axhline(-180.0 + self.phase_margin, color="C3", lw=0.8, ls="--",
                        label=f"−180° + PM ({self.phase_margin:.0f}°)")
        for ax in axes[:2]:
            ax.axvline(self.crossover, color="C3", lw=0.8, ls=":")
            ax.set_xlabel("ω [rad/s]")
            ax.grid(True, which="both", alpha=0.3)
        axes[0].set_ylabel("|L(jω)|")
        axes[1].set_ylabel("∠L(jω) [deg]")
        axes[1].legend(fontsize=7)
        t = np.linspace(0.0, STEP_HORIZON * _limits(self.specs)["settling"], 2000)
        step = control.step_response(response, T=t)
        axes[2].plot(step.time, np.asarray(step.outputs).ravel(), label="linear closed loop")
        band = self.specs.band
        for level in (1 - band, 1 + band):
            axes[2].axhline(level, color="0.6", lw=0.6, ls="--")
        axes[2].set_xlabel("time [s]")
        axes[2].set_ylabel("position / step")
        axes[2].grid(True, alpha=0.3)
        axes[2].legend(fontsize=7)
        fig.suptitle("PID designed on the linearised plant", fontsize=10)
        tight_layout(fig)
        return fig


def linear_design(loop: ClosedLoop, specs: Specs | str, *, at: float | None = None,
                  regime: str = "sliding", velocity: float | None = None,
                  inputs: Mapping[str, float] | None = None) -> LinearDesign:
    """A PID for ``loop``'s plant designed on its linearisation (module docstring).

    ``at``: the operating position [m] (default mid-stroke); ``regime``: ``"sliding"``
    (default; at ``velocity`` [m/s], default 20 % of the stroke over the settling spec)
    or ``"presliding"``; ``inputs``: the plant's other declared inputs held at constant
    values there (a cylinder's ``{"load": F}``, as ``linearise`` and ``holding_input``
    take them). The loop's controller must be a ``PID``; its limits and
    anti-windup are kept, its gains replaced. Raises ``ParameterError`` naming the field
    where the loop, the specs or the point do not allow a design."""
    _require_control()
    specs = Specs.of(specs)
    if not isinstance(loop, ClosedLoop) or not isinstance(loop.controller, PID):
        raise ParameterError(f"linear_design: loop = {loop!r}; give a ClosedLoop with a PID "
                             "(the design places Kp, Ki, Kd)")
    if loop.controller.sampled:
        raise ParameterError("linear_design: the loop's PID is sampled (sample_time = "
                             f"{loop.controller.sample_time}); the design is continuous: "
                             "give a continuous PID")
    limits = _limits(specs)
    stroke = float(loop.stroke) if loop.stroke else None
    at = (0.5 * stroke if stroke else 0.0) if at is None else float(at)
    if regime == "sliding" and velocity is None:
        velocity = 0.2 * (stroke or 1e-2) / limits["settling"]
    hold = loop.holding_input(at, inputs=inputs) * loop.drive_gain
    plant = linearise(loop.plant, hold, regime=regime, velocity=velocity, position=at,
                      inputs=inputs)
    sign = loop.action * loop.drive_gain
    zeta = _damping(limits["overshoot"])
    shape = math.sqrt(math.sqrt(1.0 + 4.0 * zeta**4) - 2.0 * zeta**2)
    margin = math.degrees(math.atan(2.0 * zeta / shape))
    target = 4.0 / (zeta * limits["settling"]) * shape
    scaled = _scaled_plant(plant, sign)
    rows = [_candidate(plant, scaled, sign, w, ratio, margin, limits, specs.band)
            for ratio in TI_OVER_TD
            for w in target * np.geomspace(*CROSSOVER_RANGE, CROSSOVER_CANDIDATES)]
    table = pd.DataFrame([r for r in rows if r is not None])
    if table.empty or not table["stable"].any():
        raise ParameterError(
            "linear_design: no PID with T_i = 4..60·T_d nor PD stabilises the linearised "
            f"plant for crossovers {CROSSOVER_RANGE[0] * target:.3g}.."
            f"{CROSSOVER_RANGE[1] * target:.3g} rad/s at {margin:.0f}° phase margin "
            f"({plant.statement})")
    best = _choose(table, target)
    controller = dataclasses.replace(
        loop.controller, kp=best["kp"], ki=best["ki"], kd=best["kd"],
        derivative="measurement", filter_time=best["filter_time"], tracking_time=None)
    predicted = {k: float(best[k]) for k in ("overshoot", "settling_time", "rise_time",
                                             "phase_margin", "gain_margin")}
    predicted["meets_specs"] = float(bool(best["meets_specs"]))
    return LinearDesign(loop=dataclasses.replace(loop, controller=controller), plant=plant,
                        specs=specs, crossover=float(best["crossover"]), phase_margin=margin,
                        predicted=predicted, candidates=table, sign=sign)


# --------------------------------------------------------------------------- the steps
def _require_control():
    try:
        import control
    except ImportError as error:  # pragma: no cover - the test extra has it
        raise ImportError("linear_design needs python-control: pip install "
                          "'pneumact[control]'") from error
    return control


def _limits(specs: Specs) -> dict[str, float]:
    return {"overshoot": DEFAULT_OVERSHOOT if specs.overshoot is None else specs.overshoot,
            "settling": DEFAULT_SETTLING if specs.settling is None else specs.settling}


def _damping(overshoot_percent: float) -> float:
    """ζ of a second-order step with this overshoot [%] (1 for none)."""
    if overshoot_percent <= 0.0:
        return 1.0
    log = math.log(overshoot_percent / 100.0)
    return min(-log / math.sqrt(math.pi**2 + log**2), 1.0)


def _scaled_plant(plant: LinearPlant, sign: float):
    """sign·P(s) as a python-control state space with the states scaled to O(1)
    (pressures in Pa beside positions in m would make its matrices ill-conditioned)."""
    import control

    scales = plant.state_scales if plant.state_scales.size == plant.A.shape[0] else (
        np.ones(plant.A.shape[0]))
    system = control.ss(plant.A, sign * plant.B, plant.C[:1], plant.D[:1])
    return control.similarity_transform(system, np.diag(1.0 / scales))


def _pid_at(response: complex, omega: float, margin_deg: float, ratio: float):
    """Kp, Ki, Kd putting C(jω)·P(jω) at −180° + PM with |L| = 1 (T_i = ratio·T_d); where
    the plant lags less than that needs, the PID lags ``MOST_LAG`` (the margin is
    larger than asked); None where it would need more lead than a PID has."""
    theta = math.radians(-180.0 + margin_deg) - math.atan2(response.imag, response.real)
    theta = math.atan2(math.sin(theta), math.cos(theta))
    if theta < -math.radians(MOST_LAG):  # a plant lagging little: mostly integral action
        theta = -math.radians(MOST_LAG)
    if math.cos(theta) <= 1e-6:
        return None
    kp = math.cos(theta) / abs(response)
    tan = math.tan(theta)
    if math.isinf(ratio):  # a PD: lead only
        return (kp, 0.0, kp * tan / omega, tan / omega / FILTER_RATIO) if tan > 0 else None
    a = 0.5 * (tan + math.sqrt(tan * tan + 4.0 / ratio))  # a = ω·T_d
    td = a / omega
    return kp, kp / (ratio * td), kp * td, td / FILTER_RATIO


def _closed_loop(plant, kp: float, ki: float, kd: float, tf: float):
    """(y/r, the open loop L) for a PID with its derivative on the measurement."""
    import control

    s = control.tf("s")
    reference = kp + ki / s
    feedback = reference + kd * s / (tf * s + 1.0)
    return control.feedback(plant, feedback) * reference, plant * feedback


def _candidate(plant: LinearPlant, scaled, sign: float, omega: float, ratio: float,
               margin: float, limits: dict[str, float], band: float) -> dict | None:
    import control

    response = np.ravel(plant.frequency_response(omega / (2 * math.pi)))[0]
    gains = _pid_at(complex(sign * response), omega, margin, ratio)
    if gains is None:
        return None
    kp, ki, kd, tf = gains
    response, open_loop = _closed_loop(scaled, kp, ki, kd, tf)
    # the loop's own poles (y/r also holds the reference path's integrator, cancelled)
    stable = bool(np.all(np.real(control.poles(control.feedback(open_loop, 1))) < 0.0))
    row = {"crossover": omega, "ti_over_td": ratio, "kp": kp, "ki": ki, "kd": kd, "filter_time": tf,
           "stable": stable, "overshoot": math.nan, "settling_time": math.nan,
           "rise_time": math.nan, "phase_margin": math.nan, "gain_margin": math.nan}
    if stable:
        t = np.linspace(0.0, STEP_HORIZON * limits["settling"], 3000)
        step = np.asarray(control.step_response(response, T=t).outputs).ravel()
        # the step ends at 1 with integral action or a plant's integrator (y/r's dc gain is
        # 0/0 in its realisation); a PD on a plant with a spring never settles there
        gm, pm = control.stability_margins(open_loop)[:2]
        row.update(phase_margin=float(pm), gain_margin=float(gm))
        if not np.max(step) >= 0.9:  # too slow to rise within the horizon
            row.update(overshoot=0.0, settling_time=math.inf, rise_time=math.inf)
            row["within_overshoot"], row["meets_specs"] = True, False
            return row
        info = control.step_info(step, T=t, yfinal=1.0, SettlingTimeThreshold=band)
        settled = info["SettlingTime"] < 0.95 * t[-1]
        row.update(overshoot=float(info["Overshoot"]),
                   settling_time=float(info["SettlingTime"]) if settled else math.inf,
                   rise_time=float(info["RiseTime"]))
    row["within_overshoot"] = bool(stable and row["overshoot"] <= limits["overshoot"])
    row["meets_specs"] = bool(row["within_overshoot"]
                              and row["settling_time"] <= limits["settling"])
    return row


def _choose(table: pd.DataFrame, target: float) -> pd.Series:
    """Among the candidates whose linear step meets the specs, the one nearest the
    specs' ω_c (``target``), the fastest integral action first; failing that, the
    fastest settling within the overshoot spec; failing that, the stable one with the
    least overshoot."""
    meets = table[table["meets_specs"]]
    if not meets.empty:
        distance = np.abs(np.log(meets["crossover"] / target)).round(6)
        order = pd.DataFrame({"d": distance, "r": meets["ti_over_td"]}).sort_values(["d", "r"])
        return meets.loc[order.index[0]]
    fine = table[table["stable"] & table["within_overshoot"]
                 & np.isfinite(table["settling_time"])]
    if not fine.empty:
        return fine.loc[fine["settling_time"].idxmin()]
    stable = table[table["stable"]]
    return stable.loc[stable["overshoot"].idxmin()]
