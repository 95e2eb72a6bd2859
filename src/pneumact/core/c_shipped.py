"""The C translations shipped with the package: a fresh install's first run only compiles.

Building a C library costs numba's typing of every function it calls (the C back end,
``core.c_source``, writes C from numba's typed IR: about 5 s of CPU for an actuator's run
library) and then the C compiler (under a second). The libraries the first ``pneumact
simulate`` builds (the default model's run library and the common library of signals and
features, ``core.c_common``) are therefore translated ahead, by ``tools/ship_c.py``, and
shipped here as package data: ``shipped_c/<name>-<key>.c.gz`` and its ``.h``.

Each is found by its ``translation_key``: a digest of the sources it is translated from
(the kernel's generated text and every source file it depends on), the C back end's own
sources, numba's version, numpy's and Python's (major.minor): what decides the C, and
nothing of the machine's. A shipped file whose key no longer matches is never read (an edit to an
equation, to the back end or another numba translates afresh, as before), and
``tests/integration/test_shipped_c.py`` fails until it is regenerated:

    PYTHONPATH=src python tools/ship_c.py
"""

from __future__ import annotations

import gzip
import hashlib
import logging
import sys
from collections.abc import Iterable
from pathlib import Path

__all__ = ["SHIPPED_DIR", "read_shipped", "shipped_path", "translation_key", "write_shipped"]

#: where the shipped translations live (package data)
SHIPPED_DIR = Path(__file__).with_name("shipped_c")
#: the layout of a shipped translation; a change of it changes every key
FORMAT = "pneumact shipped C 1"
#: the back end's sources: they decide the C of any function (and the entry signatures)
BACK_END = ("c_source.py", "c_abi.py", "c_engine.py", "c_common.py")
#: how many hex digits of the key a file name carries
KEY_DIGITS = 24

_LOG = logging.getLogger("pneumact.engine")


def translation_key(what: str, sources: Iterable[Path]) -> str:
    """The key of a translation of ``what`` (a kernel's content key and library group, or
    a library's name) from the files ``sources``: a digest of those, of the back end's
    sources and of the versions that decide numba's typing (``_versions``); no path,
    no machine."""
    digest = hashlib.sha256(f"{FORMAT}\n{what}\n".encode())
    here = Path(__file__).parent
    for path in (*sources, *(here / name for name in BACK_END)):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    digest.update(_versions().encode())
    return digest.hexdigest()


def _versions() -> str:
    """numba's version, numpy's and Python's major.minor: numba types the kernels (by
    numpy's rules for its functions) from Python's bytecode."""
    from importlib.metadata import version

    numpy = ".".join(version("numpy").split(".")[:2])
    python = ".".join(map(str, sys.version_info[:2]))
    return f"numba {version('numba')}; numpy {numpy}; python {python}"


def shipped_path(name: str, key: str, folder: Path | None = None) -> Path:
    """Where the shipped C source of library ``name`` with ``key`` lives (its header
    beside it, ``.h`` in place of ``.c.gz``)."""
    return (folder or SHIPPED_DIR) / f"{name}-{key[:KEY_DIGITS]}.c.gz"


def _header_path(source: Path) -> Path:
    return source.with_name(source.name.removesuffix(".c.gz") + ".h")


def read_shipped(name: str, key: str) -> tuple[str, str] | None:
    """(C source, header) shipped for library ``name`` under ``key``; None when none is
    (the code has changed since it was shipped, or this library was never shipped)."""
    source = shipped_path(name, key)
    try:
        text = gzip.decompress(source.read_bytes()).decode("utf-8")
        header = _header_path(source).read_text(encoding="utf-8")
    except FileNotFoundError:
        _LOG.debug("no shipped C for %s (key %s): translating", name, key[:KEY_DIGITS])
        return None
    _LOG.debug("the shipped C of %s (key %s)", name, key[:KEY_DIGITS])
    return text, header


def write_shipped(name: str, key: str, source: str, header: str,
                  folder: Path | None = None) -> list[Path]:
    """Write library ``name``'s translation under ``key`` into ``folder`` (default the
    package's), replacing the earlier ones of ``name``; the files written. The gzip
    stream carries no time stamp: the same C gives the same bytes."""
    folder = folder or SHIPPED_DIR
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob(f"{name}-*"):
        old.unlink()
    path = shipped_path(name, key, folder)
    path.write_bytes(gzip.compress(source.encode("utf-8"), compresslevel=9, mtime=0))
    _header_path(path).write_text(header, encoding="utf-8")
    return [path, _header_path(path)]
