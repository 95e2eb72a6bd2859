"""Closed-loop position control: controllers as components of the compiled loop,
friction compensation, set-point experiments, loop metrics and the linearised plant.

    loop = ClosedLoop(plant, PID(kp=..., ki=..., u_min=..., u_max=..., sample_time=1e-3))
    study = run_loop(loop, pa.SetpointStep(0.004, 0.008, 0.1, 1.0))
    study.metrics.to_pandas(); study.write("step")
    linear = linearise(plant, input_value, regime="presliding"); linear.to_control()
"""

from ..models.controllers import PID, Cascade, Controller, Dither, LuGreObserver, StaticCompensation
from .drives import DriveReplay, control_law_check, drive_plant, replay_drive
from .linear import LinearPlant, frequency_response, linearise, plot_bode
from .loop import ClosedLoop
from .metrics import LoopMetrics, loop_metrics
from .plots import plot_loop
from .study import LoopStudy, canudas_hunting, run_loop

__all__ = [
    "PID", "Cascade", "ClosedLoop", "Controller", "Dither", "DriveReplay", "LinearPlant",
    "LoopMetrics", "LoopStudy", "LuGreObserver", "StaticCompensation", "canudas_hunting",
    "control_law_check", "drive_plant", "frequency_response", "linearise", "loop_metrics",
    "plot_bode", "plot_loop", "replay_drive", "run_loop",
]
