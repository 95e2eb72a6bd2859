"""Families of plausible actuators, for testing a procedure on more than one set.

A procedure that works on ``vgt-paper`` proves little: ``ActuatorFamily`` draws
actuators from wide, realistic ranges (vacuum diaphragm actuators of VGT, wastegate and
EGR valves, and process-valve positioners), each a consistent ``ParameterSet``:

- geometry: an effective diaphragm diameter of 40-110 mm, a stroke of 10-30 mm, a
  chamber of 1.2-2× the swept volume plus 5-50 cm³ of dead volume, 0.1-1.5 kg moving;
- spring: motion starts at 8-30 kPa of vacuum (F0 = that × A_d), and the stiffness is
  drawn so that the full stroke, against the highest friction, needs at most the
  vacuum the reservoir leaves (p_atm − p_res less a 10 % margin);
- friction (LuGre): Fc 0.5-10 N, Fs/Fc 1.05-2, σ0 1e4-1e6 N/m, σ1 10-1000 N·s/m,
  σ2 0.5-30 N·s/m, vs 0.1-10 mm/s (log-uniform where a range spans decades), δ 1 or 2;
- pneumatics: a reservoir at 10-20 kPa, valve areas of 0.5-3 mm² (an EPC), air at
  293 K, p_atm 100 kPa.

Each set is named ``family-<seed>-<i>``, with every value's source saying it was drawn.

``ActuatorFamily.wide()`` (issue 38) spans more of what is built: diaphragms of
30-250 mm, strokes of 8-50 mm, 0.05-6 kg, Fc 0.3-300 N, Fs/Fc 1.05-2.2, vs 0.05-20 mm/s.
Over such a span friction cannot be drawn apart from the size (300 N on a 30 mm
diaphragm would not move): Fc is drawn log-uniform between 0.1 % and 10 % of the force
the reservoir's vacuum gives (``FRICTION_SHARE``), within the Fc range; σ0 and σ2 are
drawn from their ranges times Fc over the default family's middle Fc (so the presliding
deflection Fs/σ0 and the viscous share σ2·v/Fc keep the default family's spread), σ1
times the square root of that and of the mass over the default's middle mass (the stuck
mode's damping ratio keeps its spread), and the valve areas times the diaphragm's area
over the default's middle area (a larger actuator has a larger positioner valve). Each
set is named ``wide-<seed>-<i>``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .parameter_set import ParameterInfo, ParameterSet, number_text

__all__ = ["ActuatorFamily"]


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


#: A scaled family's Coulomb friction: this share of the force the reservoir's vacuum
#: gives at least and at most (the default family spans 0.07-11 %).
FRICTION_SHARE = (1e-3, 0.1)
#: The default family's middle (geometric for Fc) Coulomb friction [N], mass [kg] and
#: diaphragm area [m²]: a scaled family's σ0, σ1, σ2 and valve areas are relative to them.
REFERENCE_FC = float(np.sqrt(0.5 * 10.0))
REFERENCE_MASS = 0.8
REFERENCE_AREA = float(np.pi * 0.075**2 / 4)


def _scaled(values: dict[str, float]) -> dict[str, float]:
    """A scaled family's friction and valves relative to its size (module docstring)."""
    friction = values["Fc"] / REFERENCE_FC
    size = values["A_d"] / REFERENCE_AREA
    return {**values, "sigma0": values["sigma0"] * friction,
            "sigma2": values["sigma2"] * friction,
            "sigma1": values["sigma1"] * float(np.sqrt(friction * values["m"]
                                                       / REFERENCE_MASS)),
            "A_res": values["A_res"] * size, "A_atm": values["A_atm"] * size}


@dataclass(frozen=True)
class ActuatorFamily:
    """Ranges of a family of actuators (SI); ``draw(n, seed)`` gives ``n`` sets."""

    diameter: tuple[float, float] = (0.040, 0.110)
    stroke: tuple[float, float] = (0.010, 0.030)
    mass: tuple[float, float] = (0.1, 1.5)
    start_vacuum: tuple[float, float] = (8e3, 30e3)
    Fc: tuple[float, float] = (0.5, 10.0)
    static_ratio: tuple[float, float] = (1.05, 2.0)
    sigma0: tuple[float, float] = (1e4, 1e6)
    sigma1: tuple[float, float] = (10.0, 1000.0)
    sigma2: tuple[float, float] = (0.5, 30.0)
    vs: tuple[float, float] = (1e-4, 1e-2)
    deltas: tuple[float, ...] = (1.0, 2.0)
    reservoir: tuple[float, float] = (10e3, 20e3)
    valve_area: tuple[float, float] = (0.5e-6, 3e-6)
    p_atm: float = 1e5
    extra: dict[str, float] = field(default_factory=dict)
    scaled: bool = False  # friction and valves scaled with the size (``wide``)
    label: str = "family"

    @classmethod
    def wide(cls) -> ActuatorFamily:
        """The wider ranges of issue 38, friction and valves scaled with the size."""
        return cls(diameter=(0.030, 0.250), stroke=(0.008, 0.050), mass=(0.05, 6.0),
                   Fc=(0.3, 300.0), static_ratio=(1.05, 2.2), vs=(5e-5, 2e-2),
                   scaled=True, label="wide")

    def draw(self, n: int, seed: int = 0) -> list[ParameterSet]:
        """``n`` actuators, reproducible by ``seed``."""
        rng = np.random.default_rng(seed)
        return [self._one(rng, f"{self.label}-{seed}-{i}") for i in range(n)]

    def _scaled_fc(self, unit: float, available: float) -> float:
        """Fc at ``unit`` (uniform in [0, 1)) of its log range: ``FRICTION_SHARE`` of
        the ``available`` force, within the ``Fc`` range."""
        low = max(self.Fc[0], FRICTION_SHARE[0] * available)
        high = min(self.Fc[1], FRICTION_SHARE[1] * available)
        if high <= low:  # the Fc range misses the share: the share holds (it keeps the
            return float(high if high < self.Fc[0] else low)  # actuator drawable)
        return float(np.exp(np.log(low) + unit * (np.log(high) - np.log(low))))

    def _one(self, rng: np.random.Generator, name: str) -> ParameterSet:
        diameter = rng.uniform(*self.diameter)
        area = np.pi * diameter**2 / 4
        stroke = rng.uniform(*self.stroke)
        fc = rng.uniform() if self.scaled else _log_uniform(rng, *self.Fc)
        static_ratio = rng.uniform(*self.static_ratio)
        p_res = rng.uniform(*self.reservoir)
        available = 0.9 * (self.p_atm - p_res) * area  # force at full vacuum, 10 % margin
        fc = self._scaled_fc(fc, available) if self.scaled else fc
        fs = fc * static_ratio
        f0 = area * rng.uniform(*self.start_vacuum)
        k_max = (available - f0 - fs) / stroke
        k = rng.uniform(0.3, 0.9) * k_max
        swept = area * stroke
        values = {
            "m": rng.uniform(*self.mass), "F0": f0, "k": k, "x_max": stroke,
            "A_d": area, "V0": swept * rng.uniform(1.2, 2.0) + rng.uniform(5e-6, 50e-6),
            "p_atm": self.p_atm, "p_res": p_res, "gamma": 1.4, "R": 287.0, "T": 293.15,
            "A_res": rng.uniform(*self.valve_area), "A_atm": rng.uniform(*self.valve_area),
            "Fc": fc, "Fs": fs, "sigma0": _log_uniform(rng, *self.sigma0),
            "sigma1": _log_uniform(rng, *self.sigma1),
            "sigma2": _log_uniform(rng, *self.sigma2),
            "vs": _log_uniform(rng, *self.vs), "delta": float(rng.choice(self.deltas)),
        }
        if self.scaled:
            values = _scaled(values)
        values.update(self.extra)
        info = {n: ParameterInfo(number_text(n, v), "drawn", f"ActuatorFamily, {name}")
                for n, v in values.items()}
        return ParameterSet(values, name=name, description="an actuator drawn from "
                            "ActuatorFamily", provenance={"source": "ActuatorFamily.draw"},
                            info=info)
