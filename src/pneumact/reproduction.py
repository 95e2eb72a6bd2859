"""The seed paper reproduced end to end: one call, one folder, one index report.

``reproduce()`` runs, on the built-in ``vgt-paper`` set (the paper's Table I):

1. Table I as loaded, with the values the paper does not give marked as assumed;
2. the pneumatic half (eqs. 2–5): Φ(r) and its choked limit (the flow stays ∝ p_up), the
   chamber's step response through the valve, its time constant along the stroke, the
   natural frequencies free and stuck on the bristles, and every modelling choice with
   its source (``MODEL_CHOICES``, docs/model.md);
3. Fig. 2: LuGre friction against velocity, with the steady-state (Stribeck) curve;
4. Fig. 3: friction against velocity under each of the paper's parameter variations,
   whole and zoomed, and its effects across velocity amplitudes with their noise floor;
5. Fig. 5 a–f: pressure–position loops under the same variations, whole and zoomed, and
   the same study across operating conditions (the applied pressure first, then the
   command valve and the regulator, read as the sliding speed in units of vs), with σ0
   at ×0.1 … ×10, the noise floor of the loop change, and LuGre against Dahl and δ = 2;
6. the identification procedure of section III.2 on a synthetic bench campaign generated
   from Table I with measurement noise (the paper's bench data is not public), with
   stage (d) zoomed on its window in µm, then on campaigns made by richer models
   (``RICHER_CASES``: what it identifies, its errors, the faults it names), and the
   condition under which eq. 13 gives Fc and σ2;
7. Fig. 6: the identified model against a held-back record, labelled self-consistent,
   and against records made by richer models (``RICHER_CASES``); then real friction
   (the TU Delft seal records, ``seal_data``): eq. 13 identified at two supply
   pressures and predicted at the others;
8. the sensitivity ranking (SRC² and Sobol with their intervals, rank groups, Sobol's
   sample size chosen by the convergence check; one at a time at the paper's unequal
   amounts in its own table) and SRC² across conditions;
9. every statement of the paper, one parameter at a time (``pneumact.statements``), with
   the range of conditions in which it holds, where it stops, and its noise floor.

``quick=True`` shrinks the campaign, the conditions and the samples for the test suite
(and runs fewer richer campaigns, saying which it left out); every figure is still
produced.

On a machine with more than one CPU the work is split over one spawned worker process
beside the main one (``_Beside``): the full mode's worker runs two parts that depend on no
other section, the identification on the richer models' campaigns and SRC² across
conditions at the slower cycles (``Sizes.global_apart_from``); the quick mode's runs whole
sections that need no other's result (``INDEPENDENT``, ``Sizes.apart``: Figs. 2, 3 and 5,
Fig. 5 across conditions and the pneumatics, figures included). Each section writes into
parts of its own, joined in the report's order at the end: the same calls with the same
seeds, so the same numbers, tables and figures; only their wall time overlaps.
"""

from __future__ import annotations

import functools
import os
import time
import warnings
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from .io.report import NotebookDisplay
from .plotting import tight_layout
from .progress import ProgressCallback, check_progress, notify

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .io.report import Report
    from .parameters.parameter_set import ParameterSet

__all__ = ["CYCLE_PERIOD", "Reproduction", "reproduce"]

FEATURES = ("loop_width_pressure", "breakaway_pressure")
#: The features the one-at-a-time study across conditions needs (``statements``).
LOOP_FEATURES = ("loop_width_pressure", "breakaway_pressure", "loop_width_position",
                 "presliding_travel")
#: The reproduction's own cycle: the command valve driven 0 → 1 → 0 in this period [s].
CYCLE_PERIOD = 20.0
#: The valves of the global index across conditions (the applied pressure first).
GLOBAL_VALVES = ("source", "command")
#: The velocity sine of Fig. 3: amplitude in units of vs and period [s].
FIG3_AMPLITUDE_VS = 10.0
FIG3_PERIOD = 2.0
#: The lowest speed of the identification's sliding stage, in units of vs (5 mm/s).
STAGE_B_LOWEST_VS = 10.0
#: The cycle period [s] from which SRC² across conditions runs beside the sections (in
#: the full mode's worker: ``Sizes.global_apart_from``).
GLOBAL_SLOW_FROM = 40.0
#: the sections ``reproduce`` reports progress on, in order
SECTIONS = ("Table I", "pneumatics", "Figs. 2 and 3", "Fig. 5", "Fig. 5 across conditions",
            "identification", "Fig. 6", "sensitivity", "statements", "writing")


@dataclass(frozen=True)
class Sizes:
    """How much work each part does (the quick mode shrinks the samples and conditions)."""

    ramp_speeds: tuple[float, ...]
    sweep_period: float
    src_n: int
    #: the largest Sobol base sample; the convergence check stops earlier when it can
    sobol_n: int
    periods: tuple[float, ...]
    valves: tuple[str, ...]
    condition_n: int
    amplitudes_vs: tuple[float, ...]
    eq13_lowest_vs: tuple[float, ...] = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0)
    #: the Sobol base sample the convergence check starts from
    sobol_min_n: int = 64
    #: shorter cycles behind the pressure source only (the valves cannot slide that fast)
    fast_source_periods: tuple[float, ...] = (0.5, 1.0, 2.0)
    #: longer cycles behind the pressure source only: the slow end of the speed axis,
    #: where the statements' v ≲ vs verdicts are read, without the valves' slow cycles
    #: (their stiff chamber makes the command valve's 320 s cycle the costliest study:
    #: the quick mode leaves it out)
    slow_source_periods: tuple[float, ...] = ()
    #: the models that make Fig. 6's held-back record (``RICHER_CASES``)
    richer_cases: tuple[str, ...] = ("self-consistent", "δ = 2", "GMS-4",
                                     "adiabatic chamber", "5 µm steps, 5 ms lag")
    #: the richer models the identification's campaign is also made by, and that
    #: campaign's ramp speeds [m/s] and sweep period [s] (smaller than the main one)
    richer_identification: tuple[str, ...] = ("δ = 2", "GMS-4", "adiabatic chamber",
                                              "5 µm steps, 5 ms lag")
    richer_ramp_speeds: tuple[float, ...] = (2e-4, 1e-3, 5e-3, 2e-2)
    richer_sweep_period: float = 30.0
    #: the richer cases the main process identifies itself, after its other sections
    #: (the others run in the worker): they balance the two processes' work
    richer_here: tuple[str, ...] = ()
    #: the sections (``INDEPENDENT``) a worker process runs beside the others, in the
    #: order it runs them (``_Beside``; the full mode's worker has jobs of its own)
    apart: tuple[str, ...] = ()
    #: the cycle period [s] from which SRC² across conditions runs in the worker
    global_apart_from: float = GLOBAL_SLOW_FROM

    def periods_of(self, valve: str, fast: bool = True) -> tuple[float, ...]:
        """The cycle periods [s] run behind ``valve``, shortest first: ``periods``, and
        behind the source also ``slow_source_periods`` and (``fast``)
        ``fast_source_periods``."""
        if valve != "source":
            return self.periods
        return tuple(sorted({*(self.fast_source_periods if fast else ()), *self.periods,
                             *self.slow_source_periods}))

    def conditions(self, valves: Sequence[str], fast: bool = True) -> list:
        """The conditions (``sensitivity.Condition``) behind each of ``valves`` at its
        periods (``periods_of``)."""
        from .sensitivity import conditions

        return [c for valve in valves
                for c in conditions(self.periods_of(valve, fast), valves=(valve,))]

    def global_conditions(self, slow: bool | None = None) -> list:
        """SRC² across conditions' conditions (``GLOBAL_VALVES``, no fast cycles): all,
        or those from ``global_apart_from`` (``slow``) or below it (not ``slow``)."""
        every = self.conditions(GLOBAL_VALVES, fast=False)
        if slow is None:
            return every
        return [c for c in every if (c.period >= self.global_apart_from) == slow]

    @classmethod
    def full(cls) -> Sizes:
        return cls((1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 3e-2, 4e-2), 60.0, 512,
                   512, (5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0),
                   ("source", "command", "regulator"), 64,
                   (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0),
                   richer_here=("δ = 2", "adiabatic chamber"))

    @classmethod
    def quick(cls) -> Sizes:
        return cls((2e-4, 1e-3, 5e-3, 2e-2), 30.0, 64, 32, (20.0,),
                   ("source", "command"), 32, (2.0, 10.0, 100.0),
                   fast_source_periods=(1.0,), slow_source_periods=(320.0,), sobol_min_n=8,
                   richer_identification=(),
                   richer_cases=("self-consistent", "δ = 2", "5 µm steps, 5 ms lag"),
                   apart=("Fig. 5", "Figs. 2 and 3", "Fig. 5 across conditions",
                          "pneumatics"), global_apart_from=np.inf)


@dataclass(eq=False)
class Reproduction(NotebookDisplay):
    """What ``reproduce`` computed (tables in SI) and the files it wrote.

    ``to_pandas(name)``: a table by name (default "paper_statements": where each of the
    paper's statements holds); ``plot(name)``: a figure it wrote (default Fig. 5's
    loops), shown in a matplotlib Figure; ``write(folder)``: every file again in
    ``folder``, with report.html (the same page as index.html)."""

    out_dir: Path
    files: list[Path]
    tables: dict[str, pd.DataFrame]
    wall_time: float
    quick: bool
    identified: ParameterSet | None = None

    @property
    def report(self) -> Path:
        return self.out_dir / "index.html"

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The table ``name`` (default "paper_statements"; ``tables`` has them all)."""
        from .errors import ArgumentError

        name = name or "paper_statements"
        if name not in self.tables:
            raise ArgumentError(f"to_pandas: name = {name!r}; allowed: "
                                f"{', '.join(self.tables)}")
        return self.tables[name]

    def figure_names(self) -> list[str]:
        """The figures it wrote (their file names without .png)."""
        return [f.stem for f in self.files if f.suffix == ".png"]

    def plot(self, name: str | None = None) -> Figure:
        """The figure ``name`` it wrote (default "fig5_loops"), read back from its PNG
        file into a matplotlib Figure (the data behind it are in ``tables``)."""
        import matplotlib.image
        import matplotlib.pyplot as plt

        from .errors import ArgumentError

        name = name or "fig5_loops"
        if name not in self.figure_names():
            raise ArgumentError(f"plot: name = {name!r}; allowed: "
                                f"{', '.join(self.figure_names())}")
        image = matplotlib.image.imread(self.out_dir / f"{name}.png")
        fig, ax = plt.subplots(figsize=(image.shape[1] / 100, image.shape[0] / 100))
        ax.imshow(image)
        ax.set_axis_off()
        return fig

    def write(self, out_dir: str | os.PathLike[str], *, call: str = "") -> list[Path]:
        """Every file of the reproduction again in ``out_dir``, and report.html (the
        page index.html is), all or nothing; ``call`` is not used (the page records the
        call that made it)."""
        import shutil

        from .io.tables import write_files

        writers = {f.name: functools.partial(shutil.copyfile, f) for f in self.files}
        writers["report.html"] = functools.partial(shutil.copyfile, self.report)
        return write_files(out_dir, writers)


@dataclass(eq=False)
class _Parts:
    """Tables, figures and report blocks gathered along the way (a section's own, made
    in a worker, travel back as one: their writers are plain functions of their data)."""

    report: Report
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    writers: dict[str, Callable[[Path], object]] = field(default_factory=dict)

    def table(self, name: str, frame: pd.DataFrame, caption: str, index: bool = False):
        self.tables[name] = frame
        self.writers[f"{name}.csv"] = functools.partial(_write_csv, frame, index)
        self.report.table(frame, caption, index=index)

    def figure(self, name: str, make, caption: str):
        """Render once: the PNG file and the report's embedded copy."""
        from .io.report import figure_png

        png = figure_png(make(), dpi=120)
        self.writers[f"{name}.png"] = functools.partial(_write_bytes, png)
        self.report.image(png, caption)

    def insert(self, part: _Parts, at: int) -> None:
        """Put ``part``'s blocks (no headings) at ``at`` of this report, its tables and
        files with these."""
        self.report.blocks[at:at] = part.report.blocks
        self.tables.update(part.tables)
        self.writers.update(part.writers)

    def extend(self, section: _Parts) -> None:
        """Append a section's blocks (its headings numbered in this report), tables and
        files."""
        for block in section.report.blocks:
            if block.kind == "heading":
                self.report.heading(block.content)
            else:
                self.report.blocks.append(block)
        self.tables.update(section.tables)
        self.writers.update(section.writers)


def _write_csv(frame: pd.DataFrame, index: bool, path: Path) -> None:
    frame.to_csv(path, index=index)


def _write_bytes(data: bytes, path: Path) -> None:
    Path(path).write_bytes(data)


def _beside_worker_start() -> None:
    """A ``_Beside`` worker: Ctrl-C is the parent's to handle (it stops the worker), and
    on Linux the worker ends with its parent."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class _Beside:
    """Jobs ``{name: (function, args)}`` that no section's result feeds, run one after
    another in one spawned worker process while the sections run here (where more than
    one CPU is available; ``worker`` and ``BESIDE``); ``result(name)`` waits for one.
    Without a worker (one CPU, or the worker could not start or died) a job runs here
    when its result is asked for, and so do the jobs named in ``here`` (those with
    nothing to do: queued behind the worker's others, their result would keep a section
    waiting for all of them). Leaving the ``with`` block stops the worker."""

    def __init__(self, jobs: dict[str, tuple[Callable, tuple]], worker: bool = True,
                 here: Collection[str] = ()) -> None:
        self.jobs = jobs
        self.futures: dict = {}
        self.pool = None
        if not (worker and BESIDE) or _cpus() < 2:
            return
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        try:
            self.pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                            initializer=_beside_worker_start)
            self.futures = {name: self.pool.submit(job, *args)
                            for name, (job, args) in jobs.items() if name not in here}
        except OSError:
            self.close()

    def result(self, name: str):
        """The job's result (its exception raised here), once it is done."""
        from concurrent.futures.process import BrokenProcessPool

        future = self.futures.pop(name, None)
        if future is not None:
            try:
                result = future.result()
            except BrokenProcessPool:
                self.close(stop=True)
            else:
                if not self.futures:  # the last job: the worker is done
                    self.close()
                return result
        job, args = self.jobs[name]
        return job(*args)

    def close(self, stop: bool = False) -> None:
        """Let the worker go (``stop``: end it first, its jobs unfinished)."""
        pool, self.pool, self.futures = self.pool, None, {}
        if pool is not None:
            if stop:
                for process in list((getattr(pool, "_processes", None) or {}).values()):
                    process.terminate()
            pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> _Beside:
        return self

    def __exit__(self, kind, *exc) -> None:
        self.close(stop=kind is not None or bool(self.futures))  # a failure, Ctrl-C


#: the name of a richer case's job (``beside_jobs``): this prefix and the case
RICHER_JOB = "richer: "


def beside_jobs(params, sizes: Sizes, seed: int) -> tuple[dict[str, tuple[Callable, tuple]],
                                                          list[str]]:
    """The jobs no section's result feeds (``_Beside``), in the worker's order, and those
    of them run here: eq. 13's bias first (the identification asks for it early; it
    needs numba, which Figs. 2 and 3 load: here when they run here), the sections
    ``sizes.apart``, SRC² across conditions at the slow cycles (the sensitivity section
    asks for it), then each richer campaign's identification (asked for last; here those
    of ``sizes.richer_here``); a job with nothing to do runs here (queued behind the
    others, its result would keep a section waiting for all of them)."""
    from .statements import eq13_bias

    jobs: dict[str, tuple[Callable, tuple]] = {
        "eq13": (eq13_bias, (params, sizes.eq13_lowest_vs)),
        **{name: (_section_apart, (name, params, sizes)) for name in sizes.apart},
        "global_across": (_global_across, (params, sizes, seed, True)),
        **{f"{RICHER_JOB}{case}": (richer_row, (params, sizes, seed, case))
           for case in richer_cases(sizes)}}
    slow = sizes.global_conditions(slow=True)
    here = [name for name, run_here in (
        ("eq13", "Figs. 2 and 3" not in sizes.apart), ("global_across", not slow),
        *((f"{RICHER_JOB}{case}", case in sizes.richer_here)
          for case in richer_cases(sizes))) if run_here]
    return jobs, here


def _cpus() -> int:
    """The CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):  # not on macOS or Windows
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


#: Whether ``reproduce`` runs its independent jobs in a worker process (``_Beside``).
BESIDE = True


def reproduce(out_dir: str | os.PathLike = "pneumact-paper", *, quick: bool = False,
              params="vgt-paper", seed: int = 0, call: str = "",
              progress: ProgressCallback | None = None,
              seal_data: str | os.PathLike | None = None) -> Reproduction:
    """Reproduce the paper into ``out_dir`` (index.html, CSV tables, PNG figures).
    ``progress`` is called with a ``pneumact.progress.Progress`` as each section starts
    (its name, sections done of all). ``seal_data``: the folder of the TU Delft
    cylinder's seal records (``O-ring_<p>bar.csv``, CC0), for the section on real
    friction data; without it the section says how to run it."""
    import matplotlib

    from .checks import check_bool, check_out_dir, check_seed

    check_out_dir("out_dir", out_dir, where="reproduce")
    check_bool("quick", quick, where="reproduce")
    check_seed("seed", seed, where="reproduce")
    check_progress(progress, "reproduce")
    if seal_data is not None:
        seal_data = _seal_folder(seal_data)
    from .errors import PassivityWarning
    from .io.report import Report
    from .io.tables import write_files
    from .parameters import ParameterSet, load_params
    from .parameters.validation import lugre_passivity_problem

    matplotlib.use("Agg")
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PassivityWarning)
        params = params if isinstance(params, ParameterSet) else load_params(params)
    passivity = [str(w.message) for w in caught if issubclass(w.category, PassivityWarning)]
    passivity = passivity or [lugre_passivity_problem(params.values) or ""]
    sizes = Sizes.quick() if quick else Sizes.full()
    jobs, here = beside_jobs(params, sizes, seed)
    report = Report("LuGre friction in a pneumatic diaphragm actuator: the paper reproduced",
                    call=call or f"pneumact.reproduce(quick={quick}, seed={seed})",
                    parameters=params)
    parts = _Parts(report)
    _introduction(report, params, sizes, quick)
    headline_at = len(report.blocks)  # the statements' verdicts lead: filled in at the end
    done: dict[str, tuple[_Parts, object]] = {}
    with _Beside(jobs, here=here) as beside:

        def section(name: str,
                    run: Callable[[_Parts, ParameterSet, Sizes], Any] | None = None) -> Any:
            """The section's value: run here into parts of its own, or taken from the
            worker (``sizes.apart``); its parts join the report in ``SECTIONS`` order."""
            if name not in done:
                notify(progress, name, len(done), len(SECTIONS))
                if name in sizes.apart:
                    done[name] = beside.result(name)
                else:
                    own = _Parts(Report(name))
                    done[name] = own, (run or INDEPENDENT[name])(own, params, sizes)
            return done[name][1]

        section("Table I", lambda own, *_: _table_one(own, params,
                                                      [text for text in passivity if text]))
        for name in INDEPENDENT:
            if name not in sizes.apart:
                section(name)

        richer_at: list[int] = []  # where the richer campaigns' table goes, at the end

        def identification(own: _Parts, *_) -> tuple:
            identified = _identification(own, params, sizes, seed)
            richer_at.append(len(own.report.blocks))
            return identified, _eq13(own, beside.result("eq13"))

        def validation(own: _Parts, *_) -> None:
            _validation(own, params, identified, sizes, seed)
            _seal_friction(own, seal_data)

        identified, bias = section("identification", identification)
        section("Fig. 6", validation)
        global_study = section("sensitivity", lambda own, *_: _sensitivity(
            own, params, lambda: section("Fig. 5"), sizes, seed, beside))
        for name in sizes.apart:
            section(name)
        effects, friction_floor = section("Figs. 2 and 3")
        across, loop_floor = section("Fig. 5 across conditions")
        richer = _Parts(Report("richer"))
        _identification_richer(richer, sizes, [beside.result(f"{RICHER_JOB}{case}")
                                               for case in richer_cases(sizes)])
        done["identification"][0].insert(richer, richer_at[0])
    for name in SECTIONS[:SECTIONS.index("statements")]:
        parts.extend(done[name][0])
    notify(progress, "statements", len(done), len(SECTIONS))
    summary = _statements(parts, across, global_study, effects, bias, loop_floor,
                          friction_floor)
    _lead_with(report, headline_at, summary)
    notify(progress, "writing", len(done) + 1, len(SECTIONS))
    parts.writers["index.html"] = report.write
    files = write_files(out_dir, parts.writers)
    notify(progress, "done", len(SECTIONS), len(SECTIONS))
    return Reproduction(Path(out_dir), files, parts.tables, time.perf_counter() - started,
                        quick, identified.parameters)


#: The sections that need no other section's result: each ``(parts, params, sizes)``,
#: in the report's order; a worker may run them (``Sizes.apart``).
INDEPENDENT: dict[str, Callable[[_Parts, ParameterSet, Sizes], object]] = {
    "pneumatics": lambda parts, params, sizes: _pneumatics(parts, params),
    "Figs. 2 and 3": lambda parts, params, sizes: _friction_figures(parts, params, sizes),
    "Fig. 5": lambda parts, params, sizes: _loops_figure(parts, params),
    "Fig. 5 across conditions": lambda parts, params, sizes: _loops_across_conditions(
        parts, params, sizes),
}


def _section_apart(name: str, params, sizes: Sizes) -> tuple[_Parts, object]:
    """An ``INDEPENDENT`` section into parts of its own (a job of ``_Beside``): its
    blocks, tables and figures, and its value."""
    import matplotlib

    from .io.report import Report

    matplotlib.use("Agg")
    own = _Parts(Report(name))
    return own, INDEPENDENT[name](own, params, sizes)


# --------------------------------------------------------------------------- sections
def _introduction(report, params, sizes: Sizes, quick: bool) -> None:
    from .statements import VISIBLE

    report.text(
        "Each section below recomputes one result of the seed paper from the parameter set "
        f"'{params.name}'. The paper's Figs. 5 and 6 plot position against the applied "
        "pressure at a cycle speed it does not give, and LuGre friction changes character "
        "around the Stribeck velocity vs, so its statements are read first across cycle "
        f"speeds under the applied pressure (the pressure source; periods "
        f"{', '.join(f'{p:g}' for p in sizes.periods_of('source'))} s), "
        f"then behind the other valves ({', '.join(v for v in sizes.valves if v != 'source')}"
        "), each condition read as its sliding speed v (measured over 20–80 % of the stroke "
        "of the nominal run) in units of vs = "
        f"{1e3 * params['vs']:g} mm/s. The figures of Fig. 5 and the sensitivity ranking "
        f"run the command valve (u 0 → 1 → 0) over a {CYCLE_PERIOD:g} s cycle (the "
        "paper's bench drives a pressure regulator; the valve adds the chamber dynamics). "
        f"Fig. 3 uses a velocity sine of ±{FIG3_AMPLITUDE_VS:g}·vs over {FIG3_PERIOD:g} s "
        f"and is checked across amplitudes "
        f"{', '.join(f'{a:g}' for a in sizes.amplitudes_vs)}·vs. A change of the loop is "
        f"called visible (the paper's 'important', 'impact') from {100 * VISIBLE:g} % of the "
        "loop's own width, and every verdict states the noise floor of its measure; the "
        "break-away pressure is where the sliding line meets the rest position (no motion "
        "threshold). The identification and Fig. 6 run on records simulated from the same "
        "model (self-consistency, labelled so) and on records from richer models. "
        + ("Quick mode: small campaign, few conditions and small samples (for tests); the "
           "numbers are rough." if quick else ""))


def _friction_figures(parts: _Parts, params, sizes: Sizes) -> pd.DataFrame:
    from . import sensitivity as sa
    from .statements import friction_effects, friction_noise

    parts.report.heading("Figs. 2 and 3: LuGre friction against velocity")
    parts.figure("fig2_friction_velocity", lambda: _fig2(params),
                 f"Fig. 2: friction of a velocity sine (±{FIG3_AMPLITUDE_VS:g}·vs = "
                 f"±{FIG3_AMPLITUDE_VS * 1e3 * params['vs']:g} mm/s, {FIG3_PERIOD:g} s; the "
                 "bristles' hysteresis) and the steady-state (Stribeck) curve")
    curves = sa.friction_velocity(params, amplitude=FIG3_AMPLITUDE_VS * params["vs"],
                                  period=FIG3_PERIOD)
    parts.figure("fig3_friction_variations", lambda: curves.plot(zoom=True),
                 "Fig. 3: friction against velocity, each parameter at its low and high value "
                 "(the paper's amounts): the whole curve, low speeds |v| ≤ 4·vs (presliding "
                 "and the Stribeck drop, where σ0, σ1 and vs act) and the fastest 20 % (the "
                 "sliding level, where Fc and σ2 act)")
    effects = friction_effects(params, sizes.amplitudes_vs, FIG3_PERIOD)
    floor = friction_noise(params, sizes.amplitudes_vs, FIG3_PERIOD)
    wide = effects.pivot(index="amplitude_vs", columns="parameter",
                         values=["dynamic", "steady"])
    wide.columns = [f"{kind} {name}" for kind, name in wide.columns]
    wide = wide.reset_index().merge(floor, on="amplitude_vs")
    parts.table("fig3_effects", wide,
                f"Fig. 3 across velocity amplitudes (sine of {FIG3_PERIOD:g} s): RMS change of "
                "the steady-state curve F_ss(v) ('steady') and of the rest F − F_ss(v) "
                "('dynamic') under each variation, as a share of Fc; 'noise': the nominal "
                "run against a 100× tighter tolerance (the measures' floor). vs is a "
                "parameter of the steady-state (Stribeck) curve: it moves both")
    return effects, floor


def _loops_figure(parts: _Parts, params):
    from . import sensitivity as sa
    from .experiments import CommandCycle
    from .models import Actuator, CommandValve
    from .sensitivity.oat import DEFAULT_FEATURES

    model = Actuator(params, valve=CommandValve())
    oat = sa.one_at_a_time(model, CommandCycle(period=CYCLE_PERIOD),
                           features=(*DEFAULT_FEATURES, "sliding_speed", "presliding_travel"))
    speed = float(oat.runs["sliding_speed"].iloc[0])
    parts.report.heading("Fig. 5 a–f: pressure–position loops under the paper's variations")
    parts.report.text(
        f"The {CYCLE_PERIOD:g} s command cycle slides at {1e3 * speed:.3g} mm/s = "
        f"{speed / params['vs']:.3g}·vs over the middle of the stroke: there g(v) ≈ Fc, so "
        "static friction hardly shows. Over the whole stroke only Fc moves the loop "
        "visibly; the zoomed panels show the corners where σ0, σ1 and vs act.")
    parts.figure("fig5_loops", lambda: oat.plot_loops(zoom=True),
                 "Fig. 5: one row per parameter, varied by the paper's amounts (σ0 50 %, "
                 "σ1 68 %, σ2 90 %, Fs 16 %, Fc 15.36 %; vs 50 %, ours: the paper gives "
                 "none), command valve, "
                 f"{CYCLE_PERIOD:g} s cycle: the whole loop, at the break-away (where the "
                 "diaphragm leaves rest) and at the low-pressure reversal")
    parts.table("oat_runs", oat.runs, "One at a time (eq. 15): features of every run and "
                                      "their change against the nominal run (SI)")
    return oat


def _loops_across_conditions(parts: _Parts, params, sizes: Sizes):
    from . import sensitivity as sa
    from .models import Actuator
    from .sensitivity.operating import CONDITION_COLUMNS
    from .statements import (
        SIGMA0_FACTORS,
        VISIBLE,
        law_changes,
        loop_changes,
        loop_noise,
        plot_loop_changes,
        run_changes,
        variations_for,
    )

    conditions = sizes.conditions(sizes.valves)
    model = Actuator(params)
    study = sa.across_conditions(model, conditions, "oat", features=LOOP_FEATURES,
                                 variations=variations_for(params))
    floor = loop_noise(model, conditions)
    changes = loop_changes(study)
    parts.report.heading("Fig. 5 across operating conditions")
    parts.report.text(
        "The paper's Figs. 5 and 6 are position against the applied pressure at a cycle "
        "speed it does not give, so the statements are read across cycle speeds first "
        "behind the pressure source (the applied pressure), then behind the command valve "
        "and the regulator (their chamber dynamics slow and shape the stroke). The loop "
        "change of a variation is the largest of its change of the loop width and of the "
        "break-away pressure (both over the nominal loop width in pressure) and of the "
        "presliding travel at the reversal (over the loop width in position); visible "
        f"from {100 * VISIBLE:g} %. Its noise floor at each condition is the same measure "
        "between the nominal run and its reruns at a 100× tighter tolerance and on a finer "
        "output grid (table below): a verdict within it is reported as such.")
    table = study.conditions[list(CONDITION_COLUMNS)].merge(
        floor.rename(columns={"change": "noise floor"})[["condition", "noise floor"]],
        on="condition")
    parts.table("conditions", table,
                "The conditions: valve, cycle period [s], amplitude (share of the full cycle) "
                "and the sliding speed of the nominal run [m/s], also in units of vs; the "
                "noise floor of the loop change (share of the loop's width)")
    parts.figure("fig5_changes_by_speed", lambda: plot_loop_changes(changes, floor),
                 "Loop change of each parameter at the paper's amounts against v/vs, a panel "
                 f"per valve; dashed: the {100 * VISIBLE:g} % visibility line; grey: the "
                 "noise floor")
    wide = changes.pivot_table(index=["valve", "period", "speed_vs"], columns="parameter",
                               values="change").reset_index().rename_axis(columns=None)
    parts.table("fig5_changes", wide, "Loop change per condition (share of the loop's width)")
    every = run_changes(study)
    sigma0 = every[every["parameter"] == "sigma0"].pivot_table(
        index=["valve", "period", "speed_vs"], columns="factor", values="change")
    sigma0.columns = [f"σ0 ×{f:g}" for f in sigma0.columns]
    parts.table("fig5a_sigma0_factors", sigma0.reset_index(),
                "Fig. 5a as the paper words it (σ0 matters when changed by more than 50 %): "
                f"the loop change at σ0 × {', '.join(f'{f:g}' for f in SIGMA0_FACTORS)} "
                "(and ×1.5, the paper's +50 %) per condition (share of the loop's width)")
    laws = law_changes(model, [c for c in conditions if c.valve == "source"], floor)
    parts.table("law_changes", laws,
                "The friction law itself under the applied pressure: the loop change when "
                "LuGre is replaced by Dahl (the paper: 'similar results') and δ = 1 by "
                f"δ = 2, against the {100 * VISIBLE:g} % visibility line and the noise floor")
    return study, floor


def _eq13(parts: _Parts, bias: pd.DataFrame) -> pd.DataFrame:
    """Eq. 13's text and table from its ``bias`` (``statements.eq13_bias``)."""
    from .statements import EQ13_FC_RTOL, EQ13_TOP_SPEED

    parts.report.text(
        "Eq. 13 (Fc·sgn(v) + σ2·v) holds only where g(v) has dropped to Fc. Fitted to the "
        f"model's own steady-state curve from a lowest speed up to {1e3 * EQ13_TOP_SPEED:g} "
        f"mm/s, it gives Fc within {100 * EQ13_FC_RTOL:g} % once the lowest speed is above "
        "the boundary in the statements' table; the identification's sliding stage starts at "
        f"{STAGE_B_LOWEST_VS:g}·vs.")
    parts.table("eq13", bias, "Eq. 13 fitted from each lowest speed (in units of vs): the "
                              "relative errors of Fc and σ2")
    return bias


#: Richer models the held-back record is made by (Fig. 6 beyond self-consistency): the
#: case, and what differs from the model that is validated.
RICHER_CASES = (
    ("self-consistent", "the record is simulated by the validated model itself (Table I, "
                        "LuGre δ = 1, isothermal), 20 Pa and 1 µm noise, 1 µm steps"),
    ("δ = 2", "LuGre with the Gaussian Stribeck curve exp(−(v/vs)²)"),
    ("GMS-4", "generalized Maxwell-slip friction, four blocks matched to Table I "
              "(vgt-paper-gms4)"),
    ("adiabatic chamber", "the chamber gas adiabatic (n = γ) instead of isothermal"),
    ("5 µm steps, 5 ms lag", "the position sensor quantised to 5 µm (a 12-bit potentiometer "
                             "over 20 mm) behind a 5 ms first-order lag"),
)


def _richer_record(params, case: str, sweep, seed: int):
    """The held-back sweep as a richer model (``RICHER_CASES``) records it."""
    from .identification import Noise, synthetic_campaign
    from .models import GMS, Adiabatic
    from .parameters import load_params

    options: dict = {}
    if case == "δ = 2":
        params = params.replace(delta=2.0)
    elif case == "GMS-4":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            params = load_params("vgt-paper-gms4")
        options["friction"] = GMS(n_elements=4)
    elif case == "adiabatic chamber":
        options["chamber"] = Adiabatic()
    elif case == "5 µm steps, 5 ms lag":
        options["noise"] = Noise(resolution=5e-6, lag=5e-3)
    return synthetic_campaign(params, sweep, seed=seed, **options)


def _validation(parts: _Parts, params, identified, sizes: Sizes, seed: int) -> None:
    from .identification import paper_campaign
    from .io.records import PRESSURE_SIGNAL
    from .models import Actuator, PressureRegulator
    from .validation import validate

    sweep = paper_campaign(params, speeds=(), sweep_period=2 * sizes.sweep_period)[:1]
    model = Actuator(identified.parameters, valve=PressureRegulator())
    results = {case: validate(model, _richer_record(params, case, sweep, seed + 1),
                              signals=("position", PRESSURE_SIGNAL))
               for case, _ in RICHER_CASES if case in sizes.richer_cases}
    validation = results["self-consistent"]
    criteria = validation.criteria
    parts.report.heading("Fig. 6: the identified model against a held-back record")
    parts.report.note("Self-consistency, not validation: the identification's records and "
                      "this held-back one are simulated by the same model that is "
                      "identified, so a near-perfect fit is expected. The table below "
                      "repeats the check on records made by richer models.")
    parts.report.text(f"A sweep of {2 * sizes.sweep_period:g} s (twice the identification "
                      "sweep's period, its own noise), never used in the identification; "
                      "the identified model is driven by its logged regulator set-point. "
                      f"Verdict: fit % ≥ {criteria.min_fit_percent:g}, loop widths within "
                      f"{100 * criteria.loop_width:g} %, area within "
                      f"{100 * criteria.loop_area:g} %, break-away and reversals within "
                      f"{100 * criteria.breakaway:g} % of the loop width, residual lags "
                      f"outside the white-noise band ≤ {100 * criteria.max_lags_outside:g} %.")
    parts.figure("fig6_validation", lambda: _fig6(validation),
                 "Fig. 6 (self-consistent case): measured (synthetic, thick grey) and "
                 "predicted (thin) hysteresis loop, a zoom on the low-pressure reversal, and "
                 "the residuals against time")
    parts.table("validation_verdicts", validation.verdicts(),
                "Verdict: fit % together with the loop measures and the residuals")
    parts.table("validation_metrics", validation.metrics(), "Error metrics (SI)")
    parts.table("validation_loops", validation.loops(), "Loop measures, model against "
                                                        "measurement (SI)")
    rows = []
    for case, what in RICHER_CASES:
        if case not in results:
            continue
        verdict = results[case].verdicts().iloc[0]
        fit = results[case].metrics().set_index(["record", "signal"])["fit_percent"]
        rows.append({"record made by": case, "what differs": what,
                     "fit % position": float(fit[(verdict["record"], "position")]),
                     "fit % pressure": float(fit[(verdict["record"], PRESSURE_SIGNAL)]),
                     "loop width error": float(verdict["loop_width_pressure_error"]),
                     "break-away error": float(verdict["breakaway_error"]),
                     "verdict": verdict["verdict"], "reasons": verdict["reasons"]})
    parts.table("validation_richer", pd.DataFrame(rows),
                "The identified (Table I) model against held-back records made by richer "
                "models: fit % of each signal, loop width error (share), break-away "
                "error (share of the loop width), verdict and its reasons")
    changed = [f"{row['record made by']} ({row['verdict']}, fit % position "
               f"{row['fit % position']:.3g})" for row in rows[1:]
               if row["verdict"] != rows[0]["verdict"]]
    parts.report.text(
        "What changes on data the validated model did not make: "
        + (("; ".join(changed) + ". The fit % hardly moves; the residuals' structure (their "
            "autocorrelation, and the steps in the residuals below) is what tells a wrong "
            "model or sensor.") if changed else "no verdict changes in the cases run."))
    parts.figure("fig6_richer", lambda: _richer_figure(results),
                 "Held-back records made by richer models (thick grey) against the "
                 "identified model (thin): the low-pressure reversal of each loop, and the "
                 "position residual against time")


#: The TU Delft cylinder's seal records the real-data section reads (O-ring, supply
#: pressures in bar gauge), the levels it identifies at, and its low-pass [Hz] (100 Hz
#: laser samples, slow strokes: as examples/real_data_validation.py).
SEAL_FILE = "O-ring_{bar}bar.csv"
SEAL_BARS = (1, 3, 5, 7)
SEAL_TRAIN = (1, 7)
SEAL_CUTOFF = 5.0


def _seal_folder(folder: str | os.PathLike) -> Path:
    """``folder`` checked to hold the seal records (before any work is done)."""
    from .errors import ArgumentError

    path = Path(folder)
    missing = [SEAL_FILE.format(bar=bar) for bar in SEAL_BARS
               if not (path / SEAL_FILE.format(bar=bar)).is_file()]
    if missing:
        raise ArgumentError(f"reproduce: seal_data = {str(folder)!r} lacks "
                            f"{', '.join(missing)} (the TU Delft cylinder's records, "
                            "pneumatic_cylinder_friction_tudelft)")
    return path


def seal_friction(folder: str | os.PathLike):
    """The TU Delft O-ring seal's friction (force less p·A) identified as Coulomb +
    viscous at ``SEAL_TRAIN`` bar, interpolated in the supply pressure and predicted at
    the other levels (a ``FrictionValidation``); and, per level, a Stribeck fit's vs
    [m/s] (whether the records show a Stribeck dip at all)."""
    from .errors import PneumactError
    from .identification import inverse_friction
    from .io.datasets import read_tudelft_cylinder
    from .validation import friction_across_levels

    folder = _seal_folder(folder)
    records = {float(bar): read_tudelft_cylinder(folder / SEAL_FILE.format(bar=bar))
               for bar in SEAL_BARS}
    validation = friction_across_levels(records, SEAL_TRAIN, force="friction", mass=False,
                                        cutoff=SEAL_CUTOFF)
    stribeck_vs = {}
    for bar, record in records.items():
        try:
            fitted = inverse_friction(record, "stribeck", force="friction", mass=False,
                                      cutoff=SEAL_CUTOFF)
            stribeck_vs[bar] = float(fitted.estimates["vs"])
        except PneumactError:  # a fit that cannot separate Fs and vs: no dip either
            stribeck_vs[bar] = float("nan")
    return validation, stribeck_vs


def _seal_friction(parts: _Parts, folder: Path | None) -> None:
    """Real data where friction alone is concerned: the TU Delft seal records."""
    parts.report.heading("Real friction data: the TU Delft cylinder's O-ring seal")
    if folder is None:
        parts.report.note(
            "Not run: the real records are not part of pneumact. With the TU Delft "
            "cylinder's seal records (CC0; Zillen, Vallery, Smit 2021, "
            "EvaZillen/3D-printed-pneumatic-actuator), pneumact.reproduce(seal_data=FOLDER) "
            "or pneumact reproduce --seal-data FOLDER adds this section: friction "
            "identified at 1 and 7 bar and predicted at 3 and 5 bar.")
        return
    validation, stribeck_vs = seal_friction(folder)
    metrics = validation.metrics().set_index("record")
    rows = []
    for name, used in validation.parameters.iterrows():
        bar = float(name.split()[0])
        rows.append({"supply pressure [bar gauge]": bar,
                     "role": metrics.loc[name, "role"],
                     "Fc [N]": float(used["Fc"]), "σ2 (Fv) [N·s/m]": float(used["Fv"]),
                     "offset [N]": float(used["offset"]),
                     "fit % force": float(metrics.loc[name, "fit_percent"]),
                     "relative force error": float(metrics.loc[name, "relative_force_error"]),
                     "Stribeck fit's vs [mm/s]": 1e3 * stribeck_vs.get(bar, np.nan)})
    table = pd.DataFrame(rows)
    parts.report.text(
        "The paper's eq. 13 (Fc·sgn(v) + σ2·v) on measured friction: a 3D-printed "
        "single-acting cylinder (bore 25 mm, O-ring seal) stroked at a constant supply "
        "pressure, friction = load-cell force − p·A. Fc, σ2 and an offset are identified "
        f"at {' and '.join(f'{b:g}' for b in SEAL_TRAIN)} bar (inverse model, "
        f"{SEAL_CUTOFF:g} Hz zero-phase low-pass), interpolated linearly in the pressure, "
        "and predict the friction at the other levels, never fitted there.")
    parts.report.note(
        "Limits: friction alone (no chamber, no diaphragm, no spring: not the paper's "
        "actuator, so none of its parameters is checked here); 100 Hz laser samples and a "
        "5 Hz low-pass see neither the presliding (µm) nor σ0, σ1; the offset grows with "
        "the pressure (p·A with the nominal bore is not the piston's force exactly); "
        "the seal's hysteresis stays in the residual. A Stribeck fit puts vs far below "
        "the speeds sampled (last column): these records show no Stribeck dip, so Fs "
        "and vs are not identifiable from them.")
    parts.table("seal_friction", table, "TU Delft O-ring seal: Coulomb + viscous "
                "friction per supply pressure (identified at the training levels, "
                "interpolated at the others), the force's fit % and relative error, and a "
                "Stribeck fit's vs")
    parts.figure("seal_friction", lambda: _seal_figure(validation),
                 "Measured seal friction (dots) against velocity per supply pressure, and "
                 "the model each level uses (line; v > 0 and v < 0 drawn apart, the "
                 "Coulomb step at v = 0)")


def _seal_figure(validation):
    import matplotlib.pyplot as plt

    frames = validation.predictions
    fig, axes = plt.subplots(1, len(frames), figsize=(12.0, 3.4), sharey=True,
                             squeeze=False)
    for ax, (name, frame) in zip(axes[0], frames.items(), strict=True):
        velocity = frame["velocity"].to_numpy()
        ax.plot(1e3 * velocity, frame["measured"], "k.", ms=1, alpha=0.4)
        _by_branch(ax, velocity, frame["predicted"].to_numpy(), 1e3)
        ax.set_title(f"{name.split()[0]} bar ({validation.role[name]})", fontsize=9)
        ax.set_xlabel("velocity [mm/s]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("friction [N]")
    tight_layout(fig)
    return fig


def _by_branch(ax, velocity: np.ndarray, curve: np.ndarray, scale: float = 1.0,
               **style) -> None:
    """``curve`` against ``velocity`` drawn per direction (v < 0, v > 0), each sorted:
    a model with a Coulomb term jumps at v = 0 and is not drawn through it."""
    style = {"color": "C0", "lw": 1.2, **style}
    for branch in (velocity < 0, velocity > 0):
        if branch.any():
            order = np.argsort(velocity[branch])
            ax.plot(scale * velocity[branch][order], curve[branch][order], "-", **style)
            style.pop("label", None)


def _fig6(validation):
    import matplotlib.pyplot as plt

    from .io.records import PRESSURE_SIGNAL

    record = validation.records[0]
    p_meas, p_model = record.measured(PRESSURE_SIGNAL), record.predicted(PRESSURE_SIGNAL)
    x_meas, x_model = record.measured("position"), record.predicted("position")
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 3.8))
    for ax in axes[:2]:
        ax.plot(1e-3 * p_meas, 1e3 * x_meas, color="0.55", lw=3.0, label="measured")
        ax.plot(1e-3 * p_model, 1e3 * x_model, "C0-", lw=0.9, label="model")
        ax.set_xlabel("applied pressure [kPa abs]")
        ax.set_ylabel("diaphragm position [mm]")
        ax.grid(True, alpha=0.3)
    _zoom_on_reversal(axes[1], p_meas, x_meas)
    axes[1].set_title("low-pressure reversal", fontsize=9)
    axes[0].legend(fontsize=7)
    time = record.record.time
    axes[2].plot(time, 1e6 * record.residual("position"), "C1-", lw=0.6)
    axes[2].set_xlabel("time [s]")
    axes[2].set_ylabel("position residual [µm]", color="C1")
    twin = axes[2].twinx()
    twin.plot(time, record.residual(PRESSURE_SIGNAL), "C2-", lw=0.4, alpha=0.6)
    twin.set_ylabel("pressure residual [Pa]", color="C2")
    axes[2].grid(True, alpha=0.3)
    tight_layout(fig)
    return fig


def _zoom_on_reversal(ax, pressure, position, span: float = 0.08) -> None:
    """Zoom ``ax`` on the reversal at the lowest pressure: ±``span`` of the pressure
    range around it, and the positions the loop takes there."""
    low = int(np.argmin(pressure))
    width = span * float(np.ptp(pressure))
    near = np.abs(pressure - pressure[low]) <= width
    ax.set_xlim(1e-3 * (pressure[low] - 0.2 * width), 1e-3 * (pressure[low] + width))
    lo, hi = float(np.min(position[near])), float(np.max(position[near]))
    pad = 0.1 * max(hi - lo, 1e-6)
    ax.set_ylim(1e3 * (lo - pad), 1e3 * (hi + pad))


def _richer_figure(results: dict):
    import matplotlib.pyplot as plt

    from .io.records import PRESSURE_SIGNAL

    fig, axes = plt.subplots(2, len(results), figsize=(12.0, 5.6), squeeze=False)
    for column, (case, validation) in enumerate(results.items()):
        record = validation.records[0]
        pressure = record.measured(PRESSURE_SIGNAL)
        top, bottom = axes[0, column], axes[1, column]
        top.plot(1e-3 * pressure, 1e3 * record.measured("position"), color="0.55", lw=3.0)
        top.plot(1e-3 * record.predicted(PRESSURE_SIGNAL), 1e3 * record.predicted("position"),
                 "C0-", lw=0.9)
        _zoom_on_reversal(top, pressure, record.measured("position"))
        top.set_title(case, fontsize=9)
        top.set_xlabel("pressure [kPa abs]")
        bottom.plot(record.record.time, 1e6 * record.residual("position"), "C1-", lw=0.6)
        bottom.set_xlabel("time [s]")
        top.set_ylabel("position [mm]")
        bottom.set_ylabel("position residual [µm]")
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
            ax.tick_params(labelsize=7)
    tight_layout(fig)
    return fig


def _sensitivity(parts: _Parts, params, oat: Callable[[], object], sizes: Sizes, seed: int,
                 beside: _Beside):
    """Global indices, their convergence and SRC² across conditions; ``oat()`` gives
    Fig. 5's one-at-a-time study (asked for where its table goes: it may come from the
    worker)."""
    from . import sensitivity as sa
    from .experiments import CommandCycle
    from .models import Actuator, CommandValve

    model = Actuator(params, valve=CommandValve())
    problem = sa.Problem.around(params, sa.DEFAULT_RANGES)
    evaluate = sa.model_outputs(model, CommandCycle(period=CYCLE_PERIOD), problem, FEATURES)
    with warnings.catch_warnings():  # small quick samples: their warnings go in the table
        warnings.simplefilter("ignore", sa.SensitivityWarning)
        src = sa.src(problem, evaluate, sizes.src_n, seed)
        sobol, convergence = sobol_by_convergence(problem, evaluate, sizes.sobol_min_n,
                                                  sizes.sobol_n, seed)
    order = [c.label for c in sizes.global_conditions()]
    across = _joined([_global_across(params, sizes, seed, slow=False),
                      beside.result("global_across")], order)
    ranking = ranking_table(src, sobol)
    parts.report.heading("Sensitivity: which parameters matter")
    parts.report.text(
        f"At the reproduction's cycle ({CYCLE_PERIOD:g} s, command valve): SRC (eq. 14, "
        f"{sizes.src_n} runs) and Sobol total indices ({len(sobol.sample)} runs) over ±20 % "
        "of σ0, σ1, σ2, vs and ±10 % of Fc, Fs, on the loop width in pressure and the "
        "break-away pressure. Each index carries its 95 % interval (Sobol: SALib's "
        "bootstrap; SRC²: a bootstrap of the regression); parameters whose intervals "
        "overlap share a rank group, since this sample cannot order them. The break-away is "
        "led by Fc: it is the sliding friction where the diaphragm leaves rest.")
    _report_convergence(parts, convergence, sizes)
    parts.table("sensitivity_ranking", ranking, "Global indices with their 95 % half-width "
                "(conf) and rank groups (1 = most influential; one group: cannot be told "
                "apart within the intervals)")
    wide = ranking.groupby(["method", "feature"])["group"].agg(lambda g: g.value_counts().max())
    crowded = [f"{m} of {f}" for (m, f), size in wide.items() if size >= 3]
    if crowded:
        parts.report.note(f"{', '.join(crowded)}: three or more parameters share a rank "
                          "group: the intervals are too wide to rank them at this sample "
                          "size; the ranking says only which group leads.")
    parts.table("oat_ranking", oat_ranking_table(oat()),
                "One at a time at the paper's amounts (σ0 ±50 %, σ1 ±68 %, σ2 ±90 %, Fs "
                "±16 %, Fc ±15.36 %, vs ±50 %): unequal amounts, so not a ranking of "
                "sensitivity (|Δ| of each feature against the nominal run, SI)")
    for feature in FEATURES:
        parts.figure(f"sobol_{feature}", lambda f=feature: sobol.plot(f),
                     f"Sobol S1 and ST of {feature}, with 95 % confidence intervals")
    parts.report.text(
        f"Across conditions: SRC² of the loop width ({sizes.condition_n} runs per condition, "
        f"the same ranges) at cycle periods {_periods_by_valve(sizes, GLOBAL_VALVES)}. "
        "Below v ≈ vs static friction takes over from Coulomb friction.")
    parts.figure("src_by_speed", lambda: _labelled(across.plot("loop_width_pressure"),
                                                   "sliding speed v / vs [1] (nominal run)",
                                                   "SRC² of the loop width [1]"),
                 "SRC² of the loop width against the sliding speed in units of vs, per "
                 "valve, with its bootstrap 95 % band")
    table = across.indices[["condition", "speed_vs", "parameter", "SRC2", "SRC2_conf",
                            "R2"]]
    above = table[table["SRC2"] > 1.0]
    if len(above):
        where = ", ".join(f"{r.parameter} {r.SRC2:.4g} at {r.condition}"
                          for r in above.itertuples())
        parts.report.note(
            f"SRC² above 1 ({where}): SRC² is a share of variance only for uncorrelated "
            "inputs and a linear response; above 1 (within its interval of 1), one "
            "parameter explains all of it and the sample's chance correlations between "
            "the inputs push the square past 1.")
    parts.table("global_by_condition", table, "SRC² of the loop width per condition, with "
                                              "the regression's R²")
    return across


def _periods_by_valve(sizes: Sizes, valves: Sequence[str]) -> str:
    """"5, 20 s behind the source and 20 s behind the command valve"."""
    return " and ".join(
        f"{', '.join(f'{p:g}' for p in periods)} s behind the "
        f"{valve}{'' if valve == 'source' else ' valve'}"
        for valve in valves
        for periods in [sizes.periods_of(valve, fast=False)])


def _global_across(params, sizes: Sizes, seed: int, slow: bool):
    """SRC² of the loop width across conditions (the sensitivity section's last study)
    at the ``slow`` cycles (periods from ``sizes.global_apart_from``, a job of ``_Beside``)
    or the others (run here: they balance the two processes' work). Each condition is a
    study of its own with the same seed, so the two parts are the whole study split."""
    from . import sensitivity as sa
    from .models import Actuator

    conditions = sizes.global_conditions(slow)
    if not conditions:
        return None
    with warnings.catch_warnings():  # small samples: their warnings go in the table
        warnings.simplefilter("ignore", sa.SensitivityWarning)
        return sa.across_conditions(Actuator(params), conditions, "src",
                                    features=["loop_width_pressure"], n=sizes.condition_n,
                                    seed=seed)




def _joined(parts: list, order: list[str]):
    """One ``ConditionStudy`` of studies over parts of the conditions, in the order of the
    condition labels ``order``."""
    from .sensitivity.operating import ConditionStudy

    parts = [part for part in parts if part is not None]
    rank = {label: i for i, label in enumerate(order)}
    conditions = pd.concat([part.conditions for part in parts], ignore_index=True)
    place = np.argsort([rank[label] for label in conditions["condition"]], kind="stable")
    results = [result for part in parts for result in part.results]
    indices = pd.concat([part.indices for part in parts], ignore_index=True)
    indices = indices.iloc[np.argsort([rank[label] for label in indices["condition"]],
                                      kind="stable")].reset_index(drop=True)
    return ConditionStudy(parts[0].method, conditions.iloc[place].reset_index(drop=True),
                          indices, [results[i] for i in place])


#: Sobol's sample is large enough when every ST interval (95 %) is at most this wide:
#: then indices 0.1 apart can be ranked.
SOBOL_TARGET_WIDTH = 0.1


class _PrefixCache:
    """An ``evaluate`` that runs only what a sample adds to the previous one: Sobol
    samples of n and 2n base points share their first n·(k + 2) runs, so doubling n
    costs only the new runs."""

    def __init__(self, evaluate) -> None:
        self.evaluate = evaluate
        self.inputs: np.ndarray | None = None
        self.outputs: pd.DataFrame | None = None

    def __call__(self, values: np.ndarray) -> pd.DataFrame:
        done = 0 if self.inputs is None else len(self.inputs)
        if self.inputs is not None and (len(values) < done or
                                        not np.array_equal(values[:done], self.inputs)):
            done = 0
        new = pd.DataFrame(self.evaluate(values[done:])).reset_index(drop=True)
        outputs = new if done == 0 else pd.concat([self.outputs, new], ignore_index=True)
        self.inputs, self.outputs = np.array(values, copy=True), outputs
        return outputs


def sobol_by_convergence(problem, evaluate, n_min: int, n_max: int, seed: int = 0):
    """Sobol indices at the smallest base sample n = n_min, 2·n_min, … ≤ ``n_max`` that
    the convergence check (``sensitivity.sobol_convergence``) accepts: every ST interval
    (95 %) at most ``SOBOL_TARGET_WIDTH`` wide, or every parameter in a rank group of its
    own for every output (``rank_groups``: more runs would not change the order). Each
    doubling runs only the new runs. Returns (the study at the n it stopped at, the
    convergence table of that n's prefixes: S1, ST and their interval widths per output,
    parameter and n)."""
    from . import sensitivity as sa

    cached = _PrefixCache(evaluate)
    n = n_min
    while True:
        study, table = sa.sobol_convergence(problem, cached, n_max=n, n_min=n_min,
                                            seed=seed, target_width=None)
        if sobol_converged(table) or 2 * n > n_max:
            return study, table
        n *= 2


def sobol_converged(table: pd.DataFrame) -> bool:
    """Whether the largest n of a ``sobol_convergence`` table is enough: its ST
    intervals all within ``SOBOL_TARGET_WIDTH``, or each parameter's interval apart from
    the others' for every output."""
    last = table[table["n"] == table["n"].max()]
    if float(last["ST_width"].max()) <= SOBOL_TARGET_WIDTH:
        return True
    for _, rows in last.groupby("output"):
        rows = rows.set_index("parameter")
        groups = rank_groups(rows["ST"], rows["ST_width"] / 2)
        if groups.nunique() < len(groups):
            return False
    return True


def _report_convergence(parts: _Parts, convergence: pd.DataFrame, sizes: Sizes) -> None:
    """The convergence check that chose Sobol's sample size, and its verdict."""
    widths = (convergence.groupby(["n", "runs", "output"])["ST_width"].max()
              .unstack("output").reset_index())
    widths.columns = [str(c) if c in ("n", "runs") else f"widest ST interval, {c}"
                      for c in widths.columns]
    n = int(widths["n"].iloc[-1])
    widest = float(convergence.loc[convergence["n"] == n, "ST_width"].max())
    needed = int(2 ** np.ceil(np.log2(n * (widest / SOBOL_TARGET_WIDTH) ** 2)))
    if widest <= SOBOL_TARGET_WIDTH:
        verdict = f"every ST interval is at most {widest:.2g} wide at n = {n}: converged"
    elif sobol_converged(convergence):
        verdict = (f"at n = {n} every parameter's ST interval is apart from the others' "
                   f"(the widest {widest:.2g}): the order is settled")
    else:
        verdict = (f"at n = {n}, the largest this reproduction runs, ST intervals are up "
                   f"to {widest:.2g} wide and overlap: too wide to rank the parameters that "
                   f"share a rank group below (n ≈ {needed} would reach the target)")
    parts.report.text(
        "Sobol's sample size is chosen by the convergence check: the base sample doubles "
        f"from n = {sizes.sobol_min_n} (up to {sizes.sobol_n}) until every ST interval (95 "
        f"%) is at most {SOBOL_TARGET_WIDTH:g} wide or every parameter's interval stands "
        f"apart from the others'; {verdict}.")
    parts.table("sobol_convergence", widths, "The convergence check: the widest 95 % "
                "interval of ST at each base sample size n (runs = n·(k + 2)) of the "
                "sample the check stopped at")


def _lead_with(report, position: int, summary: pd.DataFrame) -> None:
    """The statements' verdicts in one paragraph, placed after the introduction: which
    hold throughout, nowhere, or in part of the conditions (and where)."""
    from .io.report import Block

    groups: dict[str, list[str]] = {"throughout": [], "nowhere": [], "in part": []}
    for _, row in summary.iterrows():
        held = str(row["holds for"])
        if held.startswith("all of"):
            groups["throughout"].append(row["statement"])
        elif held.startswith("nowhere"):
            groups["nowhere"].append(row["statement"])
        else:
            groups["in part"].append(f"{row['statement']} ({held.split(' (of')[0]})")
    text = ("The paper's statements at a glance (applied pressure across cycle speeds; Fig. "
            "3 and eq. 13 on their own axes; details in the last section). Hold throughout "
            f"the conditions studied: {', '.join(groups['throughout']) or 'none'}. Hold "
            f"nowhere: {', '.join(groups['nowhere']) or 'none'}. Hold in part: "
            f"{'; '.join(groups['in part']) or 'none'}.")
    report.blocks.insert(position, Block("note", text))


def _statements(parts: _Parts, across, global_study, effects, bias, loop_floor,
                friction_floor) -> pd.DataFrame:
    from .statements import HEADLINE_VALVE, evaluate_statements, statement_texts, summarise

    per_condition = evaluate_statements(across, global_study, effects, bias,
                                        loop_floor=loop_floor, friction_floor=friction_floor,
                                        fig3_period=FIG3_PERIOD)
    summary = summarise(per_condition)
    parts.report.heading("The paper's statements: where each holds")
    parts.report.text(
        "Each claim of the paper, one parameter at a time (a sentence naming several "
        "parameters is split, so that one weak parameter does not sink the others), the "
        "criterion we measure it by, and the range of its condition in which it holds: "
        "for Fig. 5 and the conclusion the sliding speed v/vs of the loop under the applied "
        f"pressure (the {HEADLINE_VALVE} valve, as the paper's figures), then behind the "
        "command valve and the regulator; for Fig. 3 the velocity amplitude of the sine; "
        "for eq. 13 the lowest speed of the fit. A boundary is interpolated between the "
        "conditions studied only where the margins on both sides exceed the measure's "
        "noise floor; 'within noise' marks a condition where they do not.")
    texts = statement_texts()
    parts.table("statement_texts", texts, "The statements: the paper's words, the parameter "
                                          "and amount, and the criterion we measure each by")
    parts.table("paper_statements", summary, "Where each statement holds (applied pressure "
                "first, then the other valves), where it stops, and its noise floor")
    for _, row in summary[summary["holds for"].str.startswith("nowhere")].iterrows():
        parts.report.note(f"{row['source']}: “{row['paper']}” ({row['criterion']}) holds "
                          f"nowhere under the applied pressure; command valve: "
                          f"{row['command valve']}; regulator: {row['regulator valve']}.")
    parts.table("statement_conditions", per_condition, "Every statement at every condition: "
                "what was measured, the margin (positive: it holds), the noise floor and the "
                "verdict")
    return summary


#: The model's choices where the paper leaves it open (docs/model.md, "Open choices"):
#: (choice, what the model does, source).
MODEL_CHOICES = (
    ("one viscous coefficient", "b_d = σ2, counted once as σ2·v in the friction law",
     "Table I lists 'damping constant b_d, σ2' as one; eq. 9 has one σ2·v term"),
    ("Stribeck exponent δ", "δ = 1 (exp(−|v|/vs))", "eq. 8 as printed (the LuGre "
     "literature mostly uses δ = 2)"),
    ("chamber volume", "V(x) = V0 − A_d·x", "assumed: the paper gives V0 and A_d, no "
     "volume law"),
    ("chamber gas law", "isothermal, n = 1: dp/dt = n/V·(R·T·ṁ + p·A_d·v)", "assumed: "
     "eqs. 2–5 give the flows, no pressure equation (adiabatic: n = γ)"),
    ("choked flow", "ṁ = A·p_up·sqrt(γ/(R·T))·Φ*: ∝ p_up", "eqs. 2–4 as printed; the "
     "text's 'becomes constant' holds for Φ only"),
    ("laminar branch", "Φ linear on r ∈ [0.999, 1]", "numerical: a finite Jacobian at "
     "r → 1"),
    ("valves", "ideal pressure source; command valve with linear area maps u·A_res, "
     "(1 − u)·A_atm; a PI regulator driving it", "Figs. 5–6 use the applied pressure; "
     "the EPC's maps are not given"),
    ("assumed values", "x_max 20 mm, γ 1.4, R 287 J/(kg·K), T 293.15 K, p_res 10 kPa, "
     "A_res = A_atm = 1.5 mm²", "not in the paper; each value's note in the set says why"),
)
#: The chamber step: the command valve opened (u 0 → 1) and closed again at these times [s].
STEP_TIMES = (0.05, 1.5, 3.0)


def _pneumatics(parts: _Parts, params) -> None:
    from .analysis import chamber_time_constant, choked_limit, natural_frequencies

    ratio, phi = choked_limit(params["gamma"])
    step = _chamber_step(params)
    parts.report.heading("The pneumatic half: flows, chamber and natural frequencies")
    parts.report.text(
        f"Eqs. 2–5 with the set's gas: the flow is choked below r_c = {ratio:.4f}, where Φ "
        f"takes its largest value Φ* = {phi:.4f}. The mass flow A·p_up·sqrt(γ/(R·T))·Φ* then "
        "stays proportional to the upstream pressure: the paper's 'air mass flow becomes "
        "constant' holds for Φ, not for the flow. Emptying the chamber through the choked "
        "reservoir orifice is therefore a first-order decay whose time constant "
        "τ = V(x)/(n·A_res·Φ*·sqrt(γ·R·T)) falls with the chamber volume along the stroke "
        f"(V0 = {1e6 * params['V0']:g} cm³ at rest).")
    parts.report.note("The paper (section II.A): 'air mass flow becomes constant' when "
                      "choked. Corrected here: Φ becomes constant; the flow stays ∝ p_up.")
    parts.figure("pneumatics_flow", lambda: _flow_figure(params),
                 "Φ(r) (eq. 4) with its choked limit; the mass flow from the chamber to the "
                 "reservoir through A_res against the chamber pressure (choked: a straight "
                 "line through zero, not a constant); the chamber's time constant along the "
                 "stroke")
    parts.figure("chamber_step", lambda: _step_figure(params, step),
                 f"The chamber's step response through the command valve: u 0 → 1 at "
                 f"{STEP_TIMES[0]:g} s, back to 0 at {STEP_TIMES[1]:g} s; dashed: the "
                 "diaphragm held at rest, whose pressure decays as exp(−t/τ(0)) while choked")
    x = np.unique(np.r_[np.linspace(0.0, params["x_max"], 5), step["x_top"]])
    volume = params["V0"] - params["A_d"] * x
    parts.table("chamber_time_constant", pd.DataFrame({
        "position [mm]": 1e3 * x, "volume [cm³]": 1e6 * volume,
        "τ isothermal [ms]": 1e3 * chamber_time_constant(params, x),
        "τ adiabatic [ms]": 1e3 * chamber_time_constant(params, x,
                                                         exponent=params["gamma"])}),
        f"The chamber's time constant along the stroke (valve fully open to the reservoir, "
        f"choked, diaphragm standing); {1e3 * step['x_top']:.3g} mm: the top of the step "
        "response above")
    frequencies = natural_frequencies(params)
    parts.table("natural_frequencies", pd.DataFrame([
        {"case": case, "stiffness [N/m]": v["stiffness"], "frequency [Hz]": v["frequency"],
         "damping ratio": v["damping_ratio"]} for case, v in frequencies.items()]),
        "Natural frequencies of the diaphragm (m = Table I's m_d): free on the spring, "
        "stuck on the bristles (k + σ0, damped by σ1 + σ2), and free with the gas spring "
        "n·p·A_d²/V of a closed chamber at rest")
    parts.table("modelling_choices", pd.DataFrame(MODEL_CHOICES,
                                                  columns=["choice", "model", "source"]),
                "Every modelling choice the paper leaves open, and its source "
                "(docs/model.md, 'Open choices')")


def _chamber_step(params) -> dict:
    """The command valve's step response: the free diaphragm and one held at rest (a
    preload the pressure cannot overcome)."""
    from .experiments import Experiment, PiecewiseLinear
    from .models import Actuator, CommandValve
    from .simulation import simulate

    start, close, end = STEP_TIMES
    drive = PiecewiseLinear([0.0, start, start, close, close, end], [0, 0, 1, 1, 0, 0])
    experiment = Experiment(drive, "command", end, n_points=1501, name="chamber step")
    model = Actuator(params, valve=CommandValve())
    free = simulate(model, experiment)
    held = simulate(model, experiment, values={"F0": 10 * params["p_atm"] * params["A_d"]})
    return {"time": free.time, "free": free, "held": held,
            "x_top": float(np.max(free["position"]))}


def _flow_figure(params):
    import matplotlib.pyplot as plt

    from .analysis import chamber_time_constant, choked_limit
    from .models.pneumatics import flow_function_values, orifice_mass_flow

    ratio, phi = choked_limit(params["gamma"])
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 3.6))
    r = np.linspace(0.0, 1.0, 501)
    axes[0].plot(r, flow_function_values(r, params["gamma"]), "C0-", lw=1.4)
    axes[0].axvline(ratio, color="k", ls=":", lw=0.8)
    axes[0].axhline(phi, color="k", ls="--", lw=0.8)
    axes[0].annotate(f"r_c = {ratio:.4f}\nΦ* = {phi:.4f}", (ratio, phi), (0.05, 0.25),
                     fontsize=8)
    axes[0].set_xlabel("pressure ratio r = p_down / p_up [1]")
    axes[0].set_ylabel("Φ(r) [1]")
    pressure = np.linspace(params["p_res"], params["p_atm"], 401)
    flow = orifice_mass_flow(pressure, params["p_res"], params["A_res"], params)
    axes[1].plot(1e-3 * pressure, 1e6 * flow, "C1-", lw=1.4, label="eqs. 2, 4")
    axes[1].axvline(1e-3 * params["p_res"] / ratio, color="k", ls=":", lw=0.8,
                    label="choked above p_res / r_c")
    axes[1].set_xlabel("chamber pressure p_up [kPa abs]")
    axes[1].set_ylabel("mass flow to the reservoir [mg/s]")
    axes[1].legend(fontsize=7)
    x = np.linspace(0.0, params["x_max"], 201)
    axes[2].plot(1e3 * x, 1e3 * chamber_time_constant(params, x), "C2-", lw=1.4,
                 label="isothermal (model)")
    axes[2].plot(1e3 * x, 1e3 * chamber_time_constant(params, x, exponent=params["gamma"]),
                 "C2--", lw=1.0, label="adiabatic")
    axes[2].set_yscale("log")
    axes[2].set_xlabel("diaphragm position x [mm]")
    axes[2].set_ylabel("chamber time constant τ [ms]")
    axes[2].legend(fontsize=7)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    tight_layout(fig)
    return fig


def _step_figure(params, step: dict):
    import matplotlib.pyplot as plt

    from .analysis import chamber_time_constant, choked_limit
    from .models.actuator import CHAMBER_PRESSURE

    time, free, held = step["time"], step["free"], step["held"]
    tau = float(chamber_time_constant(params, 0.0))
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 3.6))
    axes[0].plot(time, 1e-3 * free[CHAMBER_PRESSURE], "C0-", lw=1.4, label="free diaphragm")
    axes[0].plot(time, 1e-3 * held[CHAMBER_PRESSURE], "C3--", lw=1.0, label="held at rest")
    decay = time[(time >= STEP_TIMES[0]) & (time <= STEP_TIMES[1])]
    exponential = params["p_atm"] * np.exp(-(decay - STEP_TIMES[0]) / tau)
    choked = exponential >= params["p_res"] / choked_limit(params["gamma"])[0]
    axes[0].plot(decay[choked], 1e-3 * exponential[choked], "k:", lw=1.2,
                 label=f"p_atm·exp(−t/τ) while choked, τ = {1e3 * tau:.3g} ms")
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("chamber pressure [kPa abs]")
    axes[0].legend(fontsize=7)
    axes[1].plot(time, 1e3 * free["position"], "C0-", lw=1.4)
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("diaphragm position [mm]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    tight_layout(fig)
    return fig


def _table_one(parts: _Parts, params, passivity: list[str]) -> None:
    frame = params.to_pandas()
    paper = frame["source"].str.startswith("paper")
    table = frame[paper | (frame["source"] == "assumed")][
        ["name", "value", "unit", "given", "source"]].copy()
    table["assumed"] = ~table["source"].str.startswith("paper")
    parts.report.heading("Table I: the parameter set as loaded")
    parts.report.text(f"{int(paper.sum())} values from the paper; {int(table['assumed'].sum())}"
                      " assumed where the paper gives none (marked). Values in SI.")
    parts.table("table_1", table, "Table I (SI), with the source of each value")
    for text in passivity:
        parts.report.note(f"Table I as published: {text}. We simulate it as given.")


def _fig2(params):
    import matplotlib.pyplot as plt

    from . import sensitivity as sa
    from .models import LuGre

    curves = sa.friction_velocity(params, {"Fc": 0.0})  # zero variation: the nominal run
    _, v, f = curves.curves["Fc"][0]
    grid = np.linspace(-5e-3, 5e-3, 801)
    fig, ax = plt.subplots(figsize=(6.5, 4.0))
    ax.plot(v * 1e3, f, "C0-", lw=1.2, label="LuGre, velocity sine")
    ax.plot(grid * 1e3, LuGre().steady_force(grid, params), "k--", lw=1,
            label="steady state (Stribeck curve + viscous)")
    ax.set_xlabel("velocity [mm/s]")
    ax.set_ylabel("friction [N]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    tight_layout(fig)
    return fig


def _identification(parts: _Parts, params, sizes: Sizes, seed: int):
    from .identification import Noise, identify_paper, paper_campaign, synthetic_campaign

    tests = paper_campaign(params, speeds=sizes.ramp_speeds, sweep_period=sizes.sweep_period)
    noise = Noise()  # the self-consistent case; the richer ones below
    records = synthetic_campaign(params, tests, noise=noise, seed=seed)
    identified = identify_paper(records, params)
    parts.report.heading("Identification (section III.2) on a synthetic bench campaign")
    parts.report.note(
        "Synthetic data: the paper's bench records are not public, so the campaign is "
        f"simulated from Table I ({len(records)} records: a quasi-static sweep, "
        f"{len(sizes.ramp_speeds)} ramp pairs from {1e3 * min(sizes.ramp_speeds):g} to "
        f"{1e3 * max(sizes.ramp_speeds):g} mm/s, a presliding test) with measurement noise "
        f"(pressure {noise.pressure:g} Pa, position {1e6 * noise.position:g} µm, seed {seed}).")
    table = identified.to_pandas(truth=params).reset_index()
    parts.table("identification", table, "Identified parameters beside Table I (truth), "
                "with standard errors and 95 % intervals")
    missed = table.loc[~table["truth_in_ci95"], "parameter"].tolist()
    if missed:
        parts.report.note(f"Table I's value lies outside the 95 % interval for: "
                          f"{', '.join(missed)} (the interval reflects noise only, not the "
                          "bias of the staged procedure).")
    for name, stage in identified.stages.items():
        parts.figure(f"identification_{name}", stage.plot, stage.title)
    presliding = identified.stages.get("presliding")
    if presliding is not None and "fit" in presliding.extra:
        parts.figure("identification_presliding_window",
                     lambda: _presliding_window_figure(presliding.extra["fit"]),
                     "Stage (d) zoomed on its fitted window: the position in µm from where "
                     "it rests at the window's start, measured (dots) and fitted (line), "
                     "and the residual")
    return identified


#: The parameters whose error the richer campaigns' table shows (Table I's, in order).
IDENTIFIED_SHOWN = ("F0", "k", "Fc", "Fs", "vs", "sigma0", "sigma1", "sigma2")


def _identification_richer(parts: _Parts, sizes: Sizes, rows: list[dict]) -> pd.DataFrame:
    """Section III.2 on campaigns made by richer models (``RICHER_CASES``): what
    ``identify_paper`` says on each (its verdict, the errors against the values the
    records were made with, the faults it names). The model identified stays Table I's
    (LuGre δ = 1, isothermal, an ideal sensor): the procedure as the paper gives it.
    ``rows``: ``richer_row`` of each case, most run beside the other sections."""
    skipped = [case for case, _ in RICHER_CASES[1:] if case not in sizes.richer_identification]
    speeds = sizes.richer_ramp_speeds
    parts.report.text(
        "The same procedure on campaigns made by richer models than the one it identifies "
        f"(Fig. 6's cases; a smaller campaign: {len(speeds)} ramp pairs from "
        f"{1e3 * min(speeds):g} to {1e3 * max(speeds):g} mm/s, a "
        f"{sizes.richer_sweep_period:g} s sweep, a presliding test, the same noise): the "
        "errors are against the values the records were made with (GMS-4: Table I's, "
        "which its blocks are matched to; δ is not identified), and the faults are those "
        "the identification names itself.")
    if skipped:
        parts.report.note(f"Quick mode: not run on {', '.join(skipped)} (pneumact "
                          "reproduce without --quick runs every case).")
    table = pd.DataFrame(rows, columns=["records made by", "identified",
                                        *(f"{n} error %" for n in IDENTIFIED_SHOWN),
                                        "truth outside 95 % interval", "faults named"])
    if rows:
        parts.table("identification_richer", table,
                    "Section III.2 on campaigns made by richer models: the identification's "
                    "own verdict, each parameter's error against the truth (%), where the "
                    "truth lies outside the reported 95 % interval, and the faults it names "
                    "(lag and resolution as the bench table gives them)")
        parts.report.text("What changes against the self-consistent case above: "
                          + "; ".join(_what_changes(row) for row in rows) + ".")
    return table


def richer_cases(sizes: Sizes) -> list[str]:
    """The richer cases ``sizes`` identifies, in ``RICHER_CASES``' order."""
    return [case for case, _ in RICHER_CASES[1:] if case in sizes.richer_identification]


def richer_row(params, sizes: Sizes, seed: int, case: str) -> dict:
    """One row of the richer campaigns' table: ``identify_richer`` on ``case``'s campaign
    (a job of ``_Beside``, or run here: ``Sizes.richer_here``). One case at a time: two
    at a time on threads took 1.9-3.5× the CPU time (97-185 s against 52 s on 2 cores)."""
    from .identification import paper_campaign

    tests = paper_campaign(params, speeds=sizes.richer_ramp_speeds,
                           sweep_period=sizes.richer_sweep_period)
    with warnings.catch_warnings():  # its findings go in the table, not on stderr
        warnings.simplefilter("ignore")
        return identify_richer(params, case, tests, seed)


def _what_changes(row: dict) -> str:
    """One clause per richer campaign: its verdict, its largest error, and whether the
    sensor's lag was named where the records had one."""
    errors = {name: row[f"{name} error %"] for name in IDENTIFIED_SHOWN
              if np.isfinite(row[f"{name} error %"])}
    worst = max(errors, key=lambda name: abs(errors[name]))
    clause = (f"{row['records made by']}: {row['identified']}, the largest error "
              f"{worst} {errors[worst]:+.3g} %")
    if "lag" in row["records made by"]:
        clause += (", the lag named" if "position lag" in row["faults named"] else
                   ", the lag not named (no position_lag in its bench table)")
    return clause


def identify_richer(params, case: str, tests, seed: int = 0) -> dict:
    """``identify_paper`` (Table I's model) on the campaign ``tests`` as the richer
    model ``case`` records it: one row of the richer campaigns' table."""
    from .identification import identify_paper

    records = _richer_record(params, case, tests, seed)
    result = identify_paper(records, params)
    return _richer_identification_row(case, result, result.to_pandas(truth=params))


def _richer_identification_row(case: str, result, estimates: pd.DataFrame) -> dict:
    """One row of the richer campaigns' table: verdict, errors, misses, named faults."""
    from .identification.diagnostics import named_list

    row: dict = {"records made by": case, "identified": result.headline()}
    for name in IDENTIFIED_SHOWN:
        row[f"{name} error %"] = (float(estimates.loc[name, "error_%"])
                                  if name in estimates.index else np.nan)
    inside = estimates["truth_in_ci95"]
    missed = inside.index[inside.eq(False)].tolist()
    unreported = inside.index[inside.isna()].tolist()
    row["truth outside 95 % interval"] = ", ".join(
        [*missed, *(["no interval: " + named_list(unreported)] if unreported else [])]
    ) or "none"
    named = []
    bench = result.bench_table().set_index("parameter")
    if "position_lag" in bench.index:
        named.append(f"position lag {1e3 * bench.loc['position_lag', 'value']:.3g} ms")
    if "position_resolution" in bench.index and bench.loc["position_resolution", "value"]:
        named.append(f"resolution {1e6 * bench.loc['position_resolution', 'value']:.3g} µm")
    findings = dict.fromkeys(f"{d.severity}: {d.message.split(': ')[0].split('. ')[0]}"
                             for d in result.diagnostics if d.severity != "note")
    named += list(findings)[:RICHER_FINDINGS]
    if len(findings) > RICHER_FINDINGS:
        named.append(f"and {len(findings) - RICHER_FINDINGS} more")
    row["faults named"] = "; ".join(named) or "none"
    return row


#: Findings (warnings and errors) a row of the richer campaigns' table lists at most.
RICHER_FINDINGS = 3


def _presliding_window_figure(fit):
    """Each presliding record within the window stage (d) fitted, in µm: the stuck
    deflection the whole-record plot (mm, the approach included) cannot show."""
    import matplotlib.pyplot as plt

    masks = fit.masks()
    fig, axes = plt.subplots(2, len(masks), figsize=(6.5 * min(len(masks), 2), 5.0),
                             sharex="col", squeeze=False,
                             gridspec_kw={"height_ratios": [2, 1]})
    for i, mask in enumerate(masks):
        time = fit.records[i].time[mask]
        measured = fit.records[i]["position"][mask]
        fitted = fit.fitted(i, "position")[mask]
        rest = measured[0]
        top, bottom = axes[0, i], axes[1, i]
        top.plot(time, 1e6 * (measured - rest), "k.", ms=2, label="measured")
        top.plot(time, 1e6 * (fitted - rest), "C0-", lw=1.0, label="fitted")
        bottom.plot(time, 1e6 * (measured - fitted), "C3.", ms=2)
        top.set_ylabel("position from rest [µm]")
        bottom.set_ylabel("residual [µm]")
        bottom.set_xlabel("time [s]")
        top.set_title(Path(fit.records[i].source).name, fontsize=9)
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    tight_layout(fig)
    return fig


def _labelled(fig, xlabel: str, ylabel: str):
    """``fig`` with every panel's axes labelled (units in brackets)."""
    for ax in fig.axes:
        if ax.get_visible():
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
    return fig


def rank_groups(values: pd.Series, conf: pd.Series) -> pd.Series:
    """Rank groups (1 = largest) of ``values`` with 95 % half-widths ``conf``: in order
    of the value, a parameter joins the group above while its interval overlaps that of
    the previous one (they cannot be told apart)."""
    order = values.abs().sort_values(ascending=False).index
    groups, group, previous = {}, 1, None
    for name in order:
        if previous is not None and \
                abs(values[previous]) - conf[previous] > abs(values[name]) + conf[name]:
            group += 1
        groups[name] = group
        previous = name
    return pd.Series(groups).reindex(values.index)


def ranking_table(src, sobol) -> pd.DataFrame:
    """Long table: method, feature, parameter, value, conf (95 % half-width), group
    (``rank_groups``), rank (1 = most influential, order within the sample)."""
    rows = []
    for feature in FEATURES:
        src_table = src.to_pandas(output=feature)
        sobol_table = sobol.to_pandas(output=feature)
        per_method = {"SRC²": (src_table["SRC2"], src_table["SRC2_conf"]),
                      "Sobol ST": (sobol_table["ST"], sobol_table["ST_conf"])}
        for method, (values, conf) in per_method.items():
            groups = rank_groups(values, conf)
            ordered = values.abs().sort_values(ascending=False)
            for rank, (name, value) in enumerate(ordered.items(), start=1):
                rows.append({"method": method, "feature": feature, "parameter": name,
                             "value": float(value), "conf": float(conf[name]),
                             "group": int(groups[name]), "rank": rank})
    return pd.DataFrame(rows)


def oat_ranking_table(oat) -> pd.DataFrame:
    """One at a time at the paper's (unequal) amounts: parameter, amount, |Δ| of each
    feature (SI)."""
    from .sensitivity import PAPER_VARIATIONS

    table = pd.DataFrame({f"|Δ {feature}|": oat.ranking(feature) for feature in FEATURES})
    table.insert(0, "amount", [f"±{100 * PAPER_VARIATIONS[n]:g} %" for n in table.index])
    return table.rename_axis("parameter").reset_index()
