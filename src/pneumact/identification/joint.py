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

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import DataError, SolverError
from ..io.records import Record
from ..models.sensors import Sensors
from ..options import Bounds, Executor, Offsets, Optimizer, Weights
from ..progress import ProgressCallback, notify
from .bench import typical_speed
from .fit import SENSOR_LAGS, FitResult, fit
from .memo import remembered
from .optima import (
    RESTART_GAIN,
    RESTART_RETURNS,
    RESTART_SPREAD,
    spread_starts,
    stuck_reason,
)
from .stages import PRIOR_FACTOR, prior_bounds, settled_part, within

__all__ = ["ADMIT_RATIO", "CHAOS_AMPLIFICATION", "JOINT_RTOL", "MAX_EVALUATIONS", "MAX_ROUNDS",
           "SPRING_AND_FRICTION", "amplification", "bench_model", "feasible",
           "joint_refinement", "prediction_ratio", "refit_without", "restart_at_bounds",
           "stuck_at_bounds"]

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


#: A record whose position moves by more than this many times its own travel for a unit
#: relative change of a parameter (|θ·∂x/∂θ| / travel) is chaotic in the parameters: a
#: stick-slip whose slips the forward sensitivities amplify without bound (measured
#: 1e13-1e18 on drawn actuators that stick-slip below vs, against 0.1-3 for records that
#: slide steadily). Output error cannot follow it sample by sample.
CHAOS_AMPLIFICATION = 1e3


#: The joint fit needs at least this many sweeps or ramps that are not chaotic.
MIN_RECORDS = 3
#: A record joins the joint fit once the model fitted so far predicts it within this many
#: sensor-noise deviations (RMS): farther off, it is in another dynamic regime at the
#: current estimate (stick-slip against steady sliding), and including it would pull
#: the fit into a local optimum (measured 70-130× on such records, 0.9-3× on records a
#: nearby estimate follows).
ADMIT_RATIO = 10.0
#: Rounds of admission before the records still waiting are left out.
MAX_ROUNDS = 4
#: More than this share of the records left out, and the joint fit is not a fit of the
#: campaign any more: it is refused.
MAX_EXCLUDED_SHARE = 1 / 3


def amplification(model, record: Record, params, free: Sequence[str], solver) -> float:
    """max over the parameters and the samples of |θ·∂x/∂θ| / the record's travel, from
    the forward sensitivities at ``params`` (see ``CHAOS_AMPLIFICATION``; within
    ``memo.remembering`` the fit that starts at ``params`` reuses them)."""
    from ..core.assembly import assemble
    from .fit import experiment_for, rebuilt_input
    from .memo import sensitivities

    assembly = assemble(model)
    names = [n for n in free if n in assembly.parameter_names]
    values = {n: params[n] for n in names}
    every = {n: v for n, v in assembly.values(assembly.pack()).items()
             if n in assembly.parameter_names}
    try:
        sens = sensitivities(model, experiment_for(model, record, smooth=True),
                             rebuilt_input(model, record), record.time, names, solver, every)
    except SolverError:
        return np.inf
    travel = max(float(np.ptp(record["position"])), 1e-12)
    scaled = np.abs(sens["position"] * np.array([values[n] for n in names])[None, :])
    return float(np.nanmax(scaled) / travel) if np.all(np.isfinite(scaled)) else np.inf


@remembered  # the screens' and the rounds' runs, reused (``memo``)
def joint_refinement(records: Sequence[Record], kinds: Sequence[str], params, *,
                     friction=None, chamber=None, free: Sequence[str] = SPRING_AND_FRICTION,
                     solver=None, replicates: int | None = None, seed: int = 0,
                     executor: Executor | int | None = None,
                     max_evaluations: int = MAX_EVALUATIONS,
                     prior=None, drop_chaotic: bool = True, excluded: list | None = None,
                     partial: bool = False,
                     progress: ProgressCallback | None = None) -> FitResult:
    """Fit ``free`` to all ``records`` at once from the values of ``params`` (the staged
    estimates), within ``stages.prior_bounds`` of ``prior`` (default ``params``);
    ``kinds`` says which records are presliding tests.

    - Continuation in the data: first the sweeps and the fastest third of the ramps
      (steady sliding: a smooth cost, one optimum), then, round after round, every
      record the model fitted so far predicts within ``ADMIT_RATIO`` noise deviations,
      refitted from where the last round stopped. Started on all records at once, slow
      ramps in another regime at the staged values (stick-slip instead of steady
      sliding, or the reverse) make the cost rugged and the fit stops in a local
      optimum (measured on drawn actuators: costs 7× the truth's, or 100× the noise on
      records the truth fits to 0.86×). A record never admitted is left out, and its
      name appended to ``excluded``. More than ``MAX_EXCLUDED_SHARE`` of the records
      left out refuses the fit (a DataError), unless ``partial``: then the fit of the
      records it follows is returned, for verdicts that refuse what rests on the others
      (a slow ramp's Fs and vs, a presliding test's σ0 and σ1).
    - Each record's weight counts the noise of its measured input as well as its
      sensor's (``uncertainty.input_noise_weights``, ``replicates`` runs).
    - With ``drop_chaotic`` a record whose motion is chaotic in the parameters at the
      start of a round (``amplification`` above ``CHAOS_AMPLIFICATION``) is left out.
    """
    excluded = [] if excluded is None else excluded
    workers = Executor.of(executor, "joint_refinement").workers
    options = dict(friction=friction, chamber=chamber, free=free, solver=solver,
                   replicates=replicates, seed=seed, workers=workers,
                   max_evaluations=max_evaluations, prior=params if prior is None else prior,
                   drop_chaotic=drop_chaotic)
    ramps = sorted((i for i, k in enumerate(kinds) if k == "ramp"),
                   key=lambda i: typical_speed(records[i]), reverse=True)
    used = sorted([i for i, k in enumerate(kinds) if k == "sweep"]
                  + ramps[: max(MIN_RECORDS, len(ramps) // 3)])
    result: FitResult | None = None
    chaotic: list[str] = []
    options.update(screened=set(), weights={})
    for round_ in range(MAX_ROUNDS):
        notify(progress, f"joint refinement: {len(used)} of {len(records)} records",
               len(used), len(records))
        result = _fit_records([records[i] for i in used], [kinds[i] for i in used], params,
                              excluded=chaotic, **options)
        used = [i for i in used if records[i].source not in chaotic]
        params = params.with_values(feasible(result.values, params))
        waiting = [i for i in range(len(records))
                   if i not in used and records[i].source not in chaotic]
        admitted = [i for i in waiting if prediction_ratio(
            records[i], kinds[i], params, friction, chamber, solver) <= ADMIT_RATIO]
        if not admitted or round_ == MAX_ROUNDS - 1:
            excluded.extend(chaotic)
            excluded.extend(records[i].source for i in waiting)
            if len(excluded) > MAX_EXCLUDED_SHARE * len(records) and not partial:
                raise DataError(
                    f"joint refinement: the model fitted to the steadier records does not "
                    f"follow {len(excluded)} of the {len(records)} records "
                    f"({', '.join(Path(name).name for name in excluded)}): either the "
                    "records hold dynamics the model lacks, or the staged values started "
                    "it in another regime")
            break
        used = sorted(used + admitted)
    assert result is not None  # MAX_ROUNDS >= 1: one round at least
    return result


def refit_without(joint: FitResult, keep: Sequence[bool],
                  max_evaluations: int = MAX_EVALUATIONS,
                  start: dict[str, float] | None = None,
                  held: dict[str, float] | None = None,
                  freed: dict[str, tuple[float, float, float]] | None = None
                  ) -> FitResult | None:
    """The ``joint`` fit again on the records ``keep`` marks, from its optimum (or from
    ``start`` where it names a value), with its models, windows, weights, offsets and
    bounds: what the records the model fits say without the others
    (``diagnostics.misfit_influence``), or, with ``held``, what they say with those
    parameters held at other values, or, with ``freed`` (name -> (start, low, high)),
    with those freed too, in linear scale (a sensor's lag the joint fit held at zero:
    its bound at zero is reached in a step or two, where log scale walked to its floor
    in 13-20 iterations). None when fewer than ``MIN_RECORDS`` sweeps or ramps would be
    left, or the fit fails."""
    from dataclasses import replace

    from ..simulation import Rodas4

    kept = [i for i, ok in enumerate(keep) if ok]
    moving = [i for i in kept if joint.windows[i] is None]
    if len(moving) < MIN_RECORDS:
        return None
    names = [n for n in joint.estimates.names if "[" not in n]
    where = {n: joint.estimates.names.index(n) for n in names}
    low, high = joint.bounds
    offset = [k for k, i in enumerate(kept)
              if f"offset_position[{i}]" in joint.estimates.names]
    models = [joint.models[i] for i in kept]
    if held:
        models = [replace(m, params=m.params.with_values(
            {n: v for n, v in held.items() if n in m.params.values})) for m in models]
    bounds = {n: (low[j], high[j]) for n, j in where.items()}
    starts = {n: float(np.clip((start or {}).get(n, joint.values[n]), low[j], high[j]))
              for n, j in where.items()}
    for name, (value, lowest, highest) in (freed or {}).items():
        bounds[name], starts[name] = (lowest, highest), value
    try:
        return fit(models, [joint.records[i] for i in kept], [*names, *(freed or {})],
                   window=[joint.windows[i] for i in kept],
                   offsets=Offsets(["position"] if offset else (), offset),
                   solver=Rodas4(rtol=JOINT_RTOL),
                   weights=Weights(records=[joint.record_weights[i] for i in kept]),
                   optimizer=Optimizer(max_nfev=max_evaluations),
                   bounds=Bounds(bounds, log=names), start=starts)
    except (DataError, SolverError):
        return None


def stuck_at_bounds(joint: FitResult) -> np.ndarray:
    """Per estimate of ``joint`` (offsets: never), whether it ended at a search bound."""
    low, high = joint.bounds
    values = joint.estimates.values
    return np.isclose(values, low, rtol=1e-6) | np.isclose(values, high, rtol=1e-6)


def _nothing_new(fitted: FitResult, best_cost: float) -> bool:
    """Whether a restart ``fitted`` ended at a bound again, no better than ``best_cost``
    (by ``RESTART_GAIN`` of it)."""
    return bool(stuck_at_bounds(fitted).any()) and \
        fitted.cost >= (1.0 - RESTART_GAIN) * best_cost


def restart_at_bounds(joint: FitResult, prior, spread: float = RESTART_SPREAD,
                      max_evaluations: int = MAX_EVALUATIONS
                      ) -> tuple[FitResult, list[FitResult], str]:
    """Where the ``joint`` fit ended with estimates at a bound, fit it again with those
    at the ``prior``'s value and at prior × (1 ± ``spread``/2) (``optima.spread_starts``;
    the others where the joint fit stopped), and keep the best optimum inside the bounds;
    stop once ``RESTART_RETURNS`` starts in a row ended at a bound again without a lower
    cost. Returns (the fit kept, the other optima inside the bounds, why it gave up: the
    estimates still at a bound, "" if none). An estimate the ``prior`` does not hold (a
    sensor's lag it does not state) is not restarted: at its bound, the records say
    there is none."""
    names = joint.estimates.names
    stuck = stuck_at_bounds(joint) & np.array([n in prior for n in names], bool)
    if not stuck.any():
        return joint, [], ""
    base = joint.estimates.values.copy()
    base[stuck] = [prior[names[j]] for j in np.flatnonzero(stuck)]
    every = [True] * len(joint.records)
    fits, returns = [joint], 0
    for start in spread_starts(base, spread, stuck):
        fitted = refit_without(joint, every, max_evaluations,
                               dict(zip(names, map(float, start), strict=True)))
        if fitted is None:
            continue
        returns = returns + 1 if _nothing_new(fitted, min(f.cost for f in fits)) else 0
        fits.append(fitted)
        if returns >= RESTART_RETURNS:
            break
    inside = [f for f in fits if not stuck_at_bounds(f).any()]
    best = min(inside or fits, key=lambda f: f.cost)
    left = stuck_at_bounds(best)
    reason = stuck_reason(names, best.estimates.values, left, len(fits)) if left.any() \
        else ""
    return best, [f for f in inside if f is not best], reason


def _within(time: np.ndarray, window: tuple[float, float] | None) -> np.ndarray:
    """The samples inside ``window`` (all of them without one)."""
    if window is None:
        return np.ones(time.size, bool)
    return (time >= window[0]) & (time <= window[1])


def feasible(values: dict[str, float], params) -> dict[str, float]:
    """The fitted parameter ``values`` (offsets dropped), with Fs raised to Fc where a fit
    of records that show no static friction above the Coulomb level went below it."""
    out = {n: v for n, v in values.items() if "[" not in n}
    fc = out.get("Fc", params["Fc"])
    if out.get("Fs", params["Fs"]) < fc:
        out["Fs"] = fc
    return out


def prediction_ratio(record: Record, kind: str, params, friction=None, chamber=None,
                     solver=None) -> float:
    """RMS of the position error of the model at ``params`` on ``record`` (a presliding
    test after its approach, less its mean: its sensor offset is fitted) against the
    noise the record shows (``inputs.sensor_noise``); the position as its sensor sees it
    (the ``position_lag`` and ``position_offset`` ``params`` state, if any)."""
    from ..simulation import Rodas4, simulate
    from .fit import experiment_for
    from .inputs import sensor_noise

    model = bench_model(record, params, friction, chamber)
    try:
        result = simulate(model, experiment_for(model, record, smooth=True),
                          Rodas4(rtol=JOINT_RTOL) if solver is None else solver,
                          t_eval=record.time)
    except SolverError:
        return np.inf
    seen = Sensors.from_params(params).measure(record.time, "position", result["position"],
                                                 quantise=False)
    error = seen - record["position"]
    part = settled_part(record, params) if kind == "presliding" else None
    if part is not None and "setpoint" not in record:  # unsettled: judged whole
        error = error[record.time >= part[0]]
        error = error - error.mean()
    noise = sensor_noise(record["position"])
    return float(np.sqrt(np.mean(error**2)) / noise) if noise > 0 else np.inf


def _fit_records(records: Sequence[Record], kinds: Sequence[str], params, *, friction,
                 chamber, free: Sequence[str], solver, replicates: int | None, seed: int,
                 workers: int | None, max_evaluations: int, prior, drop_chaotic: bool,
                 excluded: list, screened: set, weights: dict) -> FitResult:
    """One output-error fit of ``free`` to ``records`` (see ``joint_refinement``). Only
    the records not yet in ``screened`` are screened for chaos, and the input-noise
    weight of a record is computed once (``weights``, by source)."""
    from ..simulation import Rodas4
    from .uncertainty import INPUT_REPLICATES, input_noise_weights

    solver = Rodas4(rtol=JOINT_RTOL) if solver is None else solver
    bounds = prior_bounds(params if prior is None else prior,
                          [n for n in free if n not in SENSOR_LAGS])
    bounds.update({n: (params[n] / PRIOR_FACTOR, params[n] * PRIOR_FACTOR)
                   for n in free if n in SENSOR_LAGS})
    start = within({n: params[n] for n in free}, bounds)
    if drop_chaotic:  # screened where the fit starts: the fit reuses the runs (``memo``)
        seen = params.with_values(_as_fitted(start))
        chaotic = [r.source for r in records if r.source not in screened and amplification(
            bench_model(r, seen, friction, chamber), r, seen, free, solver)
            > CHAOS_AMPLIFICATION]
        screened.update(r.source for r in records)
        if chaotic:
            keep = [i for i, r in enumerate(records) if r.source not in chaotic]
            if sum(kinds[i] != "presliding" for i in keep) < MIN_RECORDS:
                raise DataError(f"joint refinement: the motion of {len(chaotic)} of "
                                f"{len(records)} records is chaotic in the parameters "
                                f"(stick-slip); fewer than {MIN_RECORDS} sweeps or ramps "
                                "are left for output error")
            records = [records[i] for i in keep]
            kinds = [kinds[i] for i in keep]
            excluded.extend(chaotic)
    models, offset_records = [], []
    windows: list[tuple[float, float] | None] = []
    for i, (record, kind) in enumerate(zip(records, kinds, strict=True)):
        models.append(bench_model(record, params, friction, chamber))
        part = settled_part(record, params) if kind == "presliding" else None
        if part is not None and "setpoint" not in record:  # unsettled: fitted whole
            windows.append(part)
            offset_records.append(i)
        else:
            windows.append(None)
    new = [i for i, r in enumerate(records) if r.source not in weights]
    if new:
        masks = [_within(records[i].time, windows[i]) for i in new]
        found = input_noise_weights([models[i] for i in new], [records[i] for i in new],
                                    dict(params.values), masks,
                                    replicates=replicates or INPUT_REPLICATES, seed=seed,
                                    solver=solver, workers=workers)
        weights.update({records[i].source: w for i, w in zip(new, found, strict=True)})
    record_weights = [weights[r.source] for r in records]
    return fit(models, list(records), list(free), window=windows,
               offsets=Offsets(["position"] if offset_records else (), offset_records),
               solver=solver, weights=Weights(records=record_weights),
               optimizer=Optimizer(max_nfev=max_evaluations), bounds=bounds,
               start=start)


def _as_fitted(start: dict[str, float]) -> dict[str, float]:
    """The values ``fit`` simulates first from ``start``: it searches positive values in
    log scale, and exp(log(v)) can differ from v in the last bit (computed as ``fit``
    does, on the array of the positive values in order)."""
    values = np.array(list(start.values()), dtype=float)
    positive = values > 0
    values[positive] = np.exp(np.log(values[positive]))
    return dict(zip(start, map(float, values), strict=True))
