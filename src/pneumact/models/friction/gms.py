"""Generalized Maxwell-slip friction (Al-Bender, Lampaert & Swevers, "The generalized
Maxwell-slip model: a novel model for friction simulation and compensation", IEEE TAC
50(11), 1883-1887, 2005): N elementary blocks in parallel, a hybrid model with one
stick/slip mode per block.

Block i is a spring of stiffness kᵢ and deflection zᵢ (force Fᵢ = kᵢ·zᵢ) with the mode
mᵢ ∈ {0: stuck, +1: slipping forward, −1: slipping backward}:

- stuck:    dzᵢ/dt = v (the block follows the motion);
- slipping: dFᵢ/dt = C·(mᵢ·νᵢ − Fᵢ/g(v)), i.e. dzᵢ/dt = (C/kᵢ)·(mᵢ·νᵢ − kᵢ·zᵢ/g(v)):
  the paper's sgn(v)·C·(νᵢ − Fᵢ/s(v)) with the signed Stribeck curve s(v) = sgn(v)·g(v)
  and the slip direction mᵢ in place of sgn(v), which it equals while the block slips;
- F = Σ (kᵢ·zᵢ + bᵢ·dzᵢ/dt) + σ2·v, with bᵢ = σ1·kᵢ/Σk (the micro-damping σ1 shared as
  the stiffness is), g(v) = Fc + (Fs − Fc)·e^(−(|v|/vs)^δ).

A stuck block starts to slip, in the direction of the motion, when its force reaches
its share of the Stribeck curve: kᵢ·|zᵢ| = νᵢ·g(v) with sgn(zᵢ) = sgn(v). A slipping
block sticks again only when the velocity reverses (mᵢ·v reaches 0). The shares are
normalised, threshold νᵢ·g(v)/Σν, so that the blocks slide together at F = g(v) + σ2·v;
a set gives them summing to 1.

The modes are states the integrator holds between events: it locates each switch (the
zero of its guard function, ``event_guards``) on the step's interpolant, ends the step
there and switches the block (``event_switch``), so a block keeps its mode exactly as
long as the paper says. Testing the threshold at every evaluation instead, as two open
implementations do, makes a slipping block whose force falls below its threshold stick
again without a reversal, and loses the non-local memory the model exists for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...core.component import Block, StateSpec
from ...core.jit import njit
from ...parameters.catalogue import ParameterSpec, declare
from .base import RELAXED_LEVEL, FrictionModel, sign, stribeck_level

#: the most blocks a GMS law may have (each declares its stiffness and share)
MAX_ELEMENTS = 8
#: the integrator locates the stick/slip switches (see ``core.integrators``)
HAS_EVENTS = True

P = ParameterSpec
declare(P("gms_C", "N/s", "GMS attraction parameter: the rate at which a slipping block's "
          "force approaches its share of the Stribeck curve", None, 0.0, True, 1e12,
          group="friction", plausible=(1e-3, 1e9)))
for _i in range(1, MAX_ELEMENTS + 1):
    declare(P(f"gms_k{_i}", "N/m", f"GMS block {_i}: stiffness", None, 0.0, True, 1e12,
              group="friction", plausible=(1.0, 1e10)),
            P(f"gms_nu{_i}", "", f"GMS block {_i}: share of the Stribeck curve it carries "
              "when slipping (the shares sum to 1)", None, 0.0, True, 1.0, group="friction"))

#: the entries of a GMS block before the blocks' stiffnesses and shares
COMMON = ("sigma1", "sigma2", "Fc", "Fs", "vs", "delta", "gms_C")
GMS_SIGMA1, GMS_SIGMA2, GMS_FC, GMS_FS, GMS_VS, GMS_DELTA, GMS_C = range(len(COMMON))
GMS_COMMON = len(COMMON)


def element_names(n_elements: int) -> tuple[str, ...]:
    """The block's parameters: the common ones, then k1..kN, then nu1..nuN."""
    return (*COMMON, *(f"gms_k{i}" for i in range(1, n_elements + 1)),
            *(f"gms_nu{i}" for i in range(1, n_elements + 1)))


@njit(cache=True)
def share_sum(p, o, n):  # pragma: no cover - compiled
    """Σν over the n blocks of the law at offset o."""
    total = 0.0
    for i in range(n):
        total += p[o + GMS_COMMON + n + i]
    return total


@njit(cache=True)
def threshold(p, o, n, i, level):  # pragma: no cover - compiled
    """Block i's slip force νᵢ·g/Σν at the Stribeck level g."""
    return p[o + GMS_COMMON + n + i] * level / share_sum(p, o, n)


@njit(cache=True)
def element_rate(v, z, mode, k, c, share, level):  # pragma: no cover - compiled
    """dz/dt of one block and its derivatives in v (through g: the caller multiplies by
    dg/dv) and z: (ż, ∂ż/∂g, ∂ż/∂z); ``share`` is νᵢ/Σν. The mode's sign is the slip
    direction (a held state, only ever 0 or ±1 in a run)."""
    if mode == 0.0:
        return v, 0.0, 0.0
    return c / k * (sign(mode) * share) - c * z / level, c * z / (level * level), -c / level


@njit(cache=True)
def guard(v, z, mode, k, limit):  # pragma: no cover - compiled
    """> 0 while block keeps its mode; 0 where it switches: a stuck block's margin to
    its slip force (loading it: sgn(z) = sgn(v)), a slipping block's velocity in its
    direction of slip."""
    if mode != 0.0:
        return sign(mode) * v
    if z * v > 0.0:
        return limit - k * abs(z)
    return limit if limit > 0.0 else 1.0


@dataclass(frozen=True, eq=False)
class GMS(FrictionModel):
    """Generalized Maxwell-slip friction with ``n_elements`` blocks (Al-Bender et al.
    2005): presliding hysteresis with non-local memory, N knees on the virgin curve.
    A set carries the blocks' stiffnesses gms_k1..N, their shares gms_nu1..N and the
    attraction parameter gms_C (``GMS.matched_values`` proposes them from a LuGre set)."""

    n_elements: int = 4
    cli_name: ClassVar[str] = "gms"
    sensitivity_refusal: ClassVar[str | None] = (
        "the GMS stick/slip switches are state events: a sensitivity crossing one jumps by "
        "the saltation term (f⁻ − f⁺)·dτ/dθ, which the integrator does not apply yet")
    template: ClassVar[str] = "pneumact.models.friction.gms_law"
    placed_alone: ClassVar[str | None] = (
        "its stick/slip switches are the model's events (event_guards, event_switch), "
        "which one law alone defines")

    def comparison_parameters(self) -> tuple[str, ...]:
        """The blocks' stiffnesses, C and the Stribeck curve; the shares νᵢ stay as set
        (normalised to Σν = 1, one of them is redundant; N shares beside N stiffnesses are
        more than any record of one law's loops tells apart)."""
        return tuple(n for n in super().comparison_parameters() if not n.startswith("gms_nu"))

    def __post_init__(self):
        from ...checks import check_int

        check_int("n_elements", self.n_elements, where="GMS", minimum=1,
                  maximum=MAX_ELEMENTS)

    @property
    def block(self) -> Block:  # type: ignore[override]
        return Block.of(*element_names(self.n_elements))

    @property
    def states(self) -> tuple[StateSpec, ...]:  # type: ignore[override]
        n = range(1, self.n_elements + 1)
        return (*(StateSpec(f"gms_z{i}", "m") for i in n),
                *(StateSpec(f"gms_mode{i}", "1") for i in n))

    @property
    def law(self) -> str:  # type: ignore[override]
        return f"gms{self.n_elements}"

    def functions(self) -> dict[str, str]:
        return {}

    def part(self):
        part = super().part()
        from dataclasses import replace

        return replace(part, constants={"HAS_EVENTS": f"{__name__}:HAS_EVENTS"})

    # -- the numpy side -------------------------------------------------------------------
    def _elements(self, params) -> tuple[np.ndarray, np.ndarray]:
        n = range(1, self.n_elements + 1)
        k = np.array([params[f"gms_k{i}"] for i in n], dtype=float)
        nu = np.array([params[f"gms_nu{i}"] for i in n], dtype=float)
        return k, nu / nu.sum()

    def steady_states(self, v, params) -> np.ndarray:
        """Every block slipping in the direction of v at its share of g(v)."""
        v = np.atleast_1d(np.asarray(v, dtype=float))
        k, share = self._elements(params)
        direction = np.sign(v)[:, None]
        z = direction * share[None, :] * stribeck_level(v, params)[:, None] / k[None, :]
        return np.hstack([z, np.broadcast_to(direction, z.shape)])

    def presliding_stiffness(self, params) -> float:
        return float(self._elements(params)[0].sum())

    def presliding_range(self, params) -> float:
        """The largest block's break-away deflection νᵢ·Fs/kᵢ: the last knee."""
        k, share = self._elements(params)
        level = max(float(params["Fs"]), float(params["Fc"]))
        return float(np.max(share * (level if level > 0.0 else 1.0) / k))

    def relaxation_length(self, v, params) -> np.ndarray:
        """The last block's break-away deflection, or the distance slid in one time
        constant g(v)/C of a slipping block's force (it relaxes in time, not distance),
        whichever is longer."""
        speed = np.abs(np.atleast_1d(np.asarray(v, float)))
        sliding = speed * stribeck_level(speed, params) / float(params["gms_C"])
        return np.maximum(self.break_away_deflections(params).max(), sliding)

    def break_away_deflections(self, params) -> np.ndarray:
        """Where each block starts to slip on the virgin curve from rest: νᵢ·Fs/(Σν·kᵢ)."""
        k, share = self._elements(params)
        return share * max(float(params["Fs"]), float(params["Fc"])) / k

    def matched_values(self, params) -> dict[str, float]:
        """Block values that match a LuGre set's presliding stiffness σ0 and its
        Stribeck curve: equal shares 1/N, stiffnesses kᵢ ∝ N + 1 − i summing to σ0 (so the
        blocks break away one after another: N knees, the last at (N + 1)/2·Fs/σ0), and
        C = σ0·vs (a slipping block relaxes as fast as LuGre's bristle at the Stribeck
        speed). A starting point to fit from, not a measurement."""
        n = self.n_elements
        weights = np.arange(n, 0, -1, dtype=float)
        weights /= weights.sum()
        values = {"gms_C": float(params["sigma0"] * params["vs"])}
        for i in range(n):
            values[f"gms_k{i + 1}"] = float(params["sigma0"] * weights[i])
            values[f"gms_nu{i + 1}"] = 1.0 / n
        return values

    def __repr__(self) -> str:
        return f"GMS(n_elements={self.n_elements})"

    @property
    def spec(self) -> str:
        return f"gms:{self.n_elements}"


__all__ = ["GMS", "MAX_ELEMENTS", "RELAXED_LEVEL", "element_names"]
