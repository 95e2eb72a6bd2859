"""A friction law on its own, compiled over arrays: the numpy side of every law
(``FrictionModel.evaluate`` and ``parameter_derivatives``) runs the law's own compiled
functions through the ``law_alone`` template, so the values tests, plots and analyses see are
those the simulations integrate."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...core.assembly import Assembly

if TYPE_CHECKING:
    from ...core.component import Part
    from .base import FrictionModel

__all__ = ["friction_law_parameter_derivatives", "friction_law_values"]


@dataclass(frozen=True, eq=False)
class _Law:
    """A friction law with nothing around it (the ``law_alone`` template)."""

    friction: FrictionModel
    params: Mapping[str, float]
    template = "pneumact.models.friction.law_alone"
    kernel_templates = ("pneumact.models.friction.law_alone",)

    def parts(self) -> tuple[Part]:
        return (self.friction.part(),)


def _law_inputs(friction, v, y, params):
    """The law's assembly, v (n,), its states y (n, N) (a scalar or an (n,) array
    broadcast over the N states) and the packed vector."""
    assembly = Assembly(_Law(friction, params))
    n_states = len(assembly.states)
    v = np.ascontiguousarray(np.atleast_1d(np.asarray(v, dtype=np.float64)))
    y = np.asarray(y, dtype=np.float64)
    if y.ndim < 2:
        y = np.broadcast_to(y.reshape(-1, 1) if y.ndim == 1 else y, (v.size, n_states))
    if y.shape != (v.size, n_states):
        raise ValueError(f"friction states: shape {y.shape}, expected ({v.size}, "
                         f"{n_states}) for {friction!r}")
    return assembly, v, np.array(y, dtype=np.float64, order="C"), assembly.pack()


def friction_law_values(friction, v, y, params) -> dict[str, np.ndarray]:
    """The law at arrays ``v`` (n,), ``y`` (n, N): force, rates and partial derivatives
    (see ``FrictionModel.evaluate``)."""
    assembly, v, y, vec = _law_inputs(friction, v, y, params)
    n = len(assembly.states)
    force, dforce_dv, rates = np.empty(v.size), np.empty(v.size), np.empty((v.size, n))
    jac = np.zeros((v.size, n + 1, n + 1))
    assembly.kernel.law_values(v, y, vec, force, dforce_dv, rates, jac)
    return {"force": force, "dforce_dv": dforce_dv, "rates": rates,
            "drates_dv": jac[:, :n, n], "drates_dy": jac[:, :n, :n],
            "dforce_dy": -jac[:, n, :n]}


def friction_law_parameter_derivatives(friction, v, y, params) -> dict[str, np.ndarray]:
    """name -> (n, N + 1) array: ∂ż_i/∂θ of each state, then ∂F/∂θ, for every parameter
    of the law."""
    assembly, v, y, vec = _law_inputs(friction, v, y, params)
    n = len(assembly.states)
    g = np.zeros((v.size, n + 1, assembly.size))
    assembly.kernel.law_parameter_derivatives(v, y, vec, g)
    return {name: g[:, :, k] for k, name in enumerate(friction.block.names)}
