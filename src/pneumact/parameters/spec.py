"""The catalogue of every parameter pneumact knows: name, SI unit, meaning, default.

The order of ``PARAMETERS`` fixes the layout of the parameter vector handed to the
compiled kernels (``INDEX[name]``); models read values only through these indices, so
equations hold no numbers. Parameters with ``default=None`` must come from a parameter
set whenever a model needs them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter: SI unit (a pint expression), meaning, default and allowed range."""

    name: str
    unit: str
    description: str
    default: float | None = None
    minimum: float | None = None  # inclusive lower bound
    strict_minimum: bool = False  # True: value must be > minimum
    maximum: float | None = None  # inclusive upper bound
    group: str = "misc"


P = ParameterSpec

PARAMETERS: tuple[ParameterSpec, ...] = (
    # --- mechanics (paper eq. 1)
    P("m", "kg", "moving mass (diaphragm, rod, linkage)", None, 0.0, True, group="mechanics"),
    P("F0", "N", "spring preload at the rest stop", None, 0.0, group="mechanics"),
    P("k", "N/m", "spring (+ membrane) stiffness", None, 0.0, group="mechanics"),
    P("x_max", "m", "stroke: position of the far end stop", None, 0.0, True, group="mechanics"),
    P("k_stop", "N/m", "end-stop contact stiffness (penalty)", 1e8, 0.0, True, group="mechanics"),
    P("c_stop", "N*s/m", "end-stop contact damping (compression only)", 5e3, 0.0,
      group="mechanics"),
    # --- friction (paper eqs. 6-8 and the other models behind the same interface)
    P("sigma0", "N/m", "bristle stiffness", None, 0.0, True, group="friction"),
    P("sigma1", "N*s/m", "bristle (micro-)damping", 0.0, 0.0, group="friction"),
    P("sigma2", "N*s/m", "viscous friction coefficient (the only viscous term)", 0.0, 0.0,
      group="friction"),
    P("Fc", "N", "Coulomb friction force", None, 0.0, group="friction"),
    P("Fs", "N", "static (break-away) friction force, Fs >= Fc", None, 0.0, group="friction"),
    P("vs", "m/s", "Stribeck velocity", None, 0.0, True, group="friction"),
    P("delta", "", "Stribeck exponent (paper eq. 8: 1; usual LuGre: 2)", 2.0, 0.0, True,
      group="friction"),
    P("v_reg", "m/s", "sign regularisation velocity of the static friction maps", 1e-4, 0.0,
      True, group="friction"),
    P("dahl_alpha", "", "Dahl shape exponent", 1.0, 0.0, True, group="friction"),
    P("bw_beta", "", "Bouc-Wen shape parameter beta", 0.5, 0.0, True, group="friction"),
    P("bw_gamma", "", "Bouc-Wen shape parameter gamma (-beta <= gamma <= beta)", 0.5,
      group="friction"),
    P("bw_n", "", "Bouc-Wen exponent n", 1.0, 0.0, True, group="friction"),
    # --- pneumatics (paper eqs. 2-5)
    P("A_d", "m^2", "effective diaphragm area", None, 0.0, True, group="pneumatics"),
    P("V0", "m^3", "chamber volume at the rest stop (x = 0)", None, 0.0, True,
      group="pneumatics"),
    P("p_atm", "Pa", "atmospheric pressure (absolute)", None, 0.0, True, group="pneumatics"),
    P("p_res", "Pa", "vacuum reservoir pressure (absolute), below p_atm", None, 0.0,
      group="pneumatics"),
    P("gamma", "", "ratio of specific heats of air", 1.4, 1.0, True, group="pneumatics"),
    P("R", "J/(kg*K)", "specific gas constant of air", 287.0, 0.0, True, group="pneumatics"),
    P("T", "K", "gas temperature (upstream and chamber)", 293.15, 0.0, True,
      group="pneumatics"),
    P("r_lin", "", "pressure ratio where the orifice flow turns linear (laminar branch)",
      0.999, 0.53, True, 1.0, group="pneumatics"),
    # --- valve / pressure regulator (the paper's EPC)
    P("A_res", "m^2", "max effective area chamber -> vacuum reservoir", None, 0.0,
      group="valve"),
    P("A_atm", "m^2", "max effective area atmosphere -> chamber", None, 0.0, group="valve"),
    P("reg_kp", "", "regulator gain: valve opening per unit of (p - p_set)/p_atm", 20.0, 0.0,
      group="valve"),
    P("reg_ti", "s", "regulator integral time", 0.05, 0.0, True, group="valve"),
    P("reg_tau", "s", "valve (spool) time constant", 0.01, 0.0, True, group="valve"),
    # --- friction test rig (Canudas de Wit et al. 1995)
    P("k_drive", "N/m", "stiffness of the spring that pulls the rig mass (stick-slip)", 2.0,
      0.0, True, group="rig"),
    P("v_drive", "m/s", "pulling speed of the stick-slip rig", 0.1, group="rig"),
)

INDEX: dict[str, int] = {p.name: i for i, p in enumerate(PARAMETERS)}
SPECS: dict[str, ParameterSpec] = {p.name: p for p in PARAMETERS}
N_PARAMETERS: int = len(PARAMETERS)
# Slot after the named parameters: the polytropic index n of the chamber law. It is set
# by the chamber-law strategy (isothermal 1, adiabatic gamma), not by a parameter file.
I_POLYTROPIC: int = N_PARAMETERS
# Slots after that hold constants derived from the parameters (orifice-flow constants),
# filled inside the kernels at the start of every run so they always match the values.
I_DERIVED: int = N_PARAMETERS + 1
N_DERIVED: int = 4
VECTOR_LENGTH: int = N_PARAMETERS + 1 + N_DERIVED
