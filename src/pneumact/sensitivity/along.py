"""Indices along time, and Sobol indices in doubling stages (convergence).

SALib analyses one scalar output at a time and has no notion of a signal; here a signal
on a time grid is many outputs (one per time), analysed together and returned as curves
of each index against time. Sobol samples of n and 2n base points share their first
n·(k + 2) runs (same scrambled sequence), so a convergence study evaluates the largest
sample once and analyses its growing prefixes.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..checks import check_int
from ..errors import ArgumentError, ParameterError
from ..options import Checkpoint, Executor
from ..plotting import tight_layout
from ..progress import ProgressCallback
from .methods import (
    Evaluate,
    SensitivityWarning,
    StudyResult,
    batch_evaluate,
    bootstrap_seed,
    check_sobol_n,
    sobol,
)
from .problem import Problem

__all__ = ["along_time", "local_along_time", "model_signal", "plot_along_loop",
           "plot_along_time", "plot_convergence", "sobol_convergence"]


def model_signal(model, experiment, problem: Problem, signal: str, times: Sequence[float],
                 *, executor: Executor | int | str | None = None,
                 checkpoint: Checkpoint | str | os.PathLike | None = None,
                 progress: ProgressCallback | None = None,
                 solver=None) -> Evaluate:
    """An ``evaluate`` giving ``signal`` at ``times`` (one output column per time, named
    by the time) from the batch engine; resumable from a ``checkpoint`` like
    ``model_outputs``."""
    return batch_evaluate(model, experiment, problem, signal=signal, times=times,
                          executor=executor, checkpoint=checkpoint, progress=progress,
                          solver=solver)


def along_time(study: StudyResult, index: str | None = None) -> pd.DataFrame:
    """One index of every parameter against time (rows: the times of the output columns;
    with ``index + '_conf'`` columns where the method gives a confidence interval)."""
    index = index or {"sobol": "ST", "morris": "mu_star", "src": "SRC",
                      "rbd_fast": "S1"}[study.method]
    wide = study.indices.pivot(index="output", columns="parameter", values=index)
    out = wide.loc[list(study.outputs.columns), list(study.sample.columns)]
    out.index = pd.Index([float(c) for c in out.index], name="time")
    out.columns.name = index
    return out


def local_along_time(model, experiment, parameters: Sequence[str], signal: str,
                     times: Sequence[float], *, values=None, solver=None) -> pd.DataFrame:
    """Local normalised sensitivities of ``signal`` at ``times`` from one forward
    sensitivity run: θ_i·∂y/∂θ_i / max|y| (the change of the signal, as a share of its
    range, per relative change of θ_i; dividing by max|y| rather than y(t) keeps the
    curves finite where the signal passes zero)."""
    from ..simulation import simulate_sensitivities

    grid = np.asarray(times, dtype=float)
    sens = simulate_sensitivities(model, experiment, list(parameters), solver, t_eval=grid,
                                  values=values)
    scale = float(np.max(np.abs(sens.result[signal])))
    curves = sens.relative(signal) / (scale if scale > 0 else 1.0)
    out = pd.DataFrame(curves, index=pd.Index(grid, name="time"), columns=sens.parameters)
    out.columns.name = f"normalised sensitivity of {signal}"
    return out


def sobol_convergence(problem: Problem, evaluate: Evaluate, n_max: int = 1024,
                      n_min: int = 64, seed: int = 0, target_width: float | None = 0.1
                      ) -> tuple[StudyResult, pd.DataFrame]:
    """Sobol indices at n = n_min, 2·n_min, … n_max base points from one evaluation of
    the largest sample. Returns (the final study, a table of S1, ST and their CI widths
    per output, parameter and n). Warns, naming the n to try, when a CI at n_max is
    wider than ``target_width`` (CI widths shrink as 1/√n)."""
    from SALib.analyze import sobol as analyze

    n_min = check_int("n_min", n_min, minimum=1, where="sobol_convergence")
    if n_min & (n_min - 1):
        raise ArgumentError(f"sobol_convergence: n_min = {n_min}: must be a power of two "
                            "(the prefixes of a Sobol sequence are balanced only then)")
    n_max = check_int("n_max", n_max, minimum=n_min, where="sobol_convergence")
    check_sobol_n(n_min * 2 ** int(np.log2(n_max / n_min)), where="sobol_convergence",
                  name="the largest sample n_max")
    sizes = [n_min * 2**s for s in range(int(np.log2(n_max / n_min)) + 1)]
    salib = problem.to_salib()
    final = sobol(problem, evaluate, sizes[-1], seed=seed)  # the largest sample, once
    rows = []
    k = len(problem.names)
    for n in sizes:
        runs = n * (k + 2)
        for column in final.outputs.columns:
            y = final.outputs[column].to_numpy(float)[:runs]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                res = analyze.analyze(salib, y, calc_second_order=False,
                                       seed=bootstrap_seed(seed))
            for j, name in enumerate(problem.names):
                rows.append({"output": column, "parameter": name, "n": n, "runs": runs,
                             "S1": res["S1"][j], "S1_width": 2 * res["S1_conf"][j],
                             "ST": res["ST"][j], "ST_width": 2 * res["ST_conf"][j]})
    table = pd.DataFrame(rows)
    if target_width is not None:
        last = table[table["n"] == sizes[-1]]
        widest = float(last[["S1_width", "ST_width"]].max().max())
        if widest > target_width:
            needed = int(2 ** np.ceil(np.log2(sizes[-1] * (widest / target_width) ** 2)))
            warnings.warn(f"Sobol confidence intervals at n = {sizes[-1]} are up to "
                          f"{widest:.3g} wide (asked: {target_width}); try n = {needed}",
                          SensitivityWarning, stacklevel=2)
    return final, table


def plot_along_time(study: StudyResult | pd.DataFrame, index: str | None = None):
    """Each parameter's index against time, with its confidence band where the method
    gives one (``study``: a study of a signal, or curves from ``local_along_time``)."""
    import matplotlib.pyplot as plt

    curves = study if isinstance(study, pd.DataFrame) else along_time(study, index)
    bands = None if isinstance(study, pd.DataFrame) else _bands(study, curves.columns.name)
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    for name in curves.columns:
        line, = ax.plot(curves.index, curves[name], label=name)
        if bands is not None:
            ax.fill_between(curves.index, curves[name] - bands[name],
                            curves[name] + bands[name], color=line.get_color(), alpha=0.2)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(curves.columns.name)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    tight_layout(fig)
    return fig


def _bands(study: StudyResult, index: str) -> pd.DataFrame | None:
    """Half-widths of the index's confidence intervals against time, if it has any."""
    if f"{index}_conf" not in study.indices:
        return None
    return along_time(study, f"{index}_conf")


def plot_along_loop(curves: pd.DataFrame, x: ArrayLike, xlabel: str):
    """Index curves (rows: times) against another signal at the same times, e.g. the
    applied pressure of a cycle, so the indices are read along the hysteresis loop."""
    import matplotlib.pyplot as plt

    x = np.asarray(x, dtype=float)
    if x.shape != (len(curves),):
        raise ParameterError(f"plot_along_loop: x has {x.size} values for {len(curves)} "
                             "times")
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    for name in curves.columns:
        ax.plot(x, curves[name], ".-", label=name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(curves.columns.name)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    tight_layout(fig)
    return fig


def plot_convergence(table: pd.DataFrame, output: str):
    """S1 and ST with their CI widths against the base sample size n (log axis)."""
    import matplotlib.pyplot as plt

    sub = table[table["output"] == output]
    fig, (ax, axw) = plt.subplots(1, 2, figsize=(10, 3.6))
    for name, rows in sub.groupby("parameter", sort=False):
        line, = ax.plot(rows["n"], rows["ST"], "o-", label=f"{name} ST")
        ax.plot(rows["n"], rows["S1"], "s--", color=line.get_color(), alpha=0.6)
        axw.loglog(rows["n"], rows["ST_width"], "o-", color=line.get_color(), label=name)
    ax.set_xscale("log", base=2)
    ax.set_xlabel("base sample size n")
    ax.set_ylabel("S1 (dashed), ST")
    axw.set_xlabel("base sample size n")
    axw.set_ylabel("width of the ST interval")
    ax.legend(fontsize=7)
    for a in (ax, axw):
        a.grid(True, alpha=0.3)
    tight_layout(fig)
    return fig
