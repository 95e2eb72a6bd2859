"""Global sensitivity indices: SALib's Sobol, Morris and RBD-FAST, and the standardised
regression coefficients (paper eq. 14) SALib lacks.

Every method takes a ``Problem`` and an ``evaluate`` function from a sample (n × k, SI)
to outputs (a DataFrame, one column per output), so the same code serves a test function
with known indices and the actuator on the batch engine (``model_outputs``).
"""

from __future__ import annotations

import functools
import logging
import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..checks import check_int, check_range, check_seed, check_type
from ..errors import ArgumentError, ArgumentTypeError, PneumactError, ResourceError
from ..io.report import ResultVocabulary
from ..options import Checkpoint, Executor
from ..plotting import tight_layout
from ..progress import ProgressCallback
from .problem import Problem

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["SensitivityWarning", "StudyResult", "model_outputs", "morris", "rbd_fast",
           "sobol", "src"]

Evaluate = Callable[[np.ndarray], pd.DataFrame]
SRC_MIN_R2 = 0.7  # below this the linear regression explains too little for SRC to mean much
#: Smallest samples each method accepts. Sobol: Saltelli's scheme on a Sobol sequence,
#: whose balance needs a power of two; below 8 the bootstrap has nothing to resample.
#: Morris: σ of the elementary effects needs two trajectories. SRC: the regression has
#: k + 1 coefficients, so 2·(k + 1) runs leave as many residual degrees of freedom (with
#: fewer, R² → 1 whatever the model). RBD-FAST: 2·M + 1 points resolve M = 10 harmonics
#: (SALib's default); 4·M leaves the estimate room.
MIN_SOBOL_N = 8
MIN_MORRIS_TRAJECTORIES = 2
MIN_RBD_FAST_N = 40


def check_sobol_n(n, *, where: str = "sobol", name: str = "n") -> int:
    """A Sobol base sample size: a power of two >= MIN_SOBOL_N."""
    n = check_int(name, n, minimum=MIN_SOBOL_N, where=where)
    if n & (n - 1):
        low = 1 << (n.bit_length() - 1)
        raise ArgumentError(f"{where + ': ' if where else ''}{name} = {n}: must be a power of "
                            f"two (the Sobol sequence is balanced only then): {low} or "
                            f"{2 * low}")
    return n


def check_src_n(n, k: int, *, where: str = "src", name: str = "n") -> int:
    """An SRC sample size: >= 2·(k + 1) for k parameters."""
    minimum = 2 * (k + 1)
    n = check_int(name, n, where=where)
    if n < minimum:
        raise ArgumentError(f"{where + ': ' if where else ''}{name} = {n}: must be >= "
                            f"{minimum} = 2·(k + 1) for k = {k} parameters (with fewer runs "
                            "the regression fits the sample exactly, R² → 1, whatever the "
                            "model)")
    return n


def _check_study(where: str, problem, evaluate, seed) -> None:
    check_type("problem", problem, Problem, where=where,
               what="a Problem (e.g. sa.Problem.around(params, {...}))")
    if not callable(evaluate):
        raise ArgumentTypeError(f"{where}: evaluate = {evaluate!r}: must be a function of the "
                                "sample (e.g. sa.model_outputs(...))")
    check_seed("seed", seed, where=where)


class SensitivityWarning(UserWarning):
    """An index that should not be trusted as it stands (low R², negative beyond its CI)."""


@dataclass(eq=False)
class StudyResult(ResultVocabulary):
    """Indices per output (``indices``: long table output × parameter × index), the
    sample and the outputs it gave.

    ``to_pandas()``: the indices, long (``to_pandas(output=...)``: one output's, a row
    per parameter; ``"sample"``, ``"outputs"``: the others); ``plot(output)``: the bar
    chart of an output's index (default the first output); ``write(folder)``: the
    tables, the figure of every output and report.html."""

    report_title = "Global sensitivity study"
    figure_name = "indices"

    def figures(self) -> dict[str, Callable[[], Figure]]:
        return {f"indices_{output}": functools.partial(self.plot, output)
                for output in self.output_names}

    method: str
    indices: pd.DataFrame
    sample: pd.DataFrame
    outputs: pd.DataFrame
    extra: dict = field(default_factory=dict)

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"indices": self.indices, "sample": self.sample, "outputs": self.outputs}

    def report_text(self) -> str:
        return (f"{self.method} indices of {', '.join(self.output_names)} over "
                f"{len(self.sample)} runs.")

    @property
    def output_names(self) -> list[str]:
        return list(dict.fromkeys(self.indices["output"]))

    def to_pandas(self, name: str | None = None, output: str | None = None
                  ) -> pd.DataFrame:
        """The indices (long: output, parameter, indices), or one ``output``'s, one row
        per parameter; ``name``: "sample" or "outputs" for those tables."""
        if output is None:
            return super().to_pandas(name)
        if output not in self.output_names:
            raise ArgumentError(f"to_pandas: output = {output!r}; allowed: "
                                f"{', '.join(self.output_names)}")
        sub = self.indices[self.indices["output"] == output]
        return sub.drop(columns="output").set_index("parameter")

    def ranking(self, output: str, by: str | None = None) -> list[str]:
        """Parameters from most to least influential on ``output``."""
        table = self.to_pandas(output=output)
        key = by or {"sobol": "ST", "morris": "mu_star", "src": "SRC2", "rbd_fast": "S1",
                     "dgsm": "ST_bound"}.get(self.method, table.columns[0])
        return list(table[key].abs().sort_values(ascending=False).index)

    def plot(self, output: str | None = None, index: str | None = None) -> Figure:
        """Bar chart of an index (with its confidence interval where there is one) of
        ``output`` (default: the first)."""
        import matplotlib.pyplot as plt

        output = output or self.output_names[0]
        table = self.to_pandas(output=output)
        keys = {"sobol": ["S1", "ST"], "morris": ["mu_star"], "src": ["SRC"],
                "rbd_fast": ["S1"], "dgsm": ["ST_bound"]}.get(self.method,
                                                              [table.columns[0]])
        keys = [index] if index else keys
        fig, ax = plt.subplots(figsize=(6.5, 3.8))
        x = np.arange(len(table))
        width = 0.8 / len(keys)
        for i, key in enumerate(keys):
            err = table[f"{key}_conf"] if f"{key}_conf" in table else None
            ax.bar(x + i * width, table[key], width, yerr=err, capsize=3, label=key)
        ax.set_xticks(x + 0.4 - width / 2, table.index)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_title(f"{self.method}: {output}", fontsize=10)
        ax.set_xlabel("parameter")
        unit = "[output unit]" if self.method in ("morris", "dgsm") else "[1]"
        ax.set_ylabel(f"{', '.join(keys)} {unit}")
        ax.legend(fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
        tight_layout(fig)
        return fig


#: a Sobol sample of this many runs or more is announced before it is drawn (SALib draws
#: about 200 000 runs a second on a loaded 2-core machine: n = 2**20 takes a minute,
#: before the first run and its progress)
ANNOUNCED_SAMPLE_RUNS = 500_000
#: runs a second SALib's Sobol sampler draws (measured: 655 360 runs x 8 parameters in
#: 2.9 s on a loaded 2-core machine)
SAMPLE_DRAW_RATE = 200_000.0
#: copies of a sample held at once: SALib's unit sample and the factors' values
SAMPLE_COPIES = 2


def _size_the_sample(method: str, runs: int, k: int) -> None:
    """Say how big the sample is before drawing it (the ``pneumact.estimates`` log, a
    ``note:`` line on the command line), so that a long draw is not a silent "0/?"; and
    refuse a sample whose copies (the unit sample and its values, ``SAMPLE_COPIES``)
    would pass the memory limit, before drawing it."""
    from ..simulation.memory import memory_limit

    needed = SAMPLE_COPIES * runs * k * 8
    limit, source = memory_limit()
    if needed > limit:
        raise ResourceError(
            f"{method}: the sample of {runs:,} runs x {k} parameters would need about "
            f"{needed / 1024**2:.0f} MiB of memory before the first run, above the limit "
            f"of {limit / 1024**2:.0f} MiB ({source})".replace(",", " "),
            api_hint="a smaller n (the convergence check, sobol_convergence, says when "
                     "the indices are good enough), or fewer factors",
            cli_hint="a smaller --n, or fewer factors, or raise the limit "
                     "(PNEUMACT_MEMORY_LIMIT=16GiB pneumact ...)")
    if runs >= ANNOUNCED_SAMPLE_RUNS:
        logging.getLogger("pneumact.estimates").info(
            "%s: drawing the sample first: %s runs x %d parameters (%.0f MiB), about %.0f s "
            "before the runs start", method, f"{runs:,}".replace(",", " "), k,
            runs * k * 8 / 1024**2, runs / SAMPLE_DRAW_RATE)


def _evaluate(problem: Problem, evaluate: Evaluate, sample: np.ndarray) -> pd.DataFrame:
    values = problem.transform(sample)
    outputs = evaluate(values)
    if not isinstance(outputs, pd.DataFrame):
        outputs = pd.DataFrame(np.asarray(outputs, dtype=float).reshape(len(values), -1))
        outputs.columns = [f"y{i}" if len(outputs.columns) > 1 else "y"
                           for i in range(len(outputs.columns))]
    bad = ~np.isfinite(outputs.to_numpy(dtype=float))
    if bad.any():
        rows = np.flatnonzero(bad.any(axis=1))
        raise PneumactError(
            f"{rows.size} of {len(values)} runs gave no value for "
            f"{', '.join(outputs.columns[bad.any(axis=0)])} (first: run {rows[0]}); an index "
            "cannot leave runs out without biasing it: fix or narrow the ranges, or study "
            "the failures (StudyResult.extra) first")
    return outputs


def _frame(problem: Problem, values: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame(problem.transform(values), columns=problem.names)


def sobol(problem: Problem, evaluate: Evaluate, n: int = 1024, second_order: bool = False,
          seed: int = 0, resamples: int = 200, conf_level: float = 0.95) -> StudyResult:
    """First-order (S1) and total (ST) Sobol indices with bootstrap confidence intervals
    (and S2 with ``second_order``): Saltelli's scheme on a scrambled Sobol sequence,
    n·(k + 2) runs (n·(2k + 2) with second order)."""
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    _check_study("sobol", problem, evaluate, seed)
    n = check_sobol_n(n)
    check_int("resamples", resamples, minimum=1, where="sobol")
    check_range("conf_level", conf_level, 0.0, 1.0, low_open=True, high_open=True,
                where="sobol")
    salib = problem.to_salib()
    k = len(problem.names)
    _size_the_sample("sobol", n * (2 * k + 2 if second_order else k + 2), k)
    x = sample.sample(salib, n, calc_second_order=bool(second_order), seed=seed)
    outputs = _evaluate(problem, evaluate, x)
    rows = []
    for column in outputs.columns:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # constant outputs: 0/0
            warnings.filterwarnings("ignore", "Constant values", UserWarning)  # → zeros
            res = analyze.analyze(salib, outputs[column].to_numpy(float),
                                  calc_second_order=second_order, num_resamples=resamples,
                                  conf_level=conf_level, seed=bootstrap_seed(seed))
        for j, name in enumerate(problem.names):
            rows.append({"output": column, "parameter": name, "S1": res["S1"][j],
                         "S1_conf": res["S1_conf"][j], "ST": res["ST"][j],
                         "ST_conf": res["ST_conf"][j]})
    _warn_negative(rows, n)
    return StudyResult("sobol", pd.DataFrame(rows), _frame(problem, x), outputs,
                       {"n": n, "second_order": second_order})


def bootstrap_seed(seed: int) -> np.random.Generator:
    """A generator for SALib's Sobol bootstrap: it tests ``if seed:``, so an int 0 would
    leave the confidence intervals unseeded (different on every call)."""
    return np.random.default_rng(seed)


def _warn_negative(rows: list[dict], n: int) -> None:
    """One warning naming the outputs (and parameters) whose S1 or ST is negative beyond
    its confidence interval: the sample is too small for them."""
    bad: dict[str, list[str]] = {}
    for r in rows:
        if r["S1"] + r["S1_conf"] < 0 or r["ST"] + r["ST_conf"] < 0:
            bad.setdefault(str(r["output"]), []).append(r["parameter"])
    if bad:
        listed = [f"{out} ({', '.join(pars)})" for out, pars in list(bad.items())[:3]]
        more = f" and {len(bad) - 3} more outputs" if len(bad) > 3 else ""
        warnings.warn(f"Sobol indices negative beyond their confidence interval with n = {n}: "
                      f"{'; '.join(listed)}{more}; try n = {4 * n}", SensitivityWarning,
                      stacklevel=3)


def morris(problem: Problem, evaluate: Evaluate, trajectories: int = 20, levels: int = 4,
           seed: int = 0, resamples: int = 200) -> StudyResult:
    """Morris elementary effects: μ* (mean |effect|, with CI), μ and σ; r·(k + 1) runs."""
    from SALib.analyze import morris as analyze
    from SALib.sample import morris as sample

    _check_study("morris", problem, evaluate, seed)
    trajectories = check_int("trajectories", trajectories, minimum=MIN_MORRIS_TRAJECTORIES,
                             where="morris")
    levels = check_int("levels", levels, minimum=2, where="morris")
    check_int("resamples", resamples, minimum=1, where="morris")
    salib = problem.to_salib()
    x = sample.sample(salib, trajectories, num_levels=levels, seed=seed)
    outputs = _evaluate(problem, evaluate, x)
    rows = []
    for column in outputs.columns:
        res = analyze.analyze(salib, x, outputs[column].to_numpy(float), num_levels=levels,
                              num_resamples=resamples, seed=seed)
        for j, name in enumerate(problem.names):
            rows.append({"output": column, "parameter": name, "mu_star": res["mu_star"][j],
                         "mu_star_conf": res["mu_star_conf"][j], "mu": res["mu"][j],
                         "sigma": res["sigma"][j]})
    return StudyResult("morris", pd.DataFrame(rows), _frame(problem, x), outputs,
                       {"trajectories": trajectories, "levels": levels})


def rbd_fast(problem: Problem, evaluate: Evaluate, n: int = 1000, seed: int = 0
             ) -> StudyResult:
    """First-order indices by RBD-FAST on a Latin hypercube of n runs."""
    from SALib.analyze import rbd_fast as analyze
    from SALib.sample import latin

    _check_study("rbd_fast", problem, evaluate, seed)
    n = check_int("n", n, minimum=MIN_RBD_FAST_N, where="rbd_fast")
    salib = problem.to_salib()
    x = latin.sample(salib, n, seed=seed)
    outputs = _evaluate(problem, evaluate, x)
    rows = []
    for column in outputs.columns:
        res = analyze.analyze(salib, x, outputs[column].to_numpy(float), seed=seed)
        for j, name in enumerate(problem.names):
            rows.append({"output": column, "parameter": name, "S1": res["S1"][j],
                         "S1_conf": res["S1_conf"][j]})
    return StudyResult("rbd_fast", pd.DataFrame(rows), _frame(problem, x), outputs, {"n": n})


def src(problem: Problem, evaluate: Evaluate, n: int = 500, seed: int = 0,
        rank: bool = False) -> StudyResult:
    """Standardised regression coefficients (paper eq. 14): SRC_i = b_i·sd(x_i)/sd(y) of
    the linear regression of y on the parameters over a Latin hypercube of n runs, with
    SRC² (the share of variance for independent inputs) with its bootstrap 95 % half-width
    (SRC2_conf) and the regression's R²; with
    ``rank`` the same on ranks (SRRC, for monotone non-linear responses). Warns when
    R² < 0.7: the linear model then explains too little for the coefficients to rank."""
    from SALib.sample import latin

    _check_study("src", problem, evaluate, seed)
    n = check_src_n(n, len(problem.names))
    x = latin.sample(problem.to_salib(), n, seed=seed)
    outputs = _evaluate(problem, evaluate, x)
    values = problem.transform(x)
    rows = []
    for column in outputs.columns:
        y = outputs[column].to_numpy(float)
        coef, r2 = src_coefficients(values, y, rank)
        conf = src_intervals(values, y, rank, seed=bootstrap_seed(seed))
        if r2 < SRC_MIN_R2:
            warnings.warn(f"{'SRRC' if rank else 'SRC'} of {column}: R² = {r2:.2f} < "
                          f"{SRC_MIN_R2}; the regression explains too little of the variance "
                          "for the coefficients to mean much (use Sobol or Morris)",
                          SensitivityWarning, stacklevel=2)
        for j, name in enumerate(problem.names):
            rows.append({"output": column, "parameter": name, "SRC": coef[j],
                         "SRC2": coef[j] ** 2, "SRC2_conf": conf[j], "R2": r2})
    return StudyResult("src", pd.DataFrame(rows), _frame(problem, x), outputs,
                       {"n": n, "rank": rank})


def src_intervals(x: np.ndarray, y: np.ndarray, rank: bool = False, *,
                  resamples: int = 200, conf_level: float = 0.95, seed=None) -> np.ndarray:
    """Half-width of the bootstrap ``conf_level`` interval of each SRC² (the runs resampled
    with replacement ``resamples`` times): two parameters whose SRC² differ by less cannot
    be ranked on this sample."""
    rng = np.random.default_rng(seed)
    squares = np.empty((resamples, x.shape[1]))
    for i in range(resamples):
        pick = rng.integers(0, len(y), len(y))
        squares[i] = src_coefficients(x[pick], y[pick], rank)[0] ** 2
    low, high = np.quantile(squares, [(1 - conf_level) / 2, (1 + conf_level) / 2], axis=0)
    return (high - low) / 2


def src_coefficients(x: np.ndarray, y: np.ndarray, rank: bool = False
                     ) -> tuple[np.ndarray, float]:
    """(SRC per column of x, R²) of the least-squares line y ≈ a + Σ b_i·x_i."""
    from scipy.stats import rankdata

    if rank:
        x = np.column_stack([rankdata(c) for c in x.T])
        y = rankdata(y)
    sx, sy = x.std(axis=0), y.std()
    if sy == 0:
        return np.zeros(x.shape[1]), 1.0
    design = np.column_stack([np.ones(len(y)), (x - x.mean(axis=0)) / np.where(sx > 0, sx, 1)])
    coef, *_ = np.linalg.lstsq(design, (y - y.mean()) / sy, rcond=None)
    fitted = design @ coef
    r2 = 1.0 - np.sum(((y - y.mean()) / sy - fitted) ** 2) / len(y)
    return coef[1:], float(r2)


def model_outputs(model, experiment, problem: Problem, features: Sequence[str], *,
                  executor: Executor | int | str | None = None,
                  checkpoint: Checkpoint | str | os.PathLike | None = None,
                  progress: ProgressCallback | None = None, solver=None) -> Evaluate:
    """An ``evaluate`` that runs the sample on the batch engine (an ``Executor``: all
    local cores by default, or a Dask scheduler; resumable from a ``Checkpoint``) and
    returns the features. Failed runs are reported with their errors, never dropped."""
    return batch_evaluate(model, experiment, problem, features=list(features),
                          executor=executor, checkpoint=checkpoint, progress=progress,
                          solver=solver)


def batch_evaluate(model, experiment, problem: Problem, *, features=(), signal=None,
                   times=None, **batch) -> Evaluate:
    """The batch engine as an ``evaluate``: one column per feature, or (``signal``) one per
    time of ``times``, named by the time. ``batch``: ``simulate_batch`` keywords."""
    from ..simulation.batch import simulate_batch

    grid = None if times is None else np.asarray(times, dtype=float)
    if signal and grid is None:
        raise ArgumentError(f"batch_evaluate: signal = {signal!r} needs times= (the times "
                            "at which it is read)")
    time_columns = [] if grid is None else [repr(float(t)) for t in grid]

    def evaluate(values: np.ndarray) -> pd.DataFrame:
        table = pd.DataFrame(values, columns=problem.names)
        result = simulate_batch(model, experiment, table, features=list(features),
                                signals=[signal] if signal else None, t_eval=grid, **batch)
        failed = result.failed
        if len(failed):
            raise PneumactError(
                f"{len(failed)} of {len(table)} runs failed (first, row {failed.index[0]}: "
                f"{failed['error'].iloc[0]}); an index cannot leave runs out: narrow the "
                "ranges or loosen the solver")
        if signal:
            return pd.DataFrame(result.signals[signal], columns=time_columns)
        return result.table[list(features)].reset_index(drop=True)

    return evaluate
