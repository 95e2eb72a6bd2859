"""The C compiler an FMU's binary is built with, and where the FMI headers come from.

The binary is built for the platform pneumact runs on, with the C compiler found on the
machine (``$CC``, else ``cc``, ``gcc``, ``clang``); the FMI 2.0 headers are FMPy's
(``pip install "pneumact[fmu]"``), never a copy kept in this repository.
"""

from __future__ import annotations

import os
import platform
import sys
from pathlib import Path

from ..core.c_build import (
    CBuildError,
    compile_library,
    compiler_path,
    missing_compiler,
    shared_library_suffix,
)
from ..errors import ExportError

__all__ = ["binary_folder", "build_binary", "find_compiler", "fmi_headers",
           "platform_tuple", "shared_library_suffix"]

#: -fno-tree-vectorize: gcc -O3 pairs the loads of the triangular solves into 16-byte loads of
#: a vector the previous row has just written 8 bytes of, which stalls every row on a failed
#: store forwarding (10-15 % of a Co-Simulation step); the results are the same either way
#: (no flag here lets the compiler reorder floating-point operations)
FLAGS = ("-O3", "-fno-tree-vectorize", "-std=c99", "-fPIC", "-fvisibility=hidden", "-shared")


def find_compiler(compiler: str | None = None) -> str:
    """Path of the C compiler: ``compiler`` if given, else ``$CC``, else the first of
    cc, gcc, clang on PATH; ExportError naming what to install when there is none."""
    found = compiler_path(compiler)
    if found is None:
        reason = missing_compiler(compiler)
        if not (compiler or os.environ.get("CC")):
            reason = reason.replace("found (", "found to build the FMU's binary (", 1)
            reason += ("; or export the sources only (binary=False, pneumact export fmu "
                       "--no-binary): an importer can build them")
        raise ExportError(reason)
    return found


def fmi_headers() -> Path:
    """The folder of FMPy's FMI 2.0 and 3.0 headers (fmi2Functions.h, fmi3Functions.h, …)."""
    try:
        import fmpy  # type: ignore[import-untyped]
    except ImportError as error:
        raise ExportError('building an FMU needs FMPy (its FMI headers): pip install '
                          '"pneumact[fmu]"') from error
    folder = Path(fmpy.__file__).parent / "c-code"
    if not (folder / "fmi2Functions.h").is_file():
        raise ExportError(f"FMPy {fmpy.__version__} has no fmi2Functions.h in {folder}")
    return folder


def binary_folder() -> str:
    """The FMI 2.0 name of this platform's binaries folder (linux64, darwin64, win64)."""
    bits = "64" if sys.maxsize > 2**32 else "32"
    system = {"linux": "linux", "darwin": "darwin", "win32": "win"}.get(sys.platform)
    if system is None or platform.machine().lower() not in ("x86_64", "amd64", "arm64",
                                                             "aarch64", "i686", "x86"):
        raise ExportError(f"no FMI 2.0 binaries folder for {sys.platform} "
                          f"{platform.machine()}: export the sources only (binary=False)")
    return system + bits


def platform_tuple() -> str:
    """FMI 3.0's name of this platform's binaries folder (x86_64-linux, aarch64-darwin, …)."""
    folder = binary_folder()  # refuses a platform FMI does not name
    machine = platform.machine().lower()
    architecture = {"amd64": "x86_64", "arm64": "aarch64", "i686": "x86"}.get(machine, machine)
    if sys.maxsize <= 2**32 and architecture == "x86_64":
        architecture = "x86"
    return f"{architecture}-{folder.rstrip('0123456789').replace('win', 'windows')}"


def build_binary(sources: list[Path], output: Path, compiler: str | None = None) -> str:
    """Compile ``sources`` into the shared library ``output``; returns the compiler used.
    A failed build raises ExportError with the compiler's own message."""
    cc = find_compiler(compiler)
    try:
        compile_library(cc, sources, output, FLAGS, (fmi_headers(), sources[0].parent))
    except CBuildError as error:
        raise ExportError(f"building the FMU's binary failed ({error})") from None
    return cc
