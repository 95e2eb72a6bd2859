"""The assembled diaphragm actuator: mechanics (paper eq. 1) + friction + chamber + valve."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..experiments.signals import Signal
from .friction import FrictionModel, LuGre
from .pneumatics import ChamberLaw, Isothermal, orifice_mass_flow
from .valves import CommandValve, PressureRegulator, PressureSource, Valve

MECHANICS = ("m", "F0", "k", "x_max", "k_stop", "c_stop", "A_d", "p_atm")
# What the static-equilibrium start depends on (friction is unloaded at rest).
EQUILIBRIUM_PARAMETERS = frozenset({
    "F0", "k", "x_max", "k_stop", "A_d", "p_atm", "p_res", "A_res", "A_atm", "gamma", "R",
    "T", "r_lin",
})


def rest_position(net0, k, k_stop, x_max):
    """Where the spring (and an end stop) balance the net force ``net0`` [N] that acts at
    x = 0 towards larger x; works elementwise on arrays (the batch engine uses it)."""
    net0, k, k_stop, x_max = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                                   for a in (net0, k, k_stop, x_max)))
    with np.errstate(divide="ignore", invalid="ignore"):
        x_free = np.where(k > 0, net0 / k, np.where(net0 <= 0, 0.0, x_max))
        low = net0 / (k + k_stop)
        high = x_max + (net0 - k * x_max) / (k + k_stop)
    return np.where(x_free <= 0.0, low, np.where(x_free >= x_max, high, x_free))


@dataclass(frozen=True, eq=False)
class Actuator:
    """A spring-return vacuum diaphragm actuator.

    ``friction``, ``valve`` and ``chamber`` are strategy objects; ``load`` is an external
    force F_ext(t) [N] and ``load_map`` a force against position F_ext(x) [N] (both
    oppose motion towards larger x; zero by default).
    """

    params: object
    friction: FrictionModel = field(default_factory=LuGre)
    valve: Valve = field(default_factory=PressureSource)
    chamber: ChamberLaw = field(default_factory=Isothermal)
    load: Signal | None = None
    load_map: Signal | None = None
    model: ClassVar[str] = "actuator"
    initial_state_parameters: ClassVar[frozenset[str]] = EQUILIBRIUM_PARAMETERS

    def __post_init__(self):
        needed = [*MECHANICS, *self.friction.required, *self.valve.required]
        self.params.require(needed, "Actuator")

    # -- what the kernel generator and the integrator need ----------------------------
    @property
    def drive_quantity(self) -> str:
        return self.valve.drive

    def components(self) -> dict[str, str]:
        prefix = self.valve.prefix
        mod = self.valve.module
        return {
            "friction_eval": f"{self.friction.module}:{self.friction.kernel}",
            "friction_dtheta": f"{self.friction.module}:{self.friction.kernel}_dtheta",
            "NSTATE": f"{mod}:{prefix.upper()}_NSTATE",
            "valve_flows": f"{mod}:{prefix}_flows",
            "valve_jac": f"{mod}:{prefix}_jac",
            "valve_pressure": f"{mod}:{prefix}_pressure",
            "valve_rhs": f"{mod}:{prefix}_rhs",
        }

    def kernel_key(self) -> str:
        return f"actuator_{self.friction.kernel}_{self.valve.prefix}"

    def vector(self, params=None) -> np.ndarray:
        params = self.params if params is None else params
        return params.vector(polytropic_index=self.chamber.polytropic_index(params))

    def channels(self, drive: Signal) -> list[Signal | None]:
        res_map, atm_map = self.valve.maps()
        return [drive, self.load, self.load_map, res_map, atm_map]

    def state_scales(self, prm: np.ndarray) -> np.ndarray:
        """Typical magnitude of each state, for default absolute tolerances."""
        p = self.params
        bristle = p["Fs"] / p["sigma0"] if "sigma0" in self.friction.required else 1e-5
        scales = np.array([p["x_max"], p["x_max"] * 10.0, bristle, p["p_atm"], 1.0, 1.0])
        return scales[: self.valve.nstate]

    # -- initial state: static equilibrium ---------------------------------------------
    def initial_state(self, drive: Signal, t0: float) -> np.ndarray:
        """Rest at the static equilibrium of the initial input (friction unloaded)."""
        p = self.params
        y0 = np.zeros(self.valve.nstate)
        u0 = 0.0
        if isinstance(self.valve, PressureSource):
            p0 = float(drive(t0))
        elif isinstance(self.valve, PressureRegulator):
            p0 = float(np.clip(drive(t0), p["p_res"], p["p_atm"]))
            u0 = self._opening_for(p0)
        else:
            u0 = float(np.clip(drive(t0), 0.0, 1.0))
            p0 = self._equilibrium_pressure(u0)
        net0 = (p["p_atm"] - p0) * p["A_d"] - p["F0"]
        if self.load is not None:
            net0 -= float(self.load(t0))
        x0 = self._rest_position(net0)
        if self.load_map is not None:  # a position-dependent load: a few fixed-point steps
            for _ in range(20):
                x0 = self._rest_position(net0 - float(self.load_map(x0)))
        y0[0] = x0
        if self.valve.nstate > 3:
            y0[3] = p0
        if self.valve.nstate > 4:
            y0[4] = u0
            y0[5] = u0
        return y0

    def _rest_position(self, net0: float) -> float:
        p = self.params
        return float(rest_position(net0, p["k"], p["k_stop"], p["x_max"]))

    def _net_flow(self, pressure: float, u: float) -> float:
        p = self.params
        res_map, atm_map = self.valve.maps()
        a_res = p["A_res"] * float(res_map(u))
        a_atm = p["A_atm"] * float(atm_map(u))
        prm = self.vector()
        q_in = orifice_mass_flow(p["p_atm"], pressure, a_atm, prm)[0]
        q_out = orifice_mass_flow(pressure, p["p_res"], a_res, prm)[0]
        return q_in - q_out

    def _equilibrium_pressure(self, u: float) -> float:
        from scipy.optimize import brentq

        p = self.params
        lo, hi = p["p_res"], p["p_atm"]
        f_lo, f_hi = self._net_flow(lo, u), self._net_flow(hi, u)
        if f_lo <= 0.0:
            return lo
        if f_hi >= 0.0:
            return hi
        return float(brentq(self._net_flow, lo, hi, args=(u,), xtol=1e-6))

    def _opening_for(self, pressure: float) -> float:
        from scipy.optimize import brentq

        f0, f1 = self._net_flow(pressure, 0.0), self._net_flow(pressure, 1.0)
        if f0 <= 0.0:
            return 0.0
        if f1 >= 0.0:
            return 1.0
        return float(brentq(lambda u: self._net_flow(pressure, u), 0.0, 1.0, xtol=1e-10))

    def describe(self) -> str:
        return (f"Actuator(friction={self.friction!r}, valve={self.valve.name}, "
                f"chamber={type(self.chamber).__name__})")


__all__ = ["Actuator", "CommandValve", "PressureRegulator", "PressureSource"]
