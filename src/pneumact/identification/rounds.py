"""A second round of bench tests, designed from what a first identification found (issue 38).

A campaign designed from a prior far from the truth can miss the speeds that tell the
friction: ramps that stick-slip give no steady segment, and stages (b, c) cannot run.
``next_round(ident)`` designs the next campaign from the first round's result:

- each guess the plan is sized from (``campaign.GUESSED``) is the first round's estimate
  where that estimate has an interval the procedure reports (identified, or poorly
  identified with a finite interval), its spread the interval's relative half-width
  (at least ``MIN_ROUND_SPREAD``); every other value stays the prior's, with the prior's
  spread: an estimate without an interval is not known, so the plan does not lean on it;
- where Fs and vs are not both identified, some of the first round's ramps slower than
  its slowest steady sliding gave no steady segment, and that speed is more than
  ``STICK_SLIP_GAP`` times the slowest ramp the new design asks for, the ramps start at
  that speed instead: the slower ones stick-slipped and would again (the actuator, not
  the prior, decides stick-slip);
- every test's name ends in ``_round<N>``, so that the records of both rounds can be
  identified together (``identify_paper`` refuses two records of one name).

The plan's ``prior`` is the design set, each value's source saying which it is
(identified, estimate, or prior), and its notes say the same in words. Identify the
records of both rounds from it: ``identify_paper(records + records_2, plan.prior)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from .bench import steady_segments
from .campaign import DEFAULT_SPREAD, GUESSED, RAMP_SPEEDS, CampaignPlan, design_campaign
from .stages import presliding_range

if TYPE_CHECKING:
    from ..parameters.parameter_set import ParameterSet
    from .paper import PaperIdentification

__all__ = ["MIN_ROUND_SPREAD", "STICK_SLIP_GAP", "design_set", "next_round",
           "stick_slip_limit"]

#: The narrowest spread a second round is designed for: an identified value's 95 %
#: interval is ±2.5 %, but the plan keeps margins for the value being off by more.
MIN_ROUND_SPREAD = 0.1
#: The widest spread a plan can be sized for (``design_campaign`` needs < 1).
MAX_ROUND_SPREAD = 0.9
#: Ramps start above the speeds where the first round stick-slipped when the slowest
#: steady segment is this many times faster than the slowest ramp designed.
STICK_SLIP_GAP = 2.0


def design_set(ident: PaperIdentification, spread: float = DEFAULT_SPREAD
               ) -> tuple[ParameterSet, dict[str, float], dict[str, str]]:
    """(the values a next round is designed from, their spreads, what each value is:
    "identified", "estimate" or "prior"); ``spread`` is the first round's prior's."""
    from ..parameters import ParameterSet
    from ..parameters.parameter_set import ParameterInfo, number_text

    table = ident.to_pandas()
    prior = ident.initial
    values, spreads, roles = {}, {}, {}
    for name in GUESSED:
        row = table.loc[name]
        low, high, value = row["ci95_low"], row["ci95_high"], float(row["value"])
        if np.isfinite(low) and np.isfinite(high) and value > 0:
            half = (high - low) / 2 / value
            values[name] = value
            spreads[name] = float(np.clip(half, MIN_ROUND_SPREAD, MAX_ROUND_SPREAD))
            roles[name] = "identified" if row["verdict"] == "identified" else "estimate"
        else:
            values[name], spreads[name], roles[name] = float(prior[name]), spread, "prior"
    if values["Fs"] < values["Fc"]:  # the prior's Fs on an estimated Fc: its ratio
        values["Fs"] = prior["Fs"] / prior["Fc"] * values["Fc"]
    words = {"identified": "identified in round 1", "estimate": "round 1's estimate, "
             "poorly identified", "prior": "prior value: not identified in round 1"}
    info = dict(prior.info)
    for name in GUESSED:
        info[name] = ParameterInfo(number_text(name, values[name]), words[roles[name]],
                                   f"designed for ±{100 * spreads[name]:.0f} %")
    try:
        chosen = ParameterSet({**prior.values, **values}, name=f"{prior.name}-round2",
                              description=f"next round's design set from {prior.name}",
                              provenance=prior.provenance, info=info)
    except ParameterError as exc:
        raise ParameterError(f"next_round: the first round's estimates do not make a "
                             f"parameter set ({exc})") from None
    return chosen, spreads, roles


def stick_slip_limit(ident: PaperIdentification, params, spread: float
                     ) -> tuple[float, int]:
    """(the slowest steady sliding speed [m/s] of the first round's ramps, how many of its
    ramps are slower and gave no steady segment); (0, 0) when none is. A slower ramp is a
    longer one: a designed ramp's duration falls with its speed."""
    from .paper import record_kind

    creep = presliding_range(params) / max(1.0 - spread, 0.1)
    ramps = [(float(r.time[-1] - r.time[0]),
              np.abs(steady_segments(r, params, presliding_range=creep)["velocity"])
              .to_numpy()) for r in ident.records if record_kind(r) == "ramp"]
    steady = [(duration, float(v.min())) for duration, v in ramps if v.size]
    if not steady:
        return 0.0, 0
    longest, slowest = min(steady, key=lambda pair: pair[1])
    stuck = sum(1 for duration, v in ramps if not v.size and duration > longest)
    return (slowest, stuck) if stuck else (0.0, 0)


def next_round(ident: PaperIdentification, spread: float = DEFAULT_SPREAD,
               ramps: int = RAMP_SPEEDS, number: int = 2) -> CampaignPlan:
    """The bench tests of round ``number``, designed from the first round's result (see
    the module docstring); ``spread`` is the first round's prior's."""
    if number < 2:
        raise ParameterError(f"next_round: number = {number}; a next round is round 2 or "
                             "later")
    chosen, spreads, roles = design_set(ident, spread)
    staged = ident.staged_parameters if ident.staged_parameters is not None else chosen
    steady, stuck = stick_slip_limit(ident, staged, spread)
    default = design_campaign(chosen, spreads, ramps)
    designed_slowest = min(v for t, v in default.speeds.items() if t.startswith("ramp"))
    slowest = None
    known = roles["Fs"] == roles["vs"] == "identified"  # eq. 12 needs no slower ramps
    if stuck and not known and steady > STICK_SLIP_GAP * designed_slowest:
        fastest = max(v for t, v in default.speeds.items() if t.startswith("ramp"))
        slowest = float(min(steady, fastest / 4))
    plan = design_campaign(chosen, spreads, ramps, slowest=slowest,
                           suffix=f"_round{number}")
    notes = [f"designed from round 1: {_listed(roles, 'identified')} identified; "
             f"{_listed(roles, 'estimate')} round 1's estimates, poorly identified; "
             f"{_listed(roles, 'prior')} the prior's values, not identified"]
    if slowest is not None:
        notes.append(f"ramps from {slowest * 1e3:.3g} mm/s, the slowest steady sliding of "
                     f"round 1 ({stuck} slower ramps gave no steady segment), not from "
                     f"{designed_slowest * 1e3:.3g} mm/s: slower ramps stick-slip")
    return CampaignPlan(plan.tests, plan.purposes, plan.speeds, plan.prior, plan.spread,
                        [*notes, *plan.notes], plan.spreads)


def _listed(roles: dict[str, str], role: str) -> str:
    names = [n for n, r in roles.items() if r == role]
    return ", ".join(names) if names else "none"
