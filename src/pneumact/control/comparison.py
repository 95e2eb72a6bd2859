"""Designs side by side on the nonlinear loop: where friction breaks a linear design.

``compare_designs(loop, specs, designs)`` runs each design (a ``ClosedLoop`` or a
controller for ``loop``'s plant) on the same reference moves of the nonlinear model and
tabulates its metrics against the specs, with what went wrong in words: it *hunts* (a
limit cycle about the set-point), it *sticks short* (a steady error on the side it came
from: friction holds it), it *creeps* (too slow into the band), it overshoots, or its run
failed. ``friction_designs(linear, ...)`` builds the usual set from a linear design: the
PID as designed, and with static (Coulomb/Stribeck feed-forward), dither and LuGre
observer compensation; add a ``tune`` result to see what the nonlinear tuning recovers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..io.report import ResultVocabulary
from ..models.controllers import Controller, Dither, LuGreObserver, StaticCompensation
from ..plotting import tight_layout
from .loop import ClosedLoop
from .specs import Move, Specs, default_moves

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .linear_design import LinearDesign

__all__ = ["DesignComparison", "compare_designs", "friction_designs"]

#: the dither's frequency over the designed crossover's (fast enough to average out in
#: the position, slow enough for the valve and chamber to pass it)
DITHER_OVER_CROSSOVER = 10.0
#: the dither's amplitude over the input that balances the Coulomb force
DITHER_OVER_COULOMB = 1.0
#: the words for each violated spec
FAILURE_WORDS = {"hunting": "hunts", "settling": "creeps", "rise": "slow rise",
                 "overshoot": "overshoots", "effort": "too much effort",
                 "variation": "command too busy"}


def friction_designs(linear: LinearDesign) -> dict[str, ClosedLoop]:
    """The linear design as it is and with each friction compensation (the plant's own
    LuGre parameters: what an identification gives): static feed-forward of the
    Stribeck curve at the reference speed, a dither of the Coulomb input at 10× the
    crossover frequency, and the LuGre observer. A command valve has no static force map:
    compensations that need one are left out unless the loop has ``compensation_gain``."""
    loop = linear.loop
    params = loop.params
    designs = {"linear (python-control)": loop}
    force_gain = loop.force_gain
    if force_gain is None:
        return designs
    base = loop.controller
    fc, fs, vs = (float(params[n]) for n in ("Fc", "Fs", "vs"))
    amplitude = DITHER_OVER_COULOMB * fc * abs(force_gain)
    frequency = DITHER_OVER_CROSSOVER * linear.crossover / (2.0 * math.pi)
    extra = {"linear + static compensation": StaticCompensation(Fc=fc, Fs=fs, vs=vs),
             "linear + dither": Dither(amplitude=amplitude, frequency=frequency),
             "linear + LuGre observer": LuGreObserver.from_parameters(params)}
    for name, term in extra.items():
        designs[name] = dataclasses.replace(
            loop, controller=dataclasses.replace(base, compensation=(term,)))
    return designs


@dataclass(eq=False)
class DesignComparison(ResultVocabulary):
    """Each design's metrics on each move of the nonlinear loop, against the specs.

    ``to_pandas()``: one row per (design, move): settling, rise, overshoot, steady-state
    error, limit-cycle amplitude, IAE, whether it meets the specs and, if not, what
    broke; ``"summary"``: per design, the moves met and the failures in words.
    ``plot()``: each move's responses, one line per design. With ``linear`` (the
    ``LinearDesign`` the designs came from), its gains, its linear predictions and its
    Bode plot join the tables, the figures and ``write``'s ``linear_gains.toml``."""

    inline_figure = False  # plot() simulates every move: not for a display

    report_title = "Designs on the nonlinear loop"
    figure_name = "designs"

    loops: dict[str, ClosedLoop]
    specs: Specs
    moves: tuple[Move, ...]
    table: pd.DataFrame
    linear: LinearDesign | None = None

    def tables(self) -> dict[str, pd.DataFrame]:
        found = {"metrics": self.table, "summary": self.summary()}
        if self.linear is not None:
            found |= {"linear_gains": self.linear.gains_table(),
                      "linear_predicted": self.linear.predicted_table()}
        return found

    def figures(self) -> dict[str, Callable[[], Figure]]:
        found: dict[str, Callable[[], Figure]] = {self.figure_name: self.plot}
        if self.linear is not None:
            found[self.linear.figure_name] = self.linear.plot
        return found

    def extra_files(self) -> dict[str, Callable[[Path], object]]:
        """With a linear design: its gains as ``linear_gains.toml`` (``pneumact control
        step --gains-file``)."""
        from .tuning import write_gains

        linear = self.linear
        if linear is None:
            return {}
        note = f"linear design for {self.specs.describe()}"
        return {"linear_gains.toml": lambda path: write_gains(
            linear.controller, path, linear.loop.gain_units, note)}

    def summary(self) -> pd.DataFrame:
        rows = []
        for name, runs in self.table.groupby("design", sort=False):
            broke = [f"{r.move}: {r.failure}" for r in runs.itertuples() if not r.meets_specs]
            rows.append((name, int(runs["meets_specs"].sum()), len(runs),
                         "; ".join(broke) or "meets every spec"))
        return pd.DataFrame(rows, columns=["design", "moves met", "moves", "what broke"])

    def meets(self, design: str) -> bool:
        """Whether ``design`` meets the specs on every move."""
        return bool(self.table.loc[self.table["design"] == design, "meets_specs"].all())

    def report_text(self) -> str:
        met = [n for n in self.loops if self.meets(n)]
        text = (f"{len(self.loops)} designs on {len(self.moves)} moves of the nonlinear loop "
                f"({self.specs.describe()}); every spec met by: "
                f"{', '.join(met) if met else 'none'}.")
        return text if self.linear is None else f"{text} {self.linear.report_text()}"

    def plot(self) -> Figure:
        from ..plotting import panel_grid
        from ..simulation import simulate

        fig, panels = panel_grid(len(self.moves), width=3.8, height=3.6)
        for (ax,), move in zip(panels, self.moves, strict=True):
            experiment = move.experiment()
            run = None
            for k, (name, loop) in enumerate(self.loops.items()):
                run = simulate(loop, experiment)
                ax.plot(run.time, 1e3 * run["position"], color=f"C{k}", lw=1.2, label=name)
            assert run is not None  # compare_designs has at least one design
            ax.plot(run.time, 1e3 * run["position_setpoint"], "k--", lw=0.8,
                    label="set-point")
            ax.set_title(move.label, fontsize=9)
            ax.set_xlabel("time [s]")
            ax.set_ylabel("position [mm]")
            ax.grid(True, alpha=0.3)
        panels[-1][0].legend(fontsize=7, loc="best")
        tight_layout(fig)
        return fig


def compare_designs(loop: ClosedLoop, specs: Specs | str,
                    designs: Mapping[str, ClosedLoop | Controller], *,
                    moves: Sequence[Move] | None = None, at: float | None = None,
                    linear: LinearDesign | None = None) -> DesignComparison:
    """Run each of ``designs`` (name -> a loop, or a controller put in ``loop``) on the
    ``moves`` (default ``default_moves(loop, specs, at)``) of the nonlinear model and
    say where each meets ``specs`` and where it breaks (module docstring). ``linear``:
    the linear design they came from, reported beside them."""
    from .tuning import evaluate_design

    specs = Specs.of(specs)
    if not designs:
        raise ParameterError("compare_designs: designs = {}; give at least one "
                             "(name -> ClosedLoop or controller)")
    loops = {name: _as_loop(loop, name, design) for name, design in designs.items()}
    moves = tuple(default_moves(loop, specs, at) if moves is None else moves)
    frames = []
    for name, design in loops.items():
        table = evaluate_design(design, specs, moves=moves).metrics_table
        table = table[table["sample"] == 0].drop(columns="sample")
        table.insert(0, "design", name)
        table["failure"] = [_failure(row, move, specs) for row, move in
                            zip(table.to_dict("records"), moves, strict=True)]
        frames.append(table)
    return DesignComparison(loops=loops, specs=specs, moves=moves,
                            table=pd.concat(frames, ignore_index=True), linear=linear)


def _as_loop(loop: ClosedLoop, name: str, design) -> ClosedLoop:
    if isinstance(design, ClosedLoop):
        return design
    if isinstance(design, Controller):
        return dataclasses.replace(loop, controller=design)
    raise ParameterError(f"compare_designs: designs[{name!r}] = {design!r}; give a "
                         "ClosedLoop or a controller (PID, Cascade)")


def _failure(row: dict, move: Move, specs: Specs) -> str:
    """What broke on this run, in words ("" where it meets the specs)."""
    if not row["ok"]:
        return "run failed"
    words = []
    if row.get("violates_error", 0.0) > 0:
        error = row["steady_state_error"]  # r − x at the end
        short = np.sign(error) == np.sign(move.stop - move.start)
        words.append("sticks short" if short else "steady error past the target")
    for spec, word in FAILURE_WORDS.items():
        if row.get(f"violates_{spec}", 0.0) > 0:
            words.append(word)
    return ", ".join(words)
