"""Validation of a model against measured records: error metrics (RMS, max, NRMSE,
fit %, R²), hysteresis-loop measures of model and measurement, residual analysis,
training/test splits, and self-contained HTML reports."""

from .loops import LOOP_MEASURES, compare_loops, loop_measures, reversals
from .metrics import METRIC_NAMES, autocorrelation, error_metrics
from .validate import RecordValidation, TrainTest, Validation, train_test, validate

__all__ = [
    "LOOP_MEASURES",
    "METRIC_NAMES",
    "RecordValidation",
    "TrainTest",
    "Validation",
    "autocorrelation",
    "compare_loops",
    "error_metrics",
    "loop_measures",
    "reversals",
    "train_test",
    "validate",
]
