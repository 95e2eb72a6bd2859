"""Sensitivity analysis (paper section III.A): the one-at-a-time study of eq. 15, and
global methods (Sobol, Morris, RBD-FAST through SALib; standardised regression
coefficients, eq. 14) on any function or on the actuator through the batch engine, and
any of them across operating conditions (cycle period or sliding speed in units of vs,
amplitude, valve)."""

from .along import (
    along_time,
    local_along_time,
    model_signal,
    plot_along_loop,
    plot_along_time,
    plot_convergence,
    sobol_convergence,
)
from .dgsm import dgsm, model_gradient
from .methods import (
    SensitivityWarning,
    StudyResult,
    batch_evaluate,
    model_outputs,
    morris,
    rbd_fast,
    sobol,
    src,
    src_coefficients,
)
from .oat import (
    PAPER_VARIATIONS,
    FrictionCurves,
    OneAtATime,
    friction_velocity,
    one_at_a_time,
)
from .operating import (
    Condition,
    ConditionStudy,
    across_conditions,
    at_speeds,
    conditions,
    where,
)
from .problem import DEFAULT_RANGES, Factor, Problem

__all__ = [
    "DEFAULT_RANGES",
    "PAPER_VARIATIONS",
    "Condition",
    "ConditionStudy",
    "Factor",
    "FrictionCurves",
    "OneAtATime",
    "Problem",
    "SensitivityWarning",
    "StudyResult",
    "across_conditions",
    "along_time",
    "at_speeds",
    "batch_evaluate",
    "conditions",
    "dgsm",
    "friction_velocity",
    "local_along_time",
    "model_gradient",
    "model_outputs",
    "model_signal",
    "morris",
    "one_at_a_time",
    "plot_along_loop",
    "plot_along_time",
    "plot_convergence",
    "rbd_fast",
    "sobol",
    "sobol_convergence",
    "src",
    "src_coefficients",
    "where",
]
