"""Intervals that hold: the noise on the measured input, and prediction bands.

An output-error fit driven by a measured input (the presliding test's chamber pressure)
treats that input as exact; its covariance, from the residuals, misses what the input's
noise does to the estimates. On the vgt-paper campaign the spread of σ1 over noise seeds
was 4.4× its output-error standard error. ``input_noise_covariance`` adds that part by a
parametric bootstrap of the input alone, linearised around the estimate:

1. for each record whose input is noisy (``inputs.noise_level`` of the input signal
   above round-off), draw white noise of that level on the input's samples;
2. move the rebuilt input's knots as that noise moves them (one Gauss-Newton step of the
   knot fit, ``inputs.knot_jacobian``);
3. simulate the fitted model under the moved input and map the change of its output to
   the parameters through the fit's Jacobian (δθ = J⁺·δr).

The second moment of δθ over the replicates is the input's share of the covariance; the
output noise's share is the fit's own (HAC) covariance, and the two add. Each replicate
costs one simulation per noisy-input record, run on threads.

``prediction_band`` draws parameter sets from the final covariance and runs them on the
batch engine: the band of a signal (or of the pressure-position loop) the uncertainty
leaves.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..errors import ParameterError, SolverError
from ..models.actuator import CHAMBER_PRESSURE
from ..options import Executor
from ..progress import stop_threads
from .estimates import Estimates
from .fit import FitResult, experiment_for, input_signal, rebuilt_input
from .inputs import knot_jacobian, noise_level, sensor_noise

__all__ = ["InputNoise", "PredictionBand", "input_noise", "input_noise_covariance",
           "input_noise_weights", "input_replicates", "nuisance_covariance", "parameter_draws",
           "prediction_band", "with_covariance"]

#: Replicates of the input-noise bootstrap: the variance of a 64-sample estimate is
#: within ±25 % (2σ) of its value, the standard error within ±12 %.
INPUT_REPLICATES = 64


@dataclass(frozen=True)
class InputNoise:
    """The input noise's share of the covariance, and what it came from."""

    covariance: np.ndarray
    noise: dict[str, float]  # record -> input noise standard deviation (SI)
    replicates: int
    #: record index -> (replicates × samples) changes of the fitted signal
    moves: dict[int, np.ndarray] = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        return pd.DataFrame({"record": list(self.noise), "input_noise": list(self.noise.values())})


def input_noise(model, record) -> float:
    """Standard deviation of the noise on the input ``record`` drives ``model`` with
    (``inputs.noise_level``), or 0 when the input is exact to round-off (a logged
    set-point, which the bench commanded)."""
    values = record[input_signal(model)]
    sigma = noise_level(values)
    return sigma if sigma > 1e-9 * max(float(np.ptp(values)), 1e-300) else 0.0


def input_replicates(models, records, values: dict[str, float], masks, *,
                     replicates: int = INPUT_REPLICATES, seed: int = 0, solver=None,
                     signal: str = "position", workers: int | None = None
                     ) -> dict[int, np.ndarray]:
    """Record index -> (replicates × samples in its mask) changes of ``signal`` when
    noise like that on the record's measured input moves the rebuilt input (steps 1-2
    of the module docstring), for the records whose input is noisy; the model runs at
    ``values``."""
    from ..experiments import from_samples
    from ..simulation import Rodas4, simulate

    if replicates < 2:
        raise ParameterError(f"input noise: replicates = {replicates}; need at least 2")
    solver = Rodas4(rtol=1e-8) if solver is None else solver
    rng = np.random.default_rng(seed)
    jobs, baselines = [], {}
    for i, (model, record) in enumerate(zip(models, records, strict=True)):
        sigma = input_noise(model, record)
        if sigma == 0.0:
            continue
        knot_t, knot_v = rebuilt_input(model, record)
        projector = _knot_projector(record.time, knot_t, knot_v, sigma)
        own = {n: v for n, v in values.items() if n in _parameters_of(model)}
        others = experiment_for(model, record, smooth=True).drives  # its load, ...
        baselines[i] = (knot_t, knot_v, own, others)
        jobs += [(i, projector @ rng.normal(0.0, sigma, record.time.size))
                 for _ in range(replicates)]

    def run(i: int, move: np.ndarray | None) -> np.ndarray | None:
        model, record = models[i], records[i]
        knot_t, knot_v, own, others = baselines[i]
        times, knots = knot_t.copy(), knot_v.copy()
        if move is not None:
            n_in = knot_t.size - 2
            times[1:-1] += move[:n_in]
            knots += move[n_in:]
            if np.any(np.diff(times)[np.diff(knot_t) > 0] <= 0):
                return None  # a knot moved past a neighbour: not a rebuilt input
        experiment = from_samples(times, knots, model.drive_quantity,
                                  n_points=record.time.size, drives=others)
        try:
            return simulate(model, experiment, solver, t_eval=record.time,
                            values=own)[signal][masks[i]]
        except SolverError:
            return None

    out: dict[int, list[np.ndarray]] = {i: [] for i in baselines}
    with stop_threads(ThreadPoolExecutor(max_workers=workers or os.cpu_count() or 1)) as pool:
        nominal = dict(zip(baselines, pool.map(lambda i: run(i, None), baselines),
                           strict=True))
        for (i, _), moved in zip(jobs, pool.map(lambda job: run(*job), jobs), strict=True):
            if moved is not None and nominal[i] is not None:
                out[i].append(moved - nominal[i])
    if any(len(v) < 2 for v in out.values()):
        raise SolverError("input noise: the simulations of the replicates failed")
    return {i: np.array(v) for i, v in out.items()}


def input_noise_weights(models, records, values: dict[str, float], masks, *,
                        replicates: int = INPUT_REPLICATES, seed: int = 0, solver=None,
                        workers: int | None = None) -> np.ndarray:
    """A weight per record for a fit of the position: 1 where the input is exact, and
    σ_x/√(σ_x² + σ_u→x²) where noise on the input adds σ_u→x (RMS over the replicates)
    to the sensor's σ_x (``inputs.sensor_noise``) — weighted least squares with each
    record's whole measurement noise, so a record whose input is noisier than its
    output says does not pull the others' parameters."""
    moves = input_replicates(models, records, values, masks, replicates=replicates,
                             seed=seed, solver=solver, workers=workers)
    weights = np.ones(len(records))
    for i, delta in moves.items():
        sensor = sensor_noise(records[i]["position"])
        added = float(np.sqrt(np.mean(delta**2)))
        weights[i] = sensor / np.hypot(sensor, added)
    return weights


def input_noise_covariance(fit: FitResult, replicates: int = INPUT_REPLICATES,
                           seed: int = 0, solver=None, workers: int | None = None
                           ) -> InputNoise:
    """Covariance of ``fit``'s estimates due to the noise on each record's measured input
    (see the module docstring). ``solver`` is the one the fit used (default Rodas4 at
    rtol 1e-8)."""
    n_par = fit.jacobian.shape[1]
    masks = fit.masks()
    values = {**fit.base_values, **fit.values}
    moves = input_replicates(fit.models, fit.records, values, masks, replicates=replicates,
                             seed=seed, solver=solver, workers=workers,
                             signal=fit.signals[0])
    noise = {fit.records[i].source: input_noise(fit.models[i], fit.records[i])
             for i in moves}
    if not moves:
        return InputNoise(np.zeros((n_par, n_par)), noise, replicates)
    if len(fit.signals) != 1:
        raise ParameterError("input noise: the covariance needs a fit of one signal")
    pinv = np.linalg.pinv(fit.jacobian)
    lengths = [int(m.sum()) for m in masks]
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    covariance = np.zeros((n_par, n_par))
    for i, delta in moves.items():  # independent noise on each input: the shares add
        shifts = (fit.weight(i, fit.signals[0]) * delta) @ pinv[:, offsets[i]:offsets[i + 1]].T
        covariance += shifts.T @ shifts / len(shifts)
    return InputNoise(covariance, noise, replicates, moves)


def nuisance_covariance(fit: FitResult, held: dict[str, float], solver=None,
                        workers: int | None = None) -> np.ndarray:
    """What parameters held at a guess do to ``fit``'s estimates: ``held`` maps each
    held parameter to the standard deviation of its guess; returns G·Σ·Gᵀ with
    G = −J⁺·J_held (how the estimates shift to absorb a change of a held parameter), from
    forward sensitivities of every record to the held parameters at the estimate. A
    parameter the records cannot tell but whose wrong value still moves them would
    otherwise bias the others inside intervals that ignore it."""
    from ..simulation import Rodas4, simulate_sensitivities
    from .fit import experiment_for

    solver = Rodas4(rtol=1e-8) if solver is None else solver
    names = list(held)
    values = {**fit.base_values, **fit.values}
    signal = fit.signals[0]

    def column_block(i: int) -> np.ndarray:
        model, record = fit.models[i], fit.records[i]
        own = _parameters_of(model)
        used = [n for n in names if n in own]
        block = np.zeros((int(fit.masks()[i].sum()), len(names)))
        if not used:
            return block
        sens = simulate_sensitivities(
            model, experiment_for(model, record, smooth=True), used, solver,
            t_eval=record.time, values={n: v for n, v in values.items() if n in own})
        for k, name in enumerate(used):
            block[:, names.index(name)] = fit.weight(i, signal) * \
                sens[signal][fit.masks()[i], k]
        return block

    with stop_threads(ThreadPoolExecutor(max_workers=workers or os.cpu_count() or 1)) as pool:
        j_held = np.vstack(list(pool.map(column_block, range(len(fit.records)))))
    gain = -np.linalg.pinv(fit.jacobian) @ j_held
    return gain @ np.diag([held[n] ** 2 for n in names]) @ gain.T


def _knot_projector(time, knot_t, knot_v, sigma: float) -> np.ndarray:
    """Linear map from noise on the input's samples to the moves of its knots (interior
    knot times, then all values): one Gauss-Newton step of the knot fit, with each
    interior knot time held (as a prior of standard deviation half the gap to its nearer
    neighbour) so that a knot between two nearly level segments, whose time the samples
    hardly fix, stays between its neighbours instead of swinging far off. A jump's knots
    (a repeated time, ``inputs.piecewise_linear_input``) keep their time, and the value
    held up to a jump, which no sample sees, moves with the knot before it."""
    from scipy.sparse import identity

    n_knots = knot_t.size
    n_in = n_knots - 2
    basis = knot_jacobian(time, knot_t, knot_v)
    repeated = np.zeros(n_knots, dtype=bool)
    repeated[1:] |= np.diff(knot_t) == 0
    repeated[:-1] |= np.diff(knot_t) == 0
    unseen = np.zeros(n_knots, dtype=bool)
    unseen[1:] = np.asarray(abs(basis[:, n_in + 1:]).sum(axis=0)).ravel() == 0
    # the moves of all knots from the free ones: a free column maps to itself, a held
    # time to nothing, an unseen value to its left neighbour's value
    expand = identity(n_in + n_knots, format="lil")
    for k in np.flatnonzero(unseen):
        expand[n_in + k, n_in + k - 1] = 1.0
    expand = expand.tocsc()[:, np.concatenate([~repeated[1:-1], ~unseen])]
    reduced = basis @ expand
    normal = (reduced.T @ reduced).toarray()
    gaps = np.minimum(np.diff(knot_t)[:-1], np.diff(knot_t)[1:])[~repeated[1:-1]]
    prior = np.zeros(normal.shape[0])
    prior[: gaps.size] = (sigma / (0.5 * gaps)) ** 2
    return expand @ np.linalg.solve(normal + np.diag(prior), reduced.T.toarray())


def _parameters_of(model) -> frozenset[str]:
    from ..core.assembly import assemble

    return frozenset(assemble(model).parameter_names)


def with_covariance(estimates: Estimates, covariance: np.ndarray) -> Estimates:
    """``estimates`` with another covariance (and the standard errors from it)."""
    covariance = np.asarray(covariance, dtype=float)
    stderr = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    stderr[~np.isfinite(np.diag(covariance))] = np.inf
    return Estimates(estimates.names, estimates.values, stderr, covariance, estimates.dof,
                     estimates.units)


# --------------------------------------------------------------------------- bands
@dataclass(frozen=True)
class PredictionBand:
    """Quantiles of signals over parameter sets drawn from the estimates' covariance."""

    time: np.ndarray
    nominal: dict[str, np.ndarray]
    lower: dict[str, np.ndarray]
    upper: dict[str, np.ndarray]
    samples: dict[str, np.ndarray]  # signal -> (n_drawn × n_time), for loop envelopes
    level: float

    def to_pandas(self) -> pd.DataFrame:
        columns = {}
        for name in self.nominal:
            columns[name] = self.nominal[name]
            columns[f"{name}_low"] = self.lower[name]
            columns[f"{name}_high"] = self.upper[name]
        return pd.DataFrame(columns, index=pd.Index(self.time, name="time"))


#: draws tried per set kept before the uncertainty is refused as mostly invalid
MAX_DRAW_FACTOR = 100


def parameter_draws(estimates: Estimates, draws: int, seed: int = 0, *,
                    what: str = "parameter draws",
                    base: Mapping[str, float] | None = None) -> pd.DataFrame:
    """``draws`` parameter sets from N(values, covariance) of ``estimates`` (its model
    parameters; offsets left out), one row each. A set the model would refuse (a value
    out of its range, as a negative Coulomb force, or a broken relation with the other
    drawn values or ``base``'s, as Fs < Fc) is drawn again: the normal truncated to the
    valid region. The input of a prediction band and of a robust controller design."""
    from ..parameters.validation import row_problems

    names = [n for n in estimates.names if "[" not in n]
    idx = [estimates.names.index(n) for n in names]
    mean = estimates.values[idx]
    cov = estimates.covariance[np.ix_(idx, idx)]
    if not np.all(np.isfinite(cov)):
        raise ParameterError(f"{what}: the covariance is not finite (a parameter is not "
                             "identifiable)")
    rng = np.random.default_rng(seed)
    known = dict(base or {})
    rows: list[np.ndarray] = []
    tried = 0
    while len(rows) < draws:
        if tried >= MAX_DRAW_FACTOR * draws:
            raise ParameterError(
                f"{what}: {len(rows)} of {tried} draws from N(values, covariance) are valid "
                f"parameter sets (fewer than 1 in {MAX_DRAW_FACTOR}); the uncertainty "
                "reaches far outside the model's valid region (e.g. Fs < Fc): it is not a "
                "usable description of the parameters")
        batch = rng.multivariate_normal(mean, cov, size=draws, method="svd")
        tried += draws
        ok = np.array([p is None for p in row_problems(known, names, batch)])
        rows.extend(batch[ok][: draws - len(rows)])
    return pd.DataFrame(np.array(rows), columns=names)


def prediction_band(model, experiment, estimates: Estimates, *, draws: int = 100,
                    level: float = 0.95,
                    signals: Sequence[str] = ("position", CHAMBER_PRESSURE),
                    t_eval=None, seed: int = 0, solver=None,
                    executor: Executor | int | str | None = None) -> PredictionBand:
    """The band of ``signals`` under ``experiment`` that the uncertainty of
    ``estimates`` leaves: ``draws`` parameter sets from N(values, covariance) (sets the
    model refuses, as Fs < Fc, are drawn again: ``parameter_draws``), simulated on the
    batch engine (``executor``: where, see ``simulate_batch``); ``level`` is the central
    probability of the band."""
    from ..simulation import simulate
    from ..simulation.batch import simulate_batch

    if not 0 < level < 1:
        raise ParameterError(f"prediction band: level = {level}; must be in (0, 1)")
    params = getattr(model, "params", None)
    table = parameter_draws(estimates, draws, seed, what="prediction band",
                            base=getattr(params, "values", None))
    values = {n: float(estimates.values[estimates.names.index(n)]) for n in table.columns}
    nominal = simulate(model, experiment, solver, t_eval=t_eval, values=values)
    result = simulate_batch(model, experiment, table, signals=list(signals),
                            t_eval=nominal.time, solver=solver, executor=executor,
                            features=())
    good = (result.table["status"] == "ok").to_numpy()
    tail = (1 - level) / 2
    lower, upper, samples = {}, {}, {}
    for s in signals:
        runs = result.signals[s][good]
        lower[s] = np.quantile(runs, tail, axis=0)
        upper[s] = np.quantile(runs, 1 - tail, axis=0)
        samples[s] = runs
    return PredictionBand(nominal.time, {s: nominal[s] for s in signals}, lower, upper,
                          samples, level)
