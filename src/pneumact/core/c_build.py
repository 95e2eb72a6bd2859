"""The C compiler on this machine, and a shared library built from C source with it.

One place for both users of the C back end (``core.c_source``): the run-time C engine
(``core.c_engine``) and the exported FMU's binary (``export.compiler``). The compiler is
``$CC``, else the first of cc, gcc, clang on PATH; nothing here raises when there is
none (``compiler_path`` answers None and ``missing_compiler`` says what to install), so
each user decides what a missing compiler means (the engine falls back to numba, the
FMU export refuses).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from ..errors import PneumactError

__all__ = [
    "CANDIDATES",
    "INSTALL_HINT",
    "CBuildError",
    "CSourceError",
    "compile_library",
    "compiler_path",
    "missing_compiler",
    "shared_library_suffix",
]

CANDIDATES = ("cc", "gcc", "clang")
#: what to install, per platform, when no C compiler is found
INSTALL_HINT = {
    "linux": "install gcc (Debian/Ubuntu: sudo apt install gcc; Fedora: sudo dnf install gcc)",
    "darwin": "install the Xcode command line tools (xcode-select --install)",
    "win32": "install a gcc or clang for Windows (e.g. MinGW-w64 or LLVM) and put it on PATH, "
             "or set CC to it",
}


class CBuildError(PneumactError, RuntimeError):
    """No C compiler, or the compiler refused a source (its own message is in the text)."""


class CSourceError(RuntimeError):
    """A construct of a kernel function the C back end does not translate (raised by
    ``core.c_source``; here so that catching it does not import numba)."""


def compiler_path(compiler: str | None = None) -> str | None:
    """Path of the C compiler: ``compiler`` if given, else ``$CC``, else the first of
    cc, gcc, clang on PATH; None when that one (or any) is not found."""
    wanted = compiler or os.environ.get("CC")
    if wanted:
        return shutil.which(wanted)
    return next((found for name in CANDIDATES if (found := shutil.which(name))), None)


def missing_compiler(compiler: str | None = None) -> str:
    """Why ``compiler_path(compiler)`` found nothing, and what to install."""
    wanted = compiler or os.environ.get("CC")
    if wanted:
        where = "compiler=" if compiler else "$CC"
        return f"C compiler {wanted!r} (from {where}) was not found on PATH"
    hint = INSTALL_HINT.get(sys.platform, INSTALL_HINT["linux"])
    return f"no C compiler found (looked for $CC, {', '.join(CANDIDATES)}): {hint}"


def shared_library_suffix() -> str:
    return {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")


def compile_library(compiler: str, sources: Sequence[Path], output: Path,
                    flags: Sequence[str], include_dirs: Sequence[Path] = ()) -> None:
    """Build the shared library ``output`` from ``sources`` with ``compiler`` and
    ``flags`` (-fPIC left out on Windows); CBuildError with the compiler's message when
    it fails."""
    flags = [f for f in flags if not (sys.platform == "win32" and f == "-fPIC")]
    includes = [arg for folder in include_dirs for arg in ("-I", str(folder))]
    command = [compiler, *flags, *includes, *map(str, sources), "-o", str(output), "-lm"]
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise CBuildError(f"{' '.join(command)} failed:\n{result.stderr[-4000:]}")
