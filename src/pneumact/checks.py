"""The boundary: checks of the arguments a public function or a command receives.

Every public entry point checks what it is given here, before any numpy, scipy, numba or
SALib call can meet it, so that every mistake gets the same kind of message: the
argument, the value and what is allowed (``"n = 8.5: must be a whole number >= 2"``).
A wrong type raises ``ArgumentTypeError`` (a ``TypeError`` too) saying which type was
expected; a wrong value ``ArgumentError`` (a ``ValueError``), or the error class the
caller names (``error=DataError`` for a record).

The second half holds the physical limits the library states (absolute pressures, the
atmosphere) and the hints that name the likely mistake behind an impossible value: a
pressure typed in kPa where Pa is expected, a gauge pressure given as absolute.

This module imports nothing from pneumact but its errors: every layer may use it.
"""

from __future__ import annotations

import difflib
import math
import numbers
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from pneumact.errors import ArgumentError, ArgumentTypeError, PneumactError

_Option = TypeVar("_Option")

__all__ = [
    "ABSOLUTE_PRESSURE_PLAUSIBLE",
    "ATMOSPHERE_PLAUSIBLE",
    "MAX_ABSOLUTE_PRESSURE",
    "as_instance",
    "as_option",
    "check_absolute_pressure",
    "check_atmosphere",
    "check_bool",
    "check_choice",
    "check_finite",
    "check_int",
    "check_names",
    "check_out_dir",
    "check_path",
    "check_positive",
    "check_range",
    "check_seed",
    "check_type",
    "pressure_hint",
    "shown",
]

#: Highest absolute pressure pneumact accepts anywhere [Pa]: 10 MPa (100 bar), five times
#: the rating of industrial pneumatics; beyond it a value is a unit mistake, not a test.
MAX_ABSOLUTE_PRESSURE = 10e6
#: The absolute pressures an input takes [Pa]: below 1 kPa only a unit mistake (kPa or
#: bar typed as Pa), above ``MAX_ABSOLUTE_PRESSURE`` not a test.
ABSOLUTE_PRESSURE_PLAUSIBLE = (1e3, MAX_ABSOLUTE_PRESSURE)
#: Atmospheric pressures met on Earth where machines run [Pa]: 50 kPa (5.5 km altitude) to
#: 110 kPa (a deep mine, a strong high); outside it p_atm is suspicious, not impossible.
ATMOSPHERE_PLAUSIBLE = (50e3, 110e3)


# --------------------------------------------------------------------------- messages
def shown(value: Any) -> str:
    """A value as a message shows it: numbers with %g, the rest with repr (shortened)."""
    if isinstance(value, bool):
        return repr(value)
    if isinstance(value, numbers.Real):
        return f"{float(value):g}"
    if isinstance(value, type):
        return f"the class {value.__name__}"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _prefix(where: str) -> str:
    return f"{where}: " if where else ""


def _fail(error: type[PneumactError], where: str, name: str, value: Any, allowed: str,
          hint: str = "", unit: str = "") -> PneumactError:
    u = f" {unit}" if unit else ""
    return error(f"{_prefix(where)}{name} = {shown(value)}{u}: {allowed}"
                 + (f" ({hint})" if hint else ""))


def type_name(expected: type | tuple[type, ...]) -> str:
    """'a number', 'a str or a Path', ... for a message."""
    names = {int: "a whole number", float: "a number", numbers.Real: "a number",
             numbers.Integral: "a whole number", str: "a string", bool: "True or False",
             Path: "a path", os.PathLike: "a path"}
    kinds = expected if isinstance(expected, tuple) else (expected,)
    words = [names.get(k, f"a {k.__name__}") for k in kinds]
    return " or ".join(dict.fromkeys(words))


# --------------------------------------------------------------------------- types
def check_type(name: str, value: Any, expected: type | tuple[type, ...], *, where: str = "",
               what: str | None = None) -> Any:
    """``value`` if it is an instance of ``expected``; else ArgumentTypeError saying
    which type was expected (``what`` replaces the generated wording)."""
    if isinstance(value, expected):
        return value
    wanted = what or type_name(expected)
    raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be {wanted}, "
                            f"not {type(value).__name__}")


def _real(name: str, value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        if isinstance(value, str):
            try:
                float(value)
                fix = f" (write {name}={value.strip()} without quotes, in SI units)"
            except ValueError:
                fix = ""
            raise ArgumentTypeError(
                f"{_prefix(where)}{name} = {value!r}: must be a number, not a string{fix}")
        raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be a number, "
                                f"not {type(value).__name__}")
    return float(value)


def check_finite(name: str, value: Any, *, where: str = "",
                 error: type[PneumactError] = ArgumentError) -> float:
    """A real number (not a bool, not a string) that is finite, as a float."""
    number = _real(name, value, where)
    if not math.isfinite(number):
        raise _fail(error, where, name, number, "must be a finite number")
    return number


def check_range(name: str, value: Any, low: float | None = None, high: float | None = None,
                *, unit: str = "", low_open: bool = False, high_open: bool = False,
                where: str = "", error: type[PneumactError] = ArgumentError,
                hint: str = "") -> float:
    """A finite number within [low, high] (either end open or absent)."""
    number = check_finite(name, value, where=where, error=error)
    below = low is not None and (number <= low if low_open else number < low)
    above = high is not None and (number >= high if high_open else number > high)
    if below or above:
        u = f" {unit}" if unit else ""
        if low is not None and high is not None:
            allowed = (f"must be in {'(' if low_open else '['}{low:g}, {high:g}"
                       f"{')' if high_open else ']'}{u}")
        elif low is not None:
            allowed = f"must be {'>' if low_open else '>='} {low:g}{u}"
        else:
            allowed = f"must be {'<' if high_open else '<='} {high:g}{u}"
        raise _fail(error, where, name, number, allowed, hint, unit)
    return number


def check_positive(name: str, value: Any, *, unit: str = "", strict: bool = True,
                   where: str = "", error: type[PneumactError] = ArgumentError) -> float:
    """A finite number > 0 (>= 0 unless ``strict``)."""
    return check_range(name, value, 0.0, unit=unit, low_open=strict, where=where, error=error)


def check_int(name: str, value: Any, *, minimum: int | None = None,
              maximum: int | None = None, where: str = "",
              error: type[PneumactError] = ArgumentError) -> int:
    """A whole number (an int, or a float with no fraction) within [minimum, maximum]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be a whole "
                                f"number, not {type(value).__name__}")
    if isinstance(value, numbers.Integral):
        whole = int(value)
    else:
        number = float(value)
        if not (math.isfinite(number) and number.is_integer()):
            raise ArgumentTypeError(f"{_prefix(where)}{name} = {number:g}: must be a whole "
                                    "number")
        whole = int(number)
    if (minimum is not None and whole < minimum) or (maximum is not None and whole > maximum):
        if minimum is not None and maximum is not None:
            allowed = f"must be a whole number in [{minimum}, {maximum}]"
        elif minimum is not None:
            allowed = f"must be a whole number >= {minimum}"
        else:
            allowed = f"must be a whole number <= {maximum}"
        raise error(f"{_prefix(where)}{name} = {whole}: {allowed}")
    return whole


def check_seed(name: str, value: Any, *, where: str = "") -> int:
    """A random seed: a whole number in [0, 2**32 - 1] (what numpy accepts)."""
    return check_int(name, value, minimum=0, maximum=2**32 - 1, where=where)


def check_bool(name: str, value: Any, *, where: str = "") -> bool:
    """True or False (numpy's bool too), nothing that is merely truthy."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be True or "
                            f"False, not {type(value).__name__}")


def check_choice(name: str, value: Any, choices: Iterable[str], *, where: str = "",
                 error: type[PneumactError] = ArgumentError) -> str:
    """One of ``choices`` (a string), with a guess when it is close to one."""
    allowed = list(choices)
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be one of "
                                f"{', '.join(allowed)}, not {type(value).__name__}")
    if value in allowed:
        return value
    close = difflib.get_close_matches(value, allowed, n=1, cutoff=0.6)
    guess = f" (did you mean '{close[0]}'?)" if close else ""
    raise error(f"{_prefix(where)}{name} = {value!r}: allowed: {', '.join(allowed)}{guess}")


def check_names(name: str, values: Any, *, known: Sequence[str] | None = None,
                where: str = "", what: str = "name", allow_empty: bool = True,
                error: type[PneumactError] = ArgumentError) -> list[str]:
    """A list of distinct names (a single string is one name), each in ``known`` if given."""
    if isinstance(values, str):
        values = [values]
    if not isinstance(values, Iterable):
        raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(values)}: must be a list "
                                f"of {what}s, not {type(values).__name__}")
    items = list(values)
    for item in items:
        if not isinstance(item, str) or not item.strip():
            raise ArgumentTypeError(f"{_prefix(where)}{name}: {shown(item)} is not a {what} "
                                    "(a non-empty string)")
    twice = sorted({n for n in items if items.count(n) > 1})
    if twice:
        raise error(f"{_prefix(where)}{name} names {', '.join(twice)} more than once; give "
                    f"each {what} once")
    if not items and not allow_empty:
        raise error(f"{_prefix(where)}{name} is empty; give at least one {what}")
    if known is not None:
        for item in items:
            if item not in known:
                close = difflib.get_close_matches(item, list(known), n=1, cutoff=0.6)
                hint = (f"did you mean '{close[0]}'?" if close
                        else f"allowed: {', '.join(known)}")
                raise error(f"{_prefix(where)}{name}: unknown {what} '{item}' ({hint})")
    return items


def check_path(name: str, value: Any, *, where: str = "") -> Path:
    """A file-system path (a str or an os.PathLike), as a Path."""
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bytes):
        text = os.fspath(value)
        if isinstance(text, str) and text.strip():
            return Path(text)
        raise ArgumentError(f"{_prefix(where)}{name} = {value!r}: must be a non-empty path")
    raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be a file path "
                            f"(a str or a pathlib.Path), not {type(value).__name__}")


#: the longest output folder name [bytes of UTF-8]: file systems allow 255, and a run
#: stages beside the folder under its name plus at most 30 characters
#: (".NAME.pneumact-stage-XXXXXXXX")
MAX_OUT_NAME_BYTES = 225


def check_out_dir(name: str, value: Any, *, where: str = "") -> Path:
    """An output folder: a path that is not an existing file, whose parents are not files,
    whose name leaves room for the run's staging folder beside it."""
    path = check_path(name, value, where=where)
    size = len(path.resolve().name.encode("utf-8", "surrogateescape"))
    if size > MAX_OUT_NAME_BYTES:
        raise ArgumentError(f"{_prefix(where)}{name}: the folder name is {size} characters "
                            f"long ('{path.name[:40]}...'); at most {MAX_OUT_NAME_BYTES} "
                            "(file systems allow 255 per name, and a run works in a folder "
                            "beside it named after it): give a shorter name")
    if path.exists() and not path.is_dir():
        raise ArgumentError(f"{_prefix(where)}{name} = '{path}': is a file; give a folder "
                            "(it is created if missing)")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise ArgumentError(f"{_prefix(where)}{name} = '{path}': '{parent}' is a file, "
                                    "so the folder cannot be created there")
            break
    return path


def as_instance(name: str, value: Any, base: type, *, examples: str, where: str = "") -> Any:
    """A strategy object: an instance of ``base``; its class is instantiated with its
    defaults (``valve=CommandValve`` reads as ``CommandValve()``); anything else (a
    name string, a function) is refused with ``examples`` of what to pass."""
    if isinstance(value, base):
        return value
    if isinstance(value, type) and issubclass(value, base):
        try:
            return value()
        except TypeError:
            raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: pass an "
                                    f"instance, {value.__name__}(...), not the class") from None
    hint = ""
    if isinstance(value, str):
        hint = (" (strategies are objects, not names: the command line's names map onto "
                "these objects)")
    raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be a "
                            f"{base.__name__} object such as {examples}, not "
                            f"{type(value).__name__}{hint}")


def as_option(name: str, value: Any, option: type[_Option], *, where: str = "",
              plain: Any = None, accepts: str = "") -> _Option:
    """An option object (a frozen dataclass that checks itself): ``value`` when it is one,
    its defaults for None, or what ``plain(value)`` makes of a plain value that means one
    thing (``multistart=4`` reads as ``Multistart(starts=4)``; ``plain`` returns None
    for a value it does not take). ``accepts`` says which plain values are taken."""
    if value is None:
        return option()
    if isinstance(value, option):
        return value
    made = plain(value) if plain is not None else None
    if made is not None:
        return made
    also = f" or {accepts}" if accepts else ""
    raise ArgumentTypeError(f"{_prefix(where)}{name} = {shown(value)}: must be a "
                            f"{option.__name__}(...){also}, not {type(value).__name__}")


# --------------------------------------------------------------------------- physics
def pressure_hint(value: float, plausible: tuple[float, float] = ATMOSPHERE_PLAUSIBLE) -> str:
    """The likely mistake behind an implausible absolute pressure [Pa], or ''."""
    lo, hi = plausible
    if not math.isfinite(value):
        return ""
    if value <= 0.0:
        return ("an absolute pressure is > 0; a value <= 0 looks like a gauge pressure "
                "(relative to the atmosphere): absolute = p_atm + gauge")
    for factor, unit in ((1e3, "kPa"), (1e5, "bar"), (1e2, "hPa or mbar"), (1e6, "MPa")):
        if lo <= value * factor <= hi:
            return (f"{value:g} looks like {unit} typed as Pa: write '{value:g} {unit}' in a "
                    f"file, or {value * factor:g} (Pa) from Python")
    return ""


def check_absolute_pressure(name: str, value: Any, *, where: str = "",
                            error: type[PneumactError] = ArgumentError,
                            plausible: tuple[float, float] = ABSOLUTE_PRESSURE_PLAUSIBLE
                            ) -> float:
    """An absolute pressure [Pa]: finite, > 0 and <= MAX_ABSOLUTE_PRESSURE; a value that
    is only possible as a unit mistake (below ``plausible``) is refused with the hint."""
    number = check_finite(name, value, where=where, error=error)
    lo, _ = plausible
    if number <= 0.0 or number > MAX_ABSOLUTE_PRESSURE or number < lo:
        hint = pressure_hint(number, (lo, MAX_ABSOLUTE_PRESSURE))
        raise error(f"{_prefix(where)}{name} = {number:g} Pa: an absolute pressure must be in "
                    f"[{lo:g}, {MAX_ABSOLUTE_PRESSURE:g}] Pa" + (f" ({hint})" if hint else ""))
    return number


def check_atmosphere(name: str, value: Any, *, where: str = "",
                     error: type[PneumactError] = ArgumentError) -> float:
    """The atmospheric pressure [Pa absolute]: refused when it can only be a mistake
    (<= 0, kPa or bar typed as Pa, beyond MAX_ABSOLUTE_PRESSURE); a value outside
    ``ATMOSPHERE_PLAUSIBLE`` that could be meant is returned (the caller may warn)."""
    number = check_finite(name, value, where=where, error=error)
    lo, hi = ATMOSPHERE_PLAUSIBLE
    hint = pressure_hint(number) if not lo <= number <= hi else ""
    if number <= 0.0 or number > MAX_ABSOLUTE_PRESSURE or hint:
        raise error(f"{_prefix(where)}{name} = {number:g} Pa: the atmosphere is {lo:g} to "
                    f"{hi:g} Pa absolute on Earth" + (f" ({hint})" if hint else ""))
    return number
