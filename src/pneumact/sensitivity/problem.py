"""What a sensitivity study varies: factors (parameters) with ranges and distributions.

``Problem.around(params, {"sigma0": "50%", "Fs": (2.8, 3.6)})`` builds the factors from
a parameter set: a per-cent string is ± that fraction of the nominal value, a pair is
(low, high) in SI. ``to_salib()`` gives SALib's problem dictionary.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["DEFAULT_RANGES", "DISTRIBUTIONS", "Factor", "Problem", "parse_variation"]

#: Ranges of a global study of the six LuGre parameters unless given: ±20 % of sigma0,
#: sigma1, sigma2 and vs, ±10 % of Fc and Fs (so that no run of vgt-paper has Fs < Fc:
#: Fc ≤ 2.86 N < 2.88 N ≤ Fs).
DEFAULT_RANGES = {"sigma0": "20%", "sigma1": "20%", "sigma2": "20%", "vs": "20%",
                  "Fc": "10%", "Fs": "10%"}

#: our name -> SALib's: uniform on [low, high]; normal with mean ± 2 sd = [low, high];
#: log-uniform on [low, high] (sampled uniform in log, mapped back).
DISTRIBUTIONS = ("uniform", "normal", "loguniform")


@dataclass(frozen=True)
class Factor:
    """One varied parameter: its range [low, high] (SI) and distribution."""

    name: str
    low: float
    high: float
    nominal: float
    distribution: str = "uniform"

    def __post_init__(self):
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"factor {self.name}: distribution = {self.distribution!r}; "
                                 f"allowed: {', '.join(DISTRIBUTIONS)}")
        if not (np.isfinite(self.low) and np.isfinite(self.high) and self.low < self.high):
            raise ParameterError(f"factor {self.name}: range ({self.low:g}, {self.high:g}) "
                                 "must be finite with low < high")
        if self.distribution == "loguniform" and self.low <= 0:
            raise ParameterError(f"factor {self.name}: a log-uniform range needs low > 0, "
                                 f"got {self.low:g}")


def parse_variation(name: str, spec, nominal: float) -> tuple[float, float]:
    """(low, high) from "20%" (± 20 % of ``nominal``), a number (± that fraction), or a
    (low, high) pair in SI."""
    if isinstance(spec, str):
        text = spec.strip()
        if not text.endswith("%"):
            raise ParameterError(f"{name}: variation {spec!r}; give 'N%' or (low, high)")
        try:
            fraction = float(text[:-1]) / 100
        except ValueError:
            raise ParameterError(f"{name}: variation {spec!r} is not a number of per cent"
                                 ) from None
        return _around(name, nominal, fraction)
    if isinstance(spec, (int, float)):
        return _around(name, nominal, float(spec))
    try:
        low, high = (float(v) for v in spec)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: variation {spec!r}; give 'N%' or (low, high)") from None
    return low, high


def _around(name: str, nominal: float, fraction: float) -> tuple[float, float]:
    if not 0 <= fraction:
        raise ParameterError(f"{name}: variation of {100 * fraction:g} %; must be >= 0")
    half = abs(nominal) * fraction
    return nominal - half, nominal + half


@dataclass(frozen=True)
class Problem:
    """The factors of a study and the nominal values of everything else."""

    factors: tuple[Factor, ...]

    @classmethod
    def around(cls, params, variations: Mapping[str, object],
               distribution: str = "uniform") -> Problem:
        from ..parameters import catalogue
        from ..parameters.validation import unknown_name

        specs = catalogue()
        factors = []
        for name, spec in variations.items():
            if name not in specs:
                raise ParameterError(unknown_name(name, "the variations"))
            nominal = float(params[name])
            low, high = parse_variation(name, spec, nominal)
            factors.append(Factor(name, low, high, nominal, distribution))
        if not factors:
            raise ParameterError("a sensitivity problem needs at least one varied parameter")
        return cls(tuple(factors))

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.factors]

    def to_salib(self) -> dict:
        bounds, dists = [], []
        for f in self.factors:
            if f.distribution == "uniform":
                bounds.append([f.low, f.high])
                dists.append("unif")
            elif f.distribution == "normal":
                bounds.append([0.5 * (f.low + f.high), 0.25 * (f.high - f.low)])
                dists.append("norm")
            else:  # log-uniform: sample uniform in log, map back in ``transform``
                bounds.append([np.log(f.low), np.log(f.high)])
                dists.append("unif")
        return {"num_vars": len(self.factors), "names": self.names, "bounds": bounds,
                "dists": dists}

    def transform(self, sample: np.ndarray) -> np.ndarray:
        """SALib's sample (log-uniform factors in log) to parameter values (SI)."""
        out = np.array(sample, dtype=float)
        for j, f in enumerate(self.factors):
            if f.distribution == "loguniform":
                out[:, j] = np.exp(out[:, j])
        return out
