"""Translate the C libraries the command line's ``pneumact simulate`` builds, and ship them
with the package (``src/pneumact/core/shipped_c/``, see ``core.c_shipped``).

Shipped: the common library of signals and features, and the run library of every model
``pneumact simulate`` builds from its options with the default parameter set:
each ``--valve`` (``pneumact.models.VALVES``) with each ``--friction``
(``friction_models()``), built as the command builds it (``cli.common.build_model``;
``--chamber`` needs none of its own: the chamber laws are parameters of one kernel), and
``--model cylinder``'s default. A combination the command refuses with the default
options (``--friction gms``: ``vgt-paper`` lacks its parameters) is skipped, saying why.
Their C comes from numba's typing of the kernel functions (2-4 s of CPU each); shipped, a
first run of any of them only compiles it. Run this after a change to a kernel's code,
the C back end or numba (``tests/integration/test_shipped_c.py`` fails until then); it
translates every library (about a minute) and removes the files of libraries no longer
shipped:

    PYTHONPATH=src python tools/ship_c.py            # write the shipped C
    PYTHONPATH=src python tools/ship_c.py --missing  # only those without a file for their key
    PYTHONPATH=src python tools/ship_c.py --check    # exit 1 if a shipped file is stale
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from pneumact.cli.common import (
    DEFAULT_FRICTION,
    DEFAULT_VALVE,
    ModelKind,
    ModelOptions,
    Valve,
    build_model,
    build_model_of,
)
from pneumact.core import c_common, c_engine
from pneumact.core.c_shipped import SHIPPED_DIR, read_shipped, shipped_path, write_shipped
from pneumact.errors import ArgumentError, PassivityWarning
from pneumact.models import VALVES
from pneumact.models.friction import friction_models
from pneumact.simulation import assemble

#: the command a fresh install runs first
FIRST_COMMAND = "pneumact simulate"
#: Python's string hashing while translating: numba's IR of some kernels (the cylinder's)
#: orders its phi variables by set iteration, which follows the hash seed; fixed, a
#: regeneration of unchanged code writes the same bytes and ``--check`` compares like
#: with like (the C differs only in the order of declarations and copies, not in meaning)
HASH_SEED = "0"
#: the shipped files' endings (``c_shipped``: the gzipped C and its header)
ENDINGS = (".c.gz", ".h")


class Library(NamedTuple):
    """A shipped library: its translation key, a fresh translation, what builds it."""

    key: str
    translate: Callable[[], tuple[str, str]]
    command: str


def _command(valve: str, friction: str) -> str:
    options = [f"--valve {valve}"] if valve != DEFAULT_VALVE.value else []
    options += [f"--friction {friction}"] if friction != str(DEFAULT_FRICTION) else []
    return " ".join([FIRST_COMMAND, *options])


def command_models() -> tuple[dict[str, Any], dict[str, str]]:
    """(command -> the model it builds, command -> why the command refuses it): every
    ``--valve`` with every ``--friction`` (the default chamber and set), built as
    ``pneumact simulate`` builds them, and ``--model cylinder``."""
    models: dict[str, Any] = {}
    refused: dict[str, str] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)  # the published sigma1
        for valve in VALVES:
            for friction in friction_models():
                command = _command(valve, friction)
                try:
                    _, models[command] = build_model(ModelOptions(valve=Valve(valve),
                                                                  friction=friction))
                except ArgumentError as error:
                    refused[command] = str(error)
        _, models[f"{FIRST_COMMAND} --model cylinder"], _ = build_model_of(
            ModelKind.cylinder, ModelOptions())
    return models, refused


def _run_library(spec, command: str) -> tuple[str, Library]:
    return c_engine.shipped_name(spec, "run"), Library(
        c_engine.kernel_translation_key(spec, "run"),
        lambda: c_engine.translate_kernel(spec, "run"), command)


def _common() -> tuple[str, Library]:
    return c_common.SHIPPED_NAME, Library(c_common.common_translation_key(),
                                          c_common.translate_common, FIRST_COMMAND)


def first_run_libraries() -> dict[str, Library]:
    """name -> library of the two a fresh install's first ``pneumact simulate`` (no
    options) builds: the default model's run library and the common library."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        _, actuator = build_model(ModelOptions())
    return dict([_run_library(assemble(actuator).kernel_spec(), FIRST_COMMAND), _common()])


def shipped_libraries() -> dict[str, Library]:
    """name -> library of each library shipped: the first run's two, then the run
    library of every other model ``command_models`` builds."""
    libraries = first_run_libraries()
    models, _ = command_models()
    for command, model in models.items():
        name, library = _run_library(assemble(model).kernel_spec(), command)
        if name in libraries and libraries[name].key != library.key:
            raise RuntimeError(f"{command} and {libraries[name].command} build different "
                               f"kernels of one name, {name}: one shipped file each cannot be")
        libraries.setdefault(name, library)
    return libraries


def orphans(libraries: dict[str, Library], folder: Path = SHIPPED_DIR) -> list[Path]:
    """The files in ``folder`` that are no current key's file of ``libraries``."""
    current = {shipped_path(name, library.key, folder).name.removesuffix(".c.gz")
               for name, library in libraries.items()}
    return sorted(path for path in folder.iterdir() if path.is_file() and not any(
        path.name.endswith(end) and path.name.removesuffix(end) in current
        for end in ENDINGS))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if a shipped translation is missing or "
                             "differs from a fresh one, or a file is no library's")
    parser.add_argument("--missing", action="store_true",
                        help="translate only the libraries without a shipped file for "
                             "their current key")
    args = parser.parse_args(argv)
    if os.environ.get("PYTHONHASHSEED") != HASH_SEED:  # again, under the fixed seed
        return subprocess.run([sys.executable, str(Path(__file__).resolve()),
                               *(sys.argv[1:] if argv is None else argv)],
                              env={**os.environ, "PYTHONHASHSEED": HASH_SEED},
                              check=False).returncode
    started = time.perf_counter()
    _, refused = command_models()
    for command, reason in refused.items():
        print(f"skipped {command}: the command refuses it ({reason})")
    libraries = shipped_libraries()
    stale = []
    for count, (name, library) in enumerate(libraries.items(), 1):
        shipped = read_shipped(name, library.key)
        if args.missing and shipped is not None:
            print(f"[{count}/{len(libraries)}] {name} ({library.command}): current",
                  flush=True)
            continue
        print(f"[{count}/{len(libraries)}] {name} ({library.command}): translating",
              end="", flush=True)
        began = time.perf_counter()
        fresh = library.translate()
        print(f" {time.perf_counter() - began:.1f} s", end="")
        if args.check:
            same = shipped == fresh
            print(", the same" if same else ", STALE" if shipped else ", NOT SHIPPED")
            if not same:
                stale.append(name)
            continue
        written = write_shipped(name, library.key, *fresh)
        print(", wrote " + ", ".join(f"{path.name} ({path.stat().st_size} bytes)"
                                     for path in written))
    for path in orphans(libraries):
        if args.check:
            print(f"orphan {path.name}: no shipped library's", file=sys.stderr)
            stale.append(path.name)
        else:
            path.unlink()
            print(f"removed {path.name}: no shipped library's")
    print(f"{len(libraries)} libraries in {time.perf_counter() - started:.0f} s")
    if stale:
        print(f"stale shipped C: {', '.join(stale)}; run PYTHONPATH=src python tools/ship_c.py",
              file=sys.stderr)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
