"""Translate the C libraries a fresh install's first ``pneumact simulate`` builds, and ship
them with the package (``src/pneumact/core/shipped_c/``, see ``core.c_shipped``).

The first run of ``pneumact simulate`` (no options) on the C engine builds two libraries:
the default model's run library and the common library of signals and features. Their C
comes from numba's typing of the kernel functions (~7 s of CPU); shipped, the first run
only compiles it. Run this after a change to a kernel's code, the C back end or numba
(``tests/integration/test_shipped_c.py`` fails until then):

    PYTHONPATH=src python tools/ship_c.py            # write the shipped C
    PYTHONPATH=src python tools/ship_c.py --check    # exit 1 if a shipped file is stale
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable

from pneumact.cli.common import ModelOptions, build_model
from pneumact.core import c_common, c_engine
from pneumact.core.c_shipped import read_shipped, write_shipped
from pneumact.errors import PassivityWarning
from pneumact.simulation import assemble


def shipped_libraries() -> dict[str, tuple[str, Callable[[], tuple[str, str]]]]:
    """name -> (translation key, fresh translation) of each library shipped: those the
    first ``pneumact simulate`` with no options builds."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)  # the published sigma1
        _, actuator = build_model(ModelOptions())
    spec = assemble(actuator).kernel_spec()
    return {c_engine.shipped_name(spec, "run"): (c_engine.kernel_translation_key(spec, "run"),
                                                 lambda: c_engine.translate_kernel(spec, "run")),
            c_common.SHIPPED_NAME: (c_common.common_translation_key(),
                                    c_common.translate_common)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if a shipped translation is missing or "
                             "differs from a fresh one")
    args = parser.parse_args(argv)
    stale = []
    for name, (key, translate) in shipped_libraries().items():
        fresh = translate()
        if args.check:
            if read_shipped(name, key) != fresh:
                stale.append(name)
            continue
        for path in write_shipped(name, key, *fresh):
            print(f"wrote {path} ({path.stat().st_size} bytes)")
    if stale:
        print(f"stale shipped C: {', '.join(stale)}; run PYTHONPATH=src python tools/ship_c.py",
              file=sys.stderr)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
