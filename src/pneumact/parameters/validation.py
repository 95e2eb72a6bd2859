"""Checks of parameter values: names, finiteness, declared ranges and relations, passivity.

One set (``problems``, ``validate``) gets every problem listed in one message, one line
per problem naming the field, the value and what is allowed. A table of many sets (the
batch engine) is checked column by column with numpy (``row_problems``), so that the
check of ten thousand rows costs milliseconds, not a Python loop over dictionaries.
"""

from __future__ import annotations

import difflib
import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from pneumact.errors import ParameterError, PassivityWarning, PlausibilityWarning
from pneumact.io.quantities import NUMBER_THEN_UNIT
from pneumact.parameters.catalogue import catalogue, explain_unknown, relations

__all__ = [
    "check_plausibility",
    "implausible",
    "lugre_passivity_problem",
    "message",
    "problems",
    "row_problems",
    "unit_slips",
    "unknown_name",
    "validate",
    "warn_passivity",
]


def unknown_name(name: str, where: str, known: Iterable[str] | None = None,
                 what: str = "parameter") -> str:
    """'unknown parameter 'Fss' in vgt-paper.toml (did you mean 'Fs'?)'; a renamed name
    with its new one, an instance's name with the instances or its kind's parameters."""
    candidates = list(catalogue() if known is None else known)
    text = f"unknown {what} '{name}'" + (f" in {where}" if where else "")
    explanation = explain_unknown(name) if known is None else ""
    if explanation:
        return f"{text}: {explanation}"
    lowered = {c.lower(): c for c in candidates}
    guess = lowered.get(name.lower())
    if guess is None:
        close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
        guess = lowered[close[0]] if close else None
    if guess is not None:
        return f"{text} (did you mean '{guess}'?)"
    return f"{text} (known: {', '.join(candidates)})"


def _shown(name: str, value: float, given: Mapping[str, str] | None = None) -> str:
    """'m = -1 kg', plus "(given as '-300 degC')" where a unit was converted."""
    spec = catalogue().get(name)
    unit = spec.unit if spec else ""
    text = f"{name} = {value:g} {unit}".rstrip()
    original = (given or {}).get(name)
    if original is not None:
        match = NUMBER_THEN_UNIT.fullmatch(original)
        if match is None or match.group(2) != unit:
            text += f" (given as '{original}')"
    return text


def problems(values: Mapping[str, Any], where: str,
             given: Mapping[str, str] | None = None) -> list[str]:
    """Every problem of a set of given SI values, one line each (empty: valid).

    Relations use what a model would use: the given value, else the catalogue default;
    a value that already failed its own range is left out of the relations so each
    mistake is reported once.
    """
    specs = catalogue()
    found: list[str] = []
    usable: dict[str, float] = {}
    for name, value in values.items():
        spec = specs.get(name)
        if spec is None:
            found.append(unknown_name(name, where))
        elif isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
            found.append(f"{name} = {value!r}: must be a number (SI value)")
        elif not math.isfinite(float(value)):
            found.append(f"{_shown(name, float(value), given)}: must be a finite number")
        elif not spec.in_range(float(value)):
            hint = spec.hint(float(value))
            found.append(f"{_shown(name, float(value), given)}: "
                         f"{spec.violation(float(value))}" + (f" ({hint})" if hint else ""))
        else:
            usable[name] = float(value)

    def current(name: str) -> float | None:
        return usable.get(name) if name in values else specs[name].default

    for relation in relations():
        args = [current(n) for n in relation.names]
        known = [a for a in args if a is not None]
        if len(known) == len(args) and not bool(relation.holds(*known)):
            first = relation.names[0]
            found.append(f"{_shown(first, known[0], given)}: {relation.explain(*known)}")
    return found


def _with_plausible_range(values: Mapping[str, float], names: Iterable[str] | None):
    """(name, value, catalogue entry) of each value (of ``names``, default all) whose
    entry states a plausible range."""
    specs = catalogue()
    for name in (values if names is None else names):
        spec = specs.get(name)
        if spec is not None and spec.plausible is not None and name in values:
            yield name, float(values[name]), spec


def unit_slips(values: Mapping[str, float], names: Iterable[str] | None = None,
               given: Mapping[str, str] | None = None) -> list[str]:
    """One line per value (of ``names``, default all) that can only be a unit slip: far
    outside the plausible range, and inside it a factor 1000 away."""
    found = []
    for name, value, spec in _with_plausible_range(values, names):
        slip = spec.unit_slip(value)
        if slip:
            lo, hi = spec.plausible
            found.append(f"{_shown(name, value, given)} is far outside the plausible range "
                         f"[{lo:g}, {hi:g}] {spec.unit}: {slip}")
    return found


def implausible(values: Mapping[str, float], names: Iterable[str] | None = None,
                given: Mapping[str, str] | None = None) -> list[str]:
    """One line per value (of ``names``, default all) that is legal but outside the range
    real actuators and rigs have, with the likely mistake where one is recognisable."""
    found = []
    for name, value, spec in _with_plausible_range(values, names):
        if not spec.is_plausible(value):
            lo, hi = spec.plausible
            hint = spec.hint(value)
            found.append(f"{_shown(name, value, given)} is outside the plausible range "
                         f"[{lo:g}, {hi:g}] {spec.unit}".rstrip()
                         + (f" ({hint})" if hint else ""))
    return found


def check_plausibility(values: Mapping[str, float], set_name: str, stacklevel: int,
                       names: Iterable[str] | None = None,
                       given: Mapping[str, str] | None = None,
                       source: object = None) -> None:
    """Raise one ParameterError for the values that can only be unit slips (like kPa
    typed as Pa: 12850 N/mm for a spring of 12850 N/m); else one PlausibilityWarning
    listing the values that are legal but implausible (if any). ``source``: the file the
    set was read from, named in the message."""
    wanted = list(values if names is None else names)
    slips = unit_slips(values, wanted, given)
    if slips:
        where = f" ({source})" if source is not None else ""
        raise ParameterError(message(f"invalid parameter set '{set_name}'{where}", slips))
    found = implausible(values, wanted, given)
    if found:
        warnings.warn(f"parameter set '{set_name}': {'; '.join(found)}; check the units "
                      "(if the values are meant, the run goes on as given)",
                      PlausibilityWarning, stacklevel=stacklevel + 1)


def message(header: str, found: Sequence[str]) -> str:
    if len(found) == 1:
        return f"{header}: {found[0]}"
    return f"{header} ({len(found)} problems):\n  " + "\n  ".join(found)


def validate(values: Mapping[str, float], set_name: str) -> None:
    """Raise one ParameterError listing every problem of ``values`` (or return)."""
    found = problems(values, f"parameter set '{set_name}'")
    if found:
        raise ParameterError(message(f"invalid parameter set '{set_name}'", found))


def row_problems(base: Mapping[str, float], columns: Sequence[str],
                 values: np.ndarray) -> list[str | None]:
    """Per row of ``values`` (n × len(columns), SI), why it is invalid, or None.

    ``base`` holds the values that apply where a column does not override them (the
    base set's given values; catalogue defaults fill the rest). Ranges and relations are
    evaluated on whole columns at once.
    """
    specs = catalogue()
    n = values.shape[0]
    reasons: list[list[str]] = [[] for _ in range(n)]
    column = {name: values[:, j] for j, name in enumerate(columns)}
    ok_value: dict[str, np.ndarray] = {}
    for name, array in column.items():
        spec = specs[name]
        inside = spec.in_range(array)
        ok_value[name] = inside
        for i in np.flatnonzero(~inside):
            shown = _shown(name, float(array[i]))
            what = ("must be a finite number" if not math.isfinite(array[i])
                    else spec.violation(float(array[i])))
            hint = spec.hint(float(array[i])) if math.isfinite(array[i]) else ""
            what += f" ({hint})" if hint else ""
            reasons[i].append(f"{shown}: {what}")
    for relation in relations():
        if not any(name in column for name in relation.names):
            continue  # unchanged by the table: the base set was validated on loading
        args, usable = [], np.ones(n, dtype=bool)
        for name in relation.names:
            if name in column:
                args.append(column[name])
                usable &= ok_value[name]
            else:
                value = base.get(name, specs[name].default)
                if value is None:
                    break
                args.append(np.full(n, float(value)))
        else:
            with np.errstate(invalid="ignore"):
                failed = usable & ~np.asarray(relation.holds(*args), dtype=bool)
            for i in np.flatnonzero(failed):
                scalars = [float(a[i]) for a in args]
                reasons[i].append(f"{_shown(relation.names[0], scalars[0])}: "
                                  f"{relation.explain(*scalars)}")
    return [None if not r else "invalid parameters: " + "; ".join(r) for r in reasons]


# --------------------------------------------------------------------------- passivity
#
# Passivity of the LuGre map v -> F_f (Barabanov & Ortega 2000, "Necessary and sufficient
# conditions for passivity of the LuGre friction model", IEEE TAC 45(4), 830-832; restated
# as eq. (7) in Astrom & Canudas de Wit 2008, "Revisiting the LuGre friction model", IEEE
# Control Systems Magazine 28(6)):
#
#     sigma1 <= sigma2 * Fc / (Fs - Fc)
#
# With y = sigma0*z, w = sgn(v)*y and the storage S = y^2/(2*sigma0):
# F*v - dS/dt = |v|*w^2/g + v^2*(sigma1 + sigma2 - sigma1*w/g). Since |y| <= Fs and
# g >= Fc, the bracket is >= sigma2 - sigma1*(Fs-Fc)/Fc, so the condition is sufficient;
# from y = Fs and a jump to a large speed V it is also necessary. The weaker
# "sigma1 < 4*sigma2*Fc/(Fs - Fc)" sometimes quoted is NOT sufficient (sigma1 = 2,
# sigma2 = 0.4, Fc = 1, Fs = 1.5 generates energy). Identified sets usually break it
# (sigma1 is chosen for presliding damping): that is a warning, not an error.

_PASSIVITY_SOURCE = "Barabanov & Ortega 2000, IEEE TAC 45(4); Astrom & Canudas de Wit 2008, eq. 7"


def lugre_passivity_problem(values: Mapping[str, float]) -> str | None:
    """How a LuGre parameter set breaks passivity, or None if it does not (or cannot
    tell: sigma0, Fc and Fs must be given; sigma1, sigma2 default to 0)."""
    if not all(name in values for name in ("sigma0", "Fc", "Fs")):
        return None
    specs = catalogue()
    s1 = float(values.get("sigma1", specs["sigma1"].default or 0.0))
    s2 = float(values.get("sigma2", specs["sigma2"].default or 0.0))
    fc, fs = float(values["Fc"]), float(values["Fs"])
    if fs <= fc:
        return None  # no Stribeck drop: passive for any sigma1 >= 0
    bound = s2 * fc / (fs - fc)
    if s1 <= bound * (1.0 + 1e-12):
        return None
    return (f"sigma1 = {s1:g} N*s/m breaks the LuGre passivity condition "
            f"sigma1 <= sigma2*Fc/(Fs - Fc) = {s2:g}*{fc:g}/({fs:g} - {fc:g}) = {bound:.4g} "
            f"N*s/m ({_PASSIVITY_SOURCE}): the friction model can deliver net energy at fast "
            "slip onsets")


def passivity_note(values: Mapping[str, float], set_name: str) -> str | None:
    """The passivity warning's text for a set, or None (``params show``, the reports)."""
    problem = lugre_passivity_problem(values)
    return f"parameter set '{set_name}': {problem}" if problem else None


def warn_passivity(values: Mapping[str, float], set_name: str, stacklevel: int) -> None:
    """A PassivityWarning, shown once per process and set (a filter registered with the
    warning category makes it "once"); ``params show``/``check`` and the reports repeat it."""
    note = passivity_note(values, set_name)
    if note:
        warnings.warn(note, PassivityWarning, stacklevel=stacklevel + 1)


# once per process and text, unless the user (or a test runner) set a filter of their own:
# appended, so any filter set before or after it takes precedence
warnings.filterwarnings("once", category=PassivityWarning, append=True)
