"""``ParameterSet``: an immutable, validated set of parameter values in SI units.

It holds the values its source gives (with the original text, source and note of each)
and the set's provenance. Defaults are not copied in: ``ps["delta"]`` falls back to the
catalogue default when the set does not give delta. Reading files is in ``files.py``,
unit conversion in ``units.py``, the checks in ``validation.py``.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, ValuesView
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from pneumact.errors import ParameterError
from pneumact.io.quantities import parse_value
from pneumact.io.report import ResultVocabulary
from pneumact.parameters.catalogue import catalogue
from pneumact.parameters.validation import (
    check_plausibility,
    implausible,
    lugre_passivity_problem,
    message,
    passivity_note,
    problems,
    unknown_name,
    warn_passivity,
)

from ..plotting import tight_layout

if TYPE_CHECKING:
    import os

    import pandas as pd
    from matplotlib.figure import Figure

__all__ = ["ParameterInfo", "ParameterSet"]


@dataclass(frozen=True)
class ParameterInfo:
    """Where a given value came from: original text (e.g. "60 cm^3"), source, note."""

    given: str
    source: str
    note: str = ""


class _GivenValues(Mapping[str, float]):
    """Read-only view of the given SI values; also callable, so ``ps.values()`` still
    behaves as ``Mapping.values()``."""

    __slots__ = ("_data",)

    def __init__(self, data: dict[str, float]) -> None:
        self._data = data

    def __getitem__(self, key: str) -> float:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __call__(self) -> ValuesView[float]:
        return ValuesView(self)

    def __repr__(self) -> str:
        return repr(self._data)


class MissingParameterError(ParameterError, KeyError):
    """A value that is neither given nor defaulted; a KeyError too, so ``get`` works."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def number_text(name: str, value: float) -> str:
    """'0.63 kg': how a value given as a plain SI number is recorded."""
    return f"{float(value)!r} {catalogue()[name].unit}".rstrip()


class ParameterSet(ResultVocabulary, Mapping[str, float]):
    """An immutable, validated parameter set in SI units.

    As a Mapping it holds the GIVEN values only (``len``, iteration, ``in``), but
    ``ps[name]`` falls back to the catalogue default and raises ParameterError (also a
    KeyError) when there is neither. ``info[name]`` tells where a given value came from.
    The constructor takes SI numbers and validates them; it does not warn about
    passivity (``load_params``, ``from_dict`` and ``replace`` do).

    Like every result: ``to_pandas()`` (the table of values with provenance), ``plot()``
    (each value within its plausible range) and ``write(folder)`` (the TOML file, the
    table, the figure and report.html).
    """

    __slots__ = ("_description", "_info", "_name", "_provenance", "_source_path",
                 "_values")
    # the slots' types (bare annotations create no class attribute, so no clash with
    # __slots__); they are set once, in _init
    _name: str
    _description: str
    _provenance: dict[str, str]
    _values: dict[str, float]
    _info: dict[str, ParameterInfo]
    _source_path: Path | None

    def __init__(self, values: Mapping[str, float], *, name: str = "custom",
                 description: str = "", provenance: Mapping[str, str] | None = None,
                 info: Mapping[str, ParameterInfo] | None = None,
                 source_path: Path | None = None) -> None:
        given = {n: i.given for n, i in (info or {}).items()}
        found = problems(values, f"parameter set '{name}'", given)
        if found:
            where = f" ({source_path})" if source_path is not None else ""
            raise ParameterError(message(f"invalid parameter set '{name}'{where}", found))
        order = list(catalogue())
        ordered = {n: float(values[n]) for n in sorted(values, key=order.index)}
        info = dict(info or {})
        full_info = {n: info.get(n) or ParameterInfo(number_text(n, v), "", "")
                     for n, v in ordered.items()}
        self._init(name, description, dict(provenance or {}), ordered, full_info,
                   source_path)

    def _init(self, name: str, description: str, provenance: Mapping[str, str],
              values: dict[str, float], info: dict[str, ParameterInfo],
              source_path: Path | None) -> None:
        setter = object.__setattr__
        setter(self, "_name", str(name))
        setter(self, "_description", str(description))
        setter(self, "_provenance", {str(k): str(v) for k, v in provenance.items()})
        setter(self, "_values", values)
        setter(self, "_info", info)
        setter(self, "_source_path", source_path)

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"ParameterSet is immutable; use replace() (tried to set {key})")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"ParameterSet is immutable (tried to delete {key})")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (_restore, (self._name, self._description, dict(self._provenance),
                           dict(self._values), dict(self._info), self._source_path))

    # -- attributes
    @property
    def name(self) -> str:
        """Set name, e.g. 'vgt-paper'."""
        return self._name

    @property
    def description(self) -> str:
        """One-line description of the set."""
        return self._description

    @property
    def provenance(self) -> dict[str, str]:
        """Source and notes of the set as a whole (a copy)."""
        return dict(self._provenance)

    @property
    def source_path(self) -> Path | None:
        """The TOML file the set was read from, if any."""
        return self._source_path

    @property
    def values(self) -> _GivenValues:
        """Given values only, name -> SI float (read-only; ``values()`` also works)."""
        return _GivenValues(self._values)

    @property
    def info(self) -> Mapping[str, ParameterInfo]:
        """name -> ParameterInfo (original text, source, note) of each given value."""
        return MappingProxyType(self._info)

    # -- Mapping over the given values
    def __getitem__(self, name: str) -> float:
        value = self._values.get(name)
        if value is not None:
            return value
        spec = catalogue().get(name)
        if spec is None:
            raise MissingParameterError(unknown_name(name, f"parameter set '{self._name}'"))
        if spec.default is None:
            raise MissingParameterError(f"parameter '{name}' is not given in parameter set "
                                        f"'{self._name}' and has no default")
        return spec.default

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __contains__(self, name: object) -> bool:
        return name in self._values

    def __repr__(self) -> str:
        return f"ParameterSet({self._name!r}, {len(self._values)} given)"

    # -- derived sets
    @classmethod
    def from_dict(cls, values: Mapping[str, float | str], name: str = "custom", *,
                  description: str = "") -> ParameterSet:
        """Build a validated set from Python: numbers are SI, strings carry units."""
        parsed, info = parse_entries(values, f"parameter set '{name}'", "from_dict")
        ps = cls(parsed, name=name, description=description, info=info)
        check_plausibility(ps.values, ps.name, stacklevel=2,
                           given={n: i.given for n, i in info.items()},
                           source=ps.source_path)
        warn_passivity(ps.values, ps.name, stacklevel=2)
        return ps

    def replace(self, values: Mapping[str, float | str] | None = None, /,
                **kw: float | str) -> ParameterSet:
        """A validated copy with values changed or added (numbers SI, strings with units).

        Warns about passivity only if the change breaks it (a set loaded with the warning
        does not warn again on every replace, e.g. in an identification loop).
        """
        changes = {**(values or {}), **kw}
        parsed, info = parse_entries(changes, f"replace() on parameter set '{self._name}'",
                                     "replace()")
        ps = ParameterSet({**self._values, **parsed}, name=self._name,
                          description=self._description, provenance=self._provenance,
                          info={**self._info, **info}, source_path=self._source_path)
        check_plausibility(ps.values, ps.name, stacklevel=2, names=list(parsed),
                           given={n: i.given for n, i in info.items()},
                           source=ps.source_path)
        if lugre_passivity_problem(self._values) is None:
            warn_passivity(ps.values, ps.name, stacklevel=2)
        return ps

    def with_values(self, values: Mapping[str, float]) -> ParameterSet:
        """A validated copy with SI ``values`` changed, without the passivity and
        plausibility warnings of ``replace``: for procedures that move values many times
        (fits, identification) and judge the result as a whole."""
        changed = {n: float(v) for n, v in values.items()}
        info = {n: ParameterInfo(number_text(n, v), "computed", "")
                for n, v in changed.items() if n not in self._info or
                self._values.get(n) != v}
        return ParameterSet({**self._values, **changed}, name=self._name,
                            description=self._description, provenance=self._provenance,
                            info={**self._info, **info}, source_path=self._source_path)

    # -- use by models
    def require(self, names: Iterable[str], model: str) -> None:
        """Raise one ParameterError listing every name that has neither value nor default."""
        specs = catalogue()
        wanted = list(dict.fromkeys(names))
        unknown = [n for n in wanted if n not in specs]
        if unknown:
            raise ParameterError("; ".join(unknown_name(n, f"the requirements of {model}")
                                           for n in unknown))
        missing = [n for n in specs if n in wanted and n not in self._values
                   and specs[n].default is None]
        if missing:
            raise ParameterError(
                f"parameter set '{self._name}' lacks {', '.join(missing)} needed by {model} "
                "(add them to the parameter file, or use ParameterSet.replace)")

    def notes(self) -> list[str]:
        """What a report says about this set besides its values: the LuGre passivity
        condition it breaks and the values outside the plausible ranges (otherwise
        warnings, shown once per process)."""
        notes = [passivity_note(self.values, self.name)]
        notes += [f"{line} (PlausibilityWarning)" for line in implausible(self.values)]
        return [n for n in notes if n]

    report_title = "Parameter set"
    figure_name = "plausible_ranges"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"parameters": self.to_pandas()}

    def report_text(self) -> str:
        return f"{self._name}: {self._description}".rstrip(": ")

    def report_parameters(self) -> ParameterSet:
        return self

    def plot(self) -> Figure:
        """Each given value with a plausible range (``catalogue``), placed within it on a
        log scale: 0 at the range's low end, 1 at its high end (outside: implausible)."""
        import matplotlib.pyplot as plt
        import numpy as np

        rows = []
        for name, value in self._values.items():
            plausible = catalogue()[name].plausible
            if plausible and value > 0 and plausible[0] > 0:
                low, high = np.log(plausible)
                rows.append((name, (np.log(value) - low) / (high - low)))
        fig, ax = plt.subplots(figsize=(6.5, 0.25 * len(rows) + 1.2))
        ax.barh([r[0] for r in rows], [r[1] for r in rows], color="C0")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.axvline(1.0, color="k", lw=0.8)
        ax.invert_yaxis()
        ax.set_xlabel("position in the plausible range (log scale; 0 low end, 1 high end)")
        ax.set_title(self._name, fontsize=10)
        ax.grid(True, axis="x", alpha=0.3)
        tight_layout(fig)
        return fig

    def write(self, out_dir: str | os.PathLike[str], *, call: str = "") -> list[Path]:
        """parameters.toml (the parameter file), parameters.csv, the figure and
        report.html, all or nothing."""
        from pneumact.io.report import figure_png, table_writer
        from pneumact.io.tables import write_files
        from pneumact.parameters.files import write_params

        png = figure_png(self.plot())
        return write_files(out_dir, {
            "parameters.toml": lambda p: write_params(self, p),
            "parameters.csv": table_writer(self.to_pandas()),
            f"{self.figure_name}.png": lambda p: Path(p).write_bytes(png),
            "report.html": self.report(call, png).write})

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """Table of the set: given parameters, then defaults in use (source 'default');
        ``name``: "parameters" (the one table) or None."""
        import pandas as pd

        if name not in (None, "parameters"):
            raise ParameterError(f"to_pandas: name = {name!r}; allowed: parameters")

        rows = []
        for spec in catalogue().values():
            if spec.name in self._values:
                meta = self._info[spec.name]
                rows.append((spec.name, self._values[spec.name], spec.unit, meta.given,
                             meta.source, spec.description))
        for spec in catalogue().values():
            if spec.name not in self._values and spec.default is not None:
                rows.append((spec.name, float(spec.default), spec.unit, "", "default",
                             spec.description))
        return pd.DataFrame(rows, columns=["name", "value", "unit", "given", "source",
                                           "description"])


def _restore(name: str, description: str, provenance: dict[str, str],
             values: dict[str, float], info: dict[str, ParameterInfo],
             source_path: Path | None) -> ParameterSet:
    """Unpickle without re-validating or warning (the set was valid when pickled)."""
    ps = object.__new__(ParameterSet)
    ps._init(name, description, provenance, values, info, source_path)
    return ps


def parse_entries(values: Mapping[str, Any], where: str, source: str
                  ) -> tuple[dict[str, float], dict[str, ParameterInfo]]:
    """Python-side values (numbers SI, strings with units) -> SI floats and their info."""
    specs = catalogue()
    found: list[str] = []
    parsed: dict[str, float] = {}
    info: dict[str, ParameterInfo] = {}
    for name, raw in values.items():
        if name not in specs:
            found.append(unknown_name(name, where))
            continue
        try:
            parsed[name] = parse_value(name, raw, specs[name].unit, bare_number_is_si=True)
        except ParameterError as exc:
            found.append(str(exc))
            continue
        given = raw if isinstance(raw, str) else number_text(name, parsed[name])
        info[name] = ParameterInfo(given, source, "")
    if found:
        raise ParameterError(message(f"cannot use values for {where}", found))
    return parsed, info
