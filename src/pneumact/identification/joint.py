"""The joint refinement: every spring and friction parameter fitted to every record at once.

The staged procedure passes each stage's errors on to the next unchecked (a k off by
0.1 % is 0.13 N of friction at 10 mm). After it, one output-error fit of all of them over
all records, started at the staged estimates, settles them together; its estimates are
the identification's result.

Each record drives the model the way it was made (``bench_model``): a record that logged
its regulator's set-point drives the actuator behind that regulator (the set-point is
commanded, so exact, and the chamber's damping is in the model as on the bench); a
record of the chamber pressure alone (the presliding test's fast steps) drives it
through an ideal pressure source, with its input rebuilt piecewise linear. Presliding
records are fitted after their approach to the stop, with a sensor offset of their own
(the stuck position remembers the approach), exactly as stage (d) does.

The fit runs at a tight tolerance (``JOINT_RTOL``): at 1e-6 the integration error alone
biased σ1 by two standard errors of the vgt-paper campaign. A record driven by a noisy
measured input gets a weight from its whole noise, the sensor's and what the input's
noise does to the output (``uncertainty.input_noise_weights``): with equal weights, a
presliding test whose steps are hardly above the pressure sensor's noise pulled Fc, σ2
and vs of a drawn actuator by tens of their standard errors.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..io.records import Record
from .fit import FitResult, fit
from .stages import presliding_window

__all__ = ["JOINT_RTOL", "MAX_EVALUATIONS", "SPRING_AND_FRICTION", "bench_model",
           "joint_refinement"]

#: Tolerance of the joint fit's simulations (see the module docstring).
JOINT_RTOL = 1e-8
#: The joint fit gives up after this many evaluations (each a simulation of every record):
#: started at the staged estimates it converges in 5-20; one that wanders longer has
#: found no optimum the records support, and says so.
MAX_EVALUATIONS = 40
#: What the joint refinement fits (δ too when asked).
SPRING_AND_FRICTION = ("F0", "k", "Fc", "sigma2", "Fs", "vs", "sigma0", "sigma1")


def bench_model(record: Record, params, friction=None, chamber=None):
    """The actuator as the bench drove it for ``record``: behind the pressure regulator
    when the record logged its set-point, else under its measured chamber pressure."""
    from ..models import Actuator, Isothermal, LuGre, PressureRegulator, PressureSource

    friction = LuGre() if friction is None else friction
    if "setpoint" in record:
        return Actuator(params, friction=friction, valve=PressureRegulator(),
                        chamber=Isothermal() if chamber is None else chamber)
    return Actuator(params, friction=friction, valve=PressureSource())


def joint_refinement(records: Sequence[Record], kinds: Sequence[str], params, *,
                     friction=None, chamber=None, free: Sequence[str] = SPRING_AND_FRICTION,
                     solver=None, replicates: int | None = None, seed: int = 0,
                     workers: int | None = None, max_evaluations: int = MAX_EVALUATIONS,
                     progress: Callable[[str, float], None] | None = None) -> FitResult:
    """Fit ``free`` to all ``records`` at once from the values of ``params`` (the staged
    estimates); ``kinds`` says which records are presliding tests. Each record's weight
    counts the noise of its measured input as well as its sensor's
    (``uncertainty.input_noise_weights``, ``replicates`` runs at the staged values)."""
    from ..simulation import Rodas4
    from .uncertainty import INPUT_REPLICATES, input_noise_weights

    solver = Rodas4(rtol=JOINT_RTOL) if solver is None else solver
    models, windows, offset_records = [], [], []
    for i, (record, kind) in enumerate(zip(records, kinds, strict=True)):
        model = bench_model(record, params, friction, chamber)
        models.append(model)
        if kind == "presliding" and "setpoint" not in record:
            windows.append((presliding_window(record, params), float(record.time[-1])))
            offset_records.append(i)
        else:
            windows.append(None)
    masks = [np.ones(r.time.size, bool) if w is None else (r.time >= w[0]) & (r.time <= w[1])
             for r, w in zip(records, windows, strict=True)]
    values = dict(params.values)
    weights = input_noise_weights(models, list(records), values, masks,
                                  replicates=replicates or INPUT_REPLICATES, seed=seed,
                                  solver=solver, workers=workers)
    return fit(models, list(records), list(free), window=windows,
               offsets=["position"] if offset_records else (),
               offset_records=offset_records, solver=solver, record_weights=weights,
               max_nfev=max_evaluations, progress=progress)
