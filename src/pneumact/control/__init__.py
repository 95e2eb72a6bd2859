"""Closed-loop position control: controllers as components of the compiled loop,
friction compensation, set-point experiments, loop metrics and the linearised plant.

    loop = ClosedLoop(plant, PID(kp=..., ki=..., u_min=..., u_max=..., sample_time=1e-3))
    study = run_loop(loop, pa.SetpointStep(0.004, 0.008, 0.1, 1.0))
    study.metrics.to_pandas(); study.write("step")
    linear = linearise(plant, input_value, regime="presliding"); linear.to_control()
    tuned = tune(loop, "settling=0.3,overshoot=5%,error=20um,no-hunting", uncertainty=fit)
    linear = linear_design(loop, specs); compare_designs(loop, specs, friction_designs(linear))
"""

from ..models.controllers import PID, Cascade, Controller, Dither, LuGreObserver, StaticCompensation
from .comparison import DesignComparison, compare_designs, friction_designs
from .drives import DriveReplay, control_law_check, drive_plant, replay_drive
from .linear import LinearPlant, frequency_response, linearise, plot_bode
from .linear_design import LinearDesign, linear_design
from .loop import ClosedLoop
from .metrics import LoopMetrics, loop_metrics, step_metric_gradients, step_metrics
from .plots import plot_loop
from .specs import Move, Specs, default_moves
from .study import LoopStudy, canudas_hunting, run_loop
from .tuning import TuningResult, draw_samples, evaluate_design, load_gains, tune, write_gains

__all__ = [
    "PID",
    "Cascade",
    "ClosedLoop",
    "Controller",
    "DesignComparison",
    "Dither",
    "DriveReplay",
    "LinearDesign",
    "LinearPlant",
    "LoopMetrics",
    "LoopStudy",
    "LuGreObserver",
    "Move",
    "Specs",
    "StaticCompensation",
    "TuningResult",
    "canudas_hunting",
    "compare_designs",
    "control_law_check",
    "default_moves",
    "draw_samples",
    "drive_plant",
    "evaluate_design",
    "frequency_response",
    "friction_designs",
    "linear_design",
    "linearise",
    "load_gains",
    "loop_metrics",
    "plot_bode",
    "plot_loop",
    "replay_drive",
    "run_loop",
    "step_metric_gradients",
    "step_metrics",
    "tune",
    "write_gains",
]
