"""The pneumatic half of the model in numbers (paper eqs. 1-5): Φ(r)'s choked limit, the
chamber's volume and time constant along the stroke, and the natural frequencies of the
diaphragm, free and stuck on the bristles. SI in and out.

Choked flow (r ≤ r_c) does not become constant, as the paper writes: Φ does, so the mass
flow A·p_up·sqrt(γ/(R·T))·Φ* stays proportional to the upstream pressure. Emptying the
chamber through the choked reservoir orifice is therefore a first-order decay,
dp/dt = −p/τ with τ(x) = V(x) / (n·A_res·Φ*·sqrt(γ·R·T)) while the diaphragm stands
(V(x) = V0 − A_d·x, n the polytropic index), so the time constant shrinks with the
chamber along the stroke.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["chamber_time_constant", "chamber_volume", "choked_limit", "natural_frequencies"]


def choked_limit(gamma: float = 1.4) -> tuple[float, float]:
    """(critical pressure ratio r_c, choked Φ*) of eq. 4: (2/(γ+1))^(γ/(γ−1)) and
    (2/(γ+1))^((γ+1)/(2(γ−1))); 0.5283 and 0.5787 for air."""
    base = 2.0 / (gamma + 1.0)
    return base ** (gamma / (gamma - 1.0)), base ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))


def chamber_volume(params, x) -> np.ndarray:
    """V(x) = V0 − A_d·x [m³] at positions ``x`` [m]."""
    return params["V0"] - params["A_d"] * np.asarray(x, dtype=float)


def chamber_time_constant(params, x, *, area: float | None = None,
                          exponent: float = 1.0) -> np.ndarray:
    """τ(x) [s] of the chamber emptied through the choked orifice of ``area`` (default
    A_res, the valve fully open to the reservoir) with the diaphragm standing at ``x``
    [m]: V(x) / (n·A·Φ*·sqrt(γ·R·T)), n = ``exponent`` (1 isothermal, γ adiabatic)."""
    area = float(params["A_res"] if area is None else area)
    gamma = float(params["gamma"])
    _, phi = choked_limit(gamma)
    speed = math.sqrt(gamma * float(params["R"]) * float(params["T"]))
    return chamber_volume(params, x) / (exponent * area * phi * speed)


def natural_frequencies(params) -> dict[str, dict[str, float]]:
    """The diaphragm as a mass on springs: per case, the stiffness [N/m], the natural
    frequency [Hz] and the damping ratio. ``free``: on the spring k, damped by σ2 (the
    pressure given, sliding); ``stuck``: held by the bristles, k + σ0, damped by σ1 + σ2;
    ``closed chamber``: free, plus the gas spring n·p·A_d²/V of a closed isothermal
    chamber at rest (p_atm, V0), the stiffest the chamber can add."""
    m = float(params["m"])
    gas = float(params["p_atm"]) * float(params["A_d"]) ** 2 / float(params["V0"])
    cases = {"free": (params["k"], params["sigma2"]),
             "stuck on the bristles": (params["k"] + params["sigma0"],
                                       params["sigma1"] + params["sigma2"]),
             "free, closed chamber": (params["k"] + gas, params["sigma2"])}
    out = {}
    for case, (stiffness, damping) in cases.items():
        stiffness, damping = float(stiffness), float(damping)
        out[case] = {"stiffness": stiffness,
                     "frequency": math.sqrt(stiffness / m) / (2 * math.pi),
                     "damping_ratio": damping / (2 * math.sqrt(stiffness * m))}
    return out
