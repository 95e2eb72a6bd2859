"""What the FMU test modules share: skip without a C compiler, the valves they export."""

from __future__ import annotations

import pytest

import pneumact as pa
from pneumact.errors import ExportError
from pneumact.export import find_compiler


def _compiler() -> str | None:
    try:
        return find_compiler()
    except ExportError:
        return None


#: a module's ``pytestmark``: its FMUs are built with the machine's C compiler
needs_compiler = pytest.mark.skipif(_compiler() is None, reason="no C compiler to build "
                                                               "FMUs with (install gcc or clang)")

VALVES = {"source": pa.PressureSource, "command": pa.CommandValve,
          "regulator": pa.PressureRegulator}
