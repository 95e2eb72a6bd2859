"""What a tuned loop must do: the specifications and the reference moves it is tried on.

``Specs.parse("settling=0.3,overshoot=5%,error=20um,no-hunting")`` (the command line's
words) or ``Specs(settling=0.3, overshoot=5.0, error=20e-6, no_hunting=True)``; SI
inside (overshoot in % of the step). ``default_moves(loop, specs)`` chooses the moves a
position controller of that plant meets in service: a small step near the presliding
range, steps up and down that cross break-away, and a ramp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError

if TYPE_CHECKING:
    from ..experiments.actuator import Experiment
    from .loop import ClosedLoop

__all__ = ["Move", "Specs", "default_moves"]

#: the unit each specification is given in (after "=" on the command line)
SPEC_UNITS = {"settling": "s", "rise": "s", "overshoot": "%", "error": "m",
              "effort": "", "variation": "", "band": ""}
#: the position resolution a loop with friction holds, as a fraction of the stroke: the
#: smallest default move and, without an error spec, the narrowest settling band
#: (20 µm on a 20 mm stroke, the default error spec)
RESOLUTION = 1e-3
#: time before a move starts: the loop rests at its start
T_BEFORE = 0.05
#: output points per second of a move (the metrics' time resolution: 2 ms)
POINTS_PER_SECOND = 500
#: ... within these bounds (a long move is sampled coarser)
MIN_POINTS, MAX_POINTS = 401, 4001


@dataclass(frozen=True)
class Specs:
    """Specifications of a position loop, met on every reference move.

    ``settling`` [s]: settling time into the band (``band``·|step|, at least ``error``);
    ``rise`` [s]: 10-90 % rise time (steps only); ``overshoot`` [%] of the step;
    ``error`` [m]: |steady-state error| (the mean over the last ``window`` of the move);
    ``no_hunting``: half the peak-to-peak of the position over that window within the
    band (no limit cycle, no creep); ``effort``: ∫(u − u₀)² dt and ``variation``: Σ|Δu|,
    in the controller output's units. ``fraction``: the share of uncertainty samples
    that must meet all of them (a robust design)."""

    settling: float | None = None
    rise: float | None = None
    overshoot: float | None = None
    error: float | None = None
    no_hunting: bool = False
    effort: float | None = None
    variation: float | None = None
    band: float = 0.02
    fraction: float = 0.95

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "no_hunting":
                if not isinstance(value, bool):
                    raise ParameterError(f"Specs: no_hunting = {value!r}; must be True or False")
                continue
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                    math.isfinite(value)) or value < 0 or (value == 0 and f.name != "overshoot"):
                raise ParameterError(f"Specs: {f.name} = {value!r}; must be a number > 0"
                                     + (" (overshoot: ≥ 0 %)" if f.name == "overshoot" else ""))
        if not 0 < self.band < 1:
            raise ParameterError(f"Specs: band = {self.band!r}; must be in (0, 1) (a fraction "
                                 "of the step)")
        if not 0 < self.fraction <= 1:
            raise ParameterError(f"Specs: fraction = {self.fraction!r}; must be in (0, 1]")
        if not self.limits() and not self.no_hunting:
            raise ParameterError("Specs: nothing to meet; give at least one of settling, "
                                 "rise, overshoot, error, no_hunting, effort, variation")

    def limits(self) -> dict[str, float]:
        """The numeric specifications that are given: name -> limit (SI, overshoot %)."""
        return {n: float(getattr(self, n)) for n in
                ("settling", "rise", "overshoot", "error", "effort", "variation")
                if getattr(self, n) is not None}

    @classmethod
    def parse(cls, text: str) -> Specs:
        """``"settling=0.3,overshoot=5%,error=20um,no-hunting"``: values with units (a bare
        number is SI; overshoot in %), ``no-hunting`` a flag."""
        from ..io.quantities import parse_value

        values: dict[str, object] = {}
        for item in (i.strip() for i in str(text).split(",")):
            if not item:
                continue
            name, _, given = (p.strip() for p in item.partition("="))
            key = name.replace("-", "_")
            if key == "no_hunting" and not given:
                values[key] = True
                continue
            if key not in SPEC_UNITS and key != "fraction":
                raise ParameterError(
                    f"--spec: '{name}' is not a specification; allowed: "
                    f"{', '.join([*SPEC_UNITS, 'fraction'])}, no-hunting")
            if not given:
                raise ParameterError(f"--spec: '{name}' needs a value, e.g. {name}=0.3")
            unit = SPEC_UNITS.get(key, "")
            if unit == "%" or key in ("band", "fraction"):
                number = given.removesuffix("%").strip()
                try:
                    value = float(number)
                except ValueError:
                    raise ParameterError(f"--spec: {name} = {given!r}; must be a number "
                                         "(in %)" if unit == "%" else "") from None
                if key in ("band", "fraction") and given.endswith("%"):
                    value /= 100.0
                values[key] = value
            else:
                try:
                    values[key] = float(given)  # a bare number is SI
                    continue
                except ValueError:
                    pass
                try:
                    values[key] = parse_value(key, given, unit)
                except ParameterError as exc:
                    raise ParameterError(f"--spec: {name} = {given!r}: {exc}") from None
        try:
            return cls(**values)  # type: ignore[arg-type]
        except ParameterError as exc:
            raise ParameterError(f"--spec {text!r}: {exc}") from None

    @classmethod
    def of(cls, value: Specs | str) -> Specs:
        if isinstance(value, Specs):
            return value
        if isinstance(value, str):
            return cls.parse(value)
        raise ParameterError(f"specs = {value!r}; give a Specs or a string such as "
                             "'settling=0.3,overshoot=5%,error=20um,no-hunting'")

    def describe(self) -> str:
        words = []
        for name, limit in self.limits().items():
            unit = {"settling": " s", "rise": " s", "overshoot": " %", "error": " m"}.get(name, "")
            words.append(f"{name} ≤ {limit:g}{unit}")
        if self.no_hunting:
            words.append("no hunting")
        return ", ".join(words) + f" (band {100 * self.band:g} %)"


@dataclass(frozen=True)
class Move:
    """A reference move: a set-point step or ramp from ``start`` to ``stop`` [m] at
    ``T_BEFORE``, held until ``t_end``; a ramp lasts ``duration`` [s]. Step metrics
    count from the step (a ramp: from its end). ``floor`` [m]: the narrowest settling
    band the plant can hold (its friction's resolution), used where no ``error`` is
    specified: without it a looser spec (no error limit) would ask a small step to settle
    into 2 % of itself, tighter than the stricter spec's band."""

    label: str
    start: float
    stop: float
    t_end: float
    duration: float = 0.0
    floor: float = 0.0

    def __post_init__(self):
        if self.stop == self.start:
            raise ParameterError(f"Move {self.label!r}: start = stop = {self.start:g} m; a "
                                 "move must move")
        if not self.t_end > self.t_ref + 0.05:
            raise ParameterError(f"Move {self.label!r}: t_end = {self.t_end:g} s; must leave "
                                 "time after the move")

    @property
    def t_ref(self) -> float:
        """Where the step metrics count from: the step, or the ramp's end."""
        return T_BEFORE + self.duration

    @property
    def size(self) -> float:
        return self.stop - self.start

    def experiment(self) -> Experiment:
        from ..experiments.setpoints import SetpointRamp, SetpointStep

        n = min(max(round(self.t_end * POINTS_PER_SECOND) + 1, MIN_POINTS), MAX_POINTS)
        if self.duration > 0:
            return SetpointRamp(self.start, self.stop, self.duration, T_BEFORE, self.t_end,
                                n_points=n)
        return SetpointStep(self.start, self.stop, T_BEFORE, self.t_end, n_points=n)

    def tolerance(self, specs: Specs) -> float:
        """The settling band [m]: band·|step|, at least the error specification (without
        one: at least the move's ``floor``)."""
        least = specs.error if specs.error is not None else self.floor
        return max(specs.band * abs(self.size), least)

    def window(self) -> float:
        """The evaluation window at the end: the last quarter of the time after the move."""
        return 0.25 * (self.t_end - self.t_ref)


def default_moves(loop: ClosedLoop, specs: Specs, at: float | None = None
                  ) -> tuple[Move, ...]:
    """Four moves around ``at`` (default mid-stroke; a rig: 0): a small step near the
    presliding range (½·Fs/σ0, at least 2× the error spec), steps of 20 % of the stroke
    up and down that cross break-away, and a ramp over that distance. They last 2.5×
    the settling spec after the move (at least 0.5 s). Without an error spec, each
    settles into a band of at least ``RESOLUTION`` of the stroke (``Move.floor``)."""
    params = loop.params
    stroke = loop.stroke
    scale = float(stroke) if stroke else 1.0
    at = (0.5 * scale if stroke else 0.0) if at is None else float(at)
    presliding = 0.0
    if "sigma0" in loop.gains or _has(params, "sigma0"):
        presliding = 0.5 * float(params["Fs"]) / float(params["sigma0"])
    floor = RESOLUTION * scale
    small = max(presliding, 2.0 * (specs.error or 0.0), floor)
    big = 0.2 * scale
    settle = specs.settling or 0.4
    t_end = T_BEFORE + max(2.5 * settle, 0.5)
    ramp = max(settle, 0.2)
    return (Move("small step", at, at + small, t_end, floor=floor),
            Move("step up", at, at + big, t_end, floor=floor),
            Move("step down", at + big, at, t_end, floor=floor),
            Move("ramp", at, at + big, T_BEFORE + ramp + max(2.5 * settle, 0.5), ramp,
                 floor=floor))


def _has(params, name: str) -> bool:
    try:
        value = float(params[name])
    except (KeyError, TypeError):
        return False
    return bool(np.isfinite(value))
