"""Options shared by every orchestrator that runs many simulations (the batch, the fit's
starts, the sensitivity studies) and by the command line, which builds the same objects.

``Executor``: where the runs go (threads on this machine, or a Dask cluster) and in
chunks of how many. ``Checkpoint``: the folder that keeps finished runs, so that an
interrupted study can be resumed. Both are frozen and check themselves when built: a
wrong value is refused with the field, the value and what is allowed.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..checks import as_option, check_bool, check_int, check_out_dir
from ..errors import ArgumentError, ArgumentTypeError

__all__ = ["SCHEDULER_PROTOCOLS", "Checkpoint", "Executor", "check_scheduler_address"]

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
            if isinstance(v, str):
                return cls(scheduler=v)
            return None

        return as_option(name, value, cls, where=where, plain=plain,
                         accepts="a number of worker threads or a Dask scheduler address")


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
