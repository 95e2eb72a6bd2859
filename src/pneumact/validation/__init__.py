"""Validation of a model against measured records: error metrics (RMS, max, NRMSE,
fit %, R²), hysteresis-loop measures of model and measurement, residual analysis,
verdicts that combine them, training/test splits, and self-contained HTML reports."""

from .compare import FrictionComparison, compare_friction_models, friction_rig_for
from .friction import FrictionValidation, friction_across_levels, validate_friction
from .loops import LOOP_MEASURES, compare_loops, loop_measures, reversals
from .metrics import METRIC_NAMES, autocorrelation, error_metrics
from .validate import (
    INPUTS,
    RecordValidation,
    TrainTest,
    Validation,
    drive_for,
    train_test,
    validate,
)
from .verdicts import Criteria

__all__ = [
    "INPUTS",
    "LOOP_MEASURES",
    "METRIC_NAMES",
    "Criteria",
    "FrictionComparison",
    "FrictionValidation",
    "RecordValidation",
    "TrainTest",
    "Validation",
    "autocorrelation",
    "compare_friction_models",
    "compare_loops",
    "drive_for",
    "error_metrics",
    "friction_across_levels",
    "friction_rig_for",
    "loop_measures",
    "reversals",
    "train_test",
    "validate",
    "validate_friction",
]
