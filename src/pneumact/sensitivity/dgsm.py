"""Derivative-based global sensitivity measures (DGSM) from forward sensitivities.

ν_i = E[(∂y/∂x_i)²] over the factors' distribution (Sobol & Kucherenko 2009); for a
uniform factor on [a_i, b_i] the normalised measure ν_i·(b_i − a_i)²/(π²·Var y) is an
upper bound of its total Sobol index, so a small DGSM proves a parameter unimportant at
the cost of one sensitivity run per sample point (the batch of differences would need
k + 1). The derivatives of the actuator come from ``simulate_sensitivities``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

from .methods import StudyResult
from .problem import Problem

__all__ = ["dgsm", "model_gradient"]

#: values (n × k, SI) -> (outputs n × m, gradients n × m × k)
Gradient = Callable[[np.ndarray], tuple[pd.DataFrame, np.ndarray]]


def dgsm(problem: Problem, gradient: Gradient, n: int = 256, seed: int = 0) -> StudyResult:
    """ν_i, its normalised bound on ST_i, and ν_i scaled by the factor's variance, on a
    Latin hypercube of n points."""
    from SALib.sample import latin

    x = latin.sample(problem.to_salib(), n, seed=seed)
    values = problem.transform(x)
    outputs, grads = gradient(values)
    rows = []
    for m, column in enumerate(outputs.columns):
        variance = float(np.var(outputs[column].to_numpy(float)))
        for j, factor in enumerate(problem.factors):
            nu = float(np.mean(grads[:, m, j] ** 2))
            width = factor.high - factor.low
            bound = nu * width**2 / (np.pi**2 * variance) if variance > 0 else 0.0
            rows.append({"output": column, "parameter": factor.name, "nu": nu,
                         "ST_bound": bound, "nu_scaled": nu * width**2 / 12.0})
    return StudyResult("dgsm", pd.DataFrame(rows),
                       pd.DataFrame(values, columns=problem.names), outputs, {"n": n})


def model_gradient(model, experiment, problem: Problem, signal: str,
                   times: Sequence[float], solver=None) -> Gradient:
    """A ``gradient`` for ``dgsm``: the signal at ``times`` and its forward sensitivities
    to the problem's parameters, one sensitivity run per point."""
    from ..simulation import simulate_sensitivities

    grid = np.asarray(times, dtype=float)

    def gradient(values: np.ndarray):
        outs, grads = [], []
        for row in values:
            sens = simulate_sensitivities(model, experiment, problem.names, solver,
                                          t_eval=grid,
                                          values=dict(zip(problem.names, row, strict=True)))
            outs.append(sens.result[signal])
            grads.append(sens[signal])
        outputs = pd.DataFrame(np.array(outs), columns=[repr(float(t)) for t in grid])
        return outputs, np.array(grads)

    return gradient
