"""Option objects: small frozen dataclasses that group the options of the orchestrators
(``simulate_batch``, ``fit``, the sensitivity studies, ``identify_paper``) and that the
command line builds too, its defaults taken from theirs.

Each checks itself when built: a wrong value is refused with the field, the value and
what is allowed. A function that takes one accepts a plain value wherever it means one
thing: ``executor=4`` is ``Executor(workers=4)``, ``checkpoint="runs"`` is
``Checkpoint("runs")``, ``multistart=4`` is ``Multistart(starts=4)``,
``profile=["sigma0"]`` is ``Profile(names=("sigma0",))``, ``bounds={"Fc": (1, 5)}`` is
``Bounds({"Fc": (1, 5)})``, ``optimizer="soft_l1"`` is ``Optimizer(loss="soft_l1")``,
``offsets=["position"]`` is ``Offsets(signals=("position",))``,
``weights={"position": 2.0}`` is ``Weights(signals={...})``.

- where many simulations run: ``Executor`` (threads or a Dask cluster, chunk size) and
  ``Checkpoint`` (the folder that keeps finished runs, to resume);
- how ``fit`` searches: ``Bounds``, ``Weights``, ``Optimizer``, ``Multistart``,
  ``Profile``, ``Offsets``.

This module imports nothing from pneumact but its checks and errors (no numpy): the
command line reads the defaults from here without paying for the library.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from .checks import (
    as_option,
    check_bool,
    check_choice,
    check_finite,
    check_int,
    check_names,
    check_out_dir,
    check_positive,
    check_seed,
)
from .errors import ArgumentError, ArgumentTypeError

__all__ = ["JACOBIANS", "LOSSES", "SCHEDULER_PROTOCOLS", "Bounds", "Checkpoint", "Executor",
           "Multistart", "Offsets", "Optimizer", "Profile", "Weights",
           "check_scheduler_address"]

SCHEDULER_PROTOCOLS = ("tcp", "tls", "ucx", "ws", "wss", "inproc")


def check_scheduler_address(address: str, name: str = "scheduler") -> str:
    """A Dask scheduler address 'tcp://host:port' (or 'host:port'), checked before any
    connection is tried: what is not an address is refused at once, not after a timeout."""
    text = address.strip()
    protocol, sep, rest = text.partition("://")
    if not sep:
        protocol, rest = "tcp", text
    match = re.fullmatch(r"(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):(\d{1,5})", rest)
    if protocol not in SCHEDULER_PROTOCOLS or (protocol != "inproc" and (
            match is None or not 0 < int(match[2]) < 65536)):
        raise ArgumentError(
            f"{name} = {address!r}: not a Dask scheduler address; write "
            "'tcp://HOST:PORT' (e.g. 'tcp://127.0.0.1:8786', as printed by dask-scheduler)")
    return f"{protocol}://{rest}"


@dataclass(frozen=True)
class Executor:
    """Where many simulations run: ``workers`` threads on this machine (None: every
    core), or a Dask ``scheduler`` (an address 'tcp://host:port' or a
    ``distributed.Client``; its workers then count); ``chunk_size`` runs per task (None:
    about four tasks per worker)."""

    workers: int | None = None
    scheduler: Any = None
    chunk_size: int | None = None

    def __post_init__(self):
        if self.workers is not None:
            object.__setattr__(self, "workers", check_int("workers", self.workers, minimum=1,
                                                          where="Executor"))
        if self.chunk_size is not None:
            object.__setattr__(self, "chunk_size", check_int(
                "chunk_size", self.chunk_size, minimum=1, where="Executor"))
        if isinstance(self.scheduler, str):
            check_scheduler_address(self.scheduler, "Executor: scheduler")
        elif self.scheduler is not None and not hasattr(self.scheduler, "submit"):
            raise ArgumentTypeError(f"Executor: scheduler = {self.scheduler!r:.60}: must be "
                                    "an address string ('tcp://host:8786') or a "
                                    "distributed.Client")

    @property
    def threads(self) -> int:
        """The local threads it runs on: ``workers``, else every core."""
        return self.workers or os.cpu_count() or 1

    @classmethod
    def of(cls, value, where: str = "", name: str = "executor") -> Executor:
        """An Executor from itself, None (the defaults), a number of worker threads, or a
        Dask scheduler address."""
        def plain(v):
            if isinstance(v, int) and not isinstance(v, bool):
                return cls(workers=v)
            if isinstance(v, str) or hasattr(v, "submit"):  # an address, a Client
                return cls(scheduler=v)
            return None

        return as_option(name, value, cls, where=where, plain=plain,
                         accepts="a number of worker threads, or a Dask scheduler address "
                                 "or distributed.Client")


@dataclass(frozen=True)
class Checkpoint:
    """The folder that keeps a long run's finished work: an interrupted run is kept
    there and continued with ``resume=True``; ``overwrite=True`` starts it again
    (discarding what the folder holds). The folder is replaced only by a complete run."""

    folder: str | os.PathLike
    resume: bool = False
    overwrite: bool = False

    def __post_init__(self):
        object.__setattr__(self, "folder", check_out_dir("folder", self.folder,
                                                         where="Checkpoint"))
        for name in ("resume", "overwrite"):
            check_bool(name, getattr(self, name), where="Checkpoint")
        if self.resume and self.overwrite:
            raise ArgumentError("Checkpoint: resume=True and overwrite=True contradict each "
                                "other: continue the kept runs, or start them again, not both")

    @property
    def path(self) -> Path:
        return Path(self.folder)

    def within(self, name: str) -> Checkpoint:
        """The same checkpoint for a sub-folder ``name`` (one study of several)."""
        return Checkpoint(self.path / name, self.resume, self.overwrite)

    @classmethod
    def of(cls, value, where: str = "", name: str = "checkpoint") -> Checkpoint | None:
        """A Checkpoint from itself, a folder path (no resume, no overwrite), or None
        (no checkpoint)."""
        if value is None:
            return None

        def plain(v):
            return cls(v) if isinstance(v, (str, os.PathLike)) else None

        return as_option(name, value, cls, where=where, plain=plain, accepts="a folder path")


# --------------------------------------------------------------------------- fit
#: the robust losses of scipy's least_squares
LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")
#: how the Jacobian is computed: forward sensitivities, or finite differences
JACOBIANS = ("sensitivities", "2-point", "3-point")


def _names(value) -> bool:
    """A name or a sequence of names (a plain value for a list-of-names option)."""
    return isinstance(value, str) or (isinstance(value, Sequence) and not isinstance(
        value, (bytes, bytearray)))


def _frozen_mapping(name: str, where: str, value, check_item) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ArgumentTypeError(f"{where}: {name} = {value!r:.60}: must be a dict (name -> "
                                f"value), not {type(value).__name__}")
    out = {}
    for key, item in value.items():
        if not isinstance(key, str):
            raise ArgumentTypeError(f"{where}: {name} key {key!r}: must be a name")
        out[key] = check_item(f"{name}[{key!r}]", item)
    return MappingProxyType(out)


@dataclass(frozen=True)
class Bounds:
    """The search space: ``ranges`` gives (low, high) per parameter name (SI; the others
    default to the catalogue's range, or a factor of 100 either side of the start);
    ``log`` says which are fitted in log scale: True (every positive free parameter),
    False, or a list of names."""

    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    log: bool | Sequence[str] = True

    def __post_init__(self):
        def pair(name, value):
            if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or \
                    len(value) != 2:
                raise ArgumentTypeError(f"Bounds: {name} = {value!r:.60}: must be a pair "
                                        "(low, high)")
            low = check_finite(f"{name} low", value[0], where="Bounds")
            high = check_finite(f"{name} high", value[1], where="Bounds")
            if not low < high:
                raise ArgumentError(f"Bounds: {name} = ({low:g}, {high:g}): must have low < "
                                    "high")
            return low, high

        object.__setattr__(self, "ranges", _frozen_mapping("ranges", "Bounds", self.ranges,
                                                           pair))
        if not isinstance(self.log, bool):
            object.__setattr__(self, "log", tuple(check_names(
                "log", self.log, where="Bounds", what="parameter name")))

    def log_names(self, free: Sequence[str]) -> list[str]:
        """The free parameters fitted in log scale (those that are positive)."""
        return list(free) if self.log is True else [] if self.log is False else list(self.log)

    @classmethod
    def of(cls, value, where: str = "fit") -> Bounds:
        return as_option("bounds", value, cls, where=where,
                         plain=lambda v: cls(v) if isinstance(v, Mapping) else None,
                         accepts="a dict of name -> (low, high)")


@dataclass(frozen=True)
class Weights:
    """What each residual counts for: ``signals`` multiplies each fitted signal's
    residuals (keys among the fitted signals; a signal not named: 1/std of its
    measurement); ``records`` each record's (one
    finite weight > 0 per record; default 1): a record whose measured input carries more
    noise counts for less."""

    signals: Mapping[str, float] | None = None
    records: Sequence[float] | None = None

    def __post_init__(self):
        if self.signals is not None:
            object.__setattr__(self, "signals", _frozen_mapping(
                "signals", "Weights", self.signals,
                lambda n, v: check_positive(n, v, where="Weights")))
        if self.records is not None:
            if isinstance(self.records, (str, bytes)) or not isinstance(self.records,
                                                                        Sequence):
                raise ArgumentTypeError(f"Weights: records = {self.records!r:.60}: must be "
                                        "a list of weights, one per record")
            object.__setattr__(self, "records", tuple(
                check_positive(f"records[{i}]", w, where="Weights")
                for i, w in enumerate(self.records)))

    @classmethod
    def of(cls, value, where: str = "fit") -> Weights:
        return as_option("weights", value, cls, where=where,
                         plain=lambda v: cls(signals=v) if isinstance(v, Mapping) else None,
                         accepts="a dict of signal -> weight")


@dataclass(frozen=True)
class Optimizer:
    """How ``scipy.optimize.least_squares`` runs: ``loss`` and ``f_scale`` (a robust
    loss such as "soft_l1" for outliers), ``jacobian`` (forward "sensitivities", one
    simulation per record and iteration, or finite differences "2-point"/"3-point"),
    ``max_nfev`` (None: scipy's default)."""

    loss: str = "linear"
    f_scale: float = 1.0
    jacobian: str = "sensitivities"
    max_nfev: int | None = None

    def __post_init__(self):
        check_choice("loss", self.loss, LOSSES, where="Optimizer")
        object.__setattr__(self, "f_scale", check_positive("f_scale", self.f_scale,
                                                           where="Optimizer"))
        check_choice("jacobian", self.jacobian, JACOBIANS, where="Optimizer")
        if self.max_nfev is not None:
            object.__setattr__(self, "max_nfev", check_int("max_nfev", self.max_nfev,
                                                           minimum=1, where="Optimizer"))

    @classmethod
    def of(cls, value, where: str = "fit") -> Optimizer:
        return as_option("optimizer", value, cls, where=where,
                         plain=lambda v: cls(loss=v) if isinstance(v, str) else None,
                         accepts="a loss name")


@dataclass(frozen=True)
class Multistart:
    """``starts`` more Latin-hypercube starts inside the bounds (0: only the given
    start), drawn with ``seed``; they need finite bounds for every free parameter."""

    starts: int = 0
    seed: int = 0

    def __post_init__(self):
        object.__setattr__(self, "starts", check_int("starts", self.starts, minimum=0,
                                                     where="Multistart"))
        object.__setattr__(self, "seed", check_seed("seed", self.seed, where="Multistart"))

    @classmethod
    def of(cls, value, where: str = "fit") -> Multistart:
        def plain(v):
            return cls(starts=v) if isinstance(v, int) and not isinstance(v, bool) else None

        return as_option("multistart", value, cls, where=where, plain=plain,
                         accepts="a number of starts")


@dataclass(frozen=True)
class Profile:
    """Profile likelihoods of the free parameters ``names``, each stepped out at most
    ``points`` times on each side of the optimum."""

    names: Sequence[str] = ()
    points: int = 8

    def __post_init__(self):
        object.__setattr__(self, "names", tuple(check_names(
            "names", self.names, where="Profile", what="parameter name")))
        object.__setattr__(self, "points", check_int("points", self.points, minimum=3,
                                                     where="Profile"))

    @classmethod
    def of(cls, value, where: str = "fit") -> Profile:
        return as_option("profile", value, cls, where=where,
                         plain=lambda v: cls(names=v) if _names(v) else None,
                         accepts="a list of parameter names")


@dataclass(frozen=True)
class Offsets:
    """A free additive sensor offset of each signal of ``signals`` (fitted signals),
    one per record of ``records`` (record indices; None: every record)."""

    signals: Sequence[str] = ()
    records: Sequence[int] | None = None

    def __post_init__(self):
        object.__setattr__(self, "signals", tuple(check_names(
            "signals", self.signals, where="Offsets", what="signal name")))
        if self.records is not None:
            if isinstance(self.records, (str, bytes)) or not isinstance(self.records,
                                                                        Sequence):
                raise ArgumentTypeError(f"Offsets: records = {self.records!r:.60}: must be a "
                                        "list of record indices")
            object.__setattr__(self, "records", tuple(
                check_int(f"records[{i}]", r, minimum=0, where="Offsets")
                for i, r in enumerate(self.records)))

    @classmethod
    def of(cls, value, where: str = "fit") -> Offsets:
        return as_option("offsets", value, cls, where=where,
                         plain=lambda v: cls(signals=v) if _names(v) else None,
                         accepts="a list of signal names")

