"""A friction law on its own, compiled over arrays: the numpy side of every law
(``FrictionModel.evaluate`` and ``parameter_derivatives``) runs the law's own compiled
functions through the ``law_alone`` template, so the values tests, plots and analyses see are
those the simulations integrate."""

from __future__ import annotations

from collections import ChainMap
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...core.assembly import Assembly
from ...core.component import Block, Part, StateSpec

if TYPE_CHECKING:
    from .base import FrictionModel

__all__ = ["friction_law_parameter_derivatives", "friction_law_values"]

#: a component of one state and one parameter before the law, so that the law's slice
#: starts at an offset in both vectors (its state's slot carries the velocity and force)
_AHEAD = Part(role="motion", block=Block.of("motion_offset"),
              states=(StateSpec("motion", "m/s"),), label="the slot ahead of the law")


@dataclass(frozen=True, eq=False)
class _Law:
    """A friction law with nothing around it (the ``law_alone`` template)."""

    friction: FrictionModel
    params: Mapping[str, float]
    template = "pneumact.models.friction.law_alone"
    kernel_templates = ("pneumact.models.friction.law_alone",)

    def parts(self) -> tuple[Part, Part]:
        return (_AHEAD, self.friction.part())


def _law_inputs(friction, v, y, params):
    """The law's assembly, v (n,), the whole state vectors (n, 1 + N) from the law's
    states y (n, N) (a scalar or an (n,) array broadcast over the N states) and the packed
    vector."""
    assembly = Assembly(_Law(friction, ChainMap({"motion_offset": 0.0}, params)))
    n_states = len(assembly.states) - 1
    v = np.ascontiguousarray(np.atleast_1d(np.asarray(v, dtype=np.float64)))
    y = np.asarray(y, dtype=np.float64)
    if y.ndim < 2:
        y = np.broadcast_to(y.reshape(-1, 1) if y.ndim == 1 else y, (v.size, n_states))
    if y.shape != (v.size, n_states):
        raise ValueError(f"friction states: shape {y.shape}, expected ({v.size}, "
                         f"{n_states}) for {friction!r}")
    whole = np.zeros((v.size, 1 + n_states))
    whole[:, 1:] = y
    return assembly, v, whole, assembly.pack()


def friction_law_values(friction, v, y, params) -> dict[str, np.ndarray]:
    """The law at arrays ``v`` (n,), ``y`` (n, N): force, rates and partial derivatives
    (see ``FrictionModel.evaluate``)."""
    assembly, v, y, vec = _law_inputs(friction, v, y, params)
    whole = len(assembly.states)
    force, dforce_dv = np.empty(v.size), np.empty(v.size)
    rates, jac = np.zeros((v.size, whole)), np.zeros((v.size, whole, whole))
    assembly.kernel.law_values(v, y, vec, force, dforce_dv, rates, jac)
    return {"force": force, "dforce_dv": dforce_dv, "rates": rates[:, 1:],
            "drates_dv": jac[:, 1:, 0], "drates_dy": jac[:, 1:, 1:],
            "dforce_dy": -jac[:, 0, 1:]}


def friction_law_parameter_derivatives(friction, v, y, params) -> dict[str, np.ndarray]:
    """name -> (n, N + 1) array: ∂ż_i/∂θ of each state, then ∂F/∂θ, for every parameter
    of the law."""
    assembly, v, y, vec = _law_inputs(friction, v, y, params)
    g = np.zeros((v.size, len(assembly.states), assembly.size))
    assembly.kernel.law_parameter_derivatives(v, y, vec, g)
    rows = [*range(1, len(assembly.states)), 0]  # the law's states, then the force
    lo = assembly.block_ranges["friction"][0]
    return {name: g[:, rows, lo + k] for k, name in enumerate(friction.block.names)}
