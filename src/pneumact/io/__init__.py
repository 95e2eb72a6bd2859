"""Reading and writing files: the edge where users' units become SI and back.

- ``tables``: CSV with ``name [unit]`` headers and Parquet with units in the metadata,
  written atomically (``atomic_write``);
- ``records``: measured bench records, checked and converted to SI (``read_record``);
- ``quantities``: values with units ("60 cm^3") to SI, the one pint registry;
- ``units``: the unit conversion of record columns (pint);
- ``chunks``: the batch engine's resumable chunk store;
- ``report``: HTML reports and the vocabulary every result speaks.

Names are imported on first use (PEP 562, as in ``pneumact``): importing one module of
``pneumact.io`` (the report machinery every result class builds on) does not import
pandas.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

#: public name -> module that defines it
_EXPORTS: dict[str, str] = {
    "Record": "pneumact.io.records",
    "read_record": "pneumact.io.records",
    "read_records": "pneumact.io.records",
    "read_signal_csv": "pneumact.io.records",
    "UNITS_METADATA_KEY": "pneumact.io.tables",
    "atomic_write": "pneumact.io.tables",
    "read_table": "pneumact.io.tables",
    "write_table": "pneumact.io.tables",
    "KNOWN_SIGNALS": "pneumact.io.units",
}

__all__ = [
    "KNOWN_SIGNALS",
    "UNITS_METADATA_KEY",
    "Record",
    "atomic_write",
    "read_record",
    "read_records",
    "read_signal_csv",
    "read_table",
    "write_table",
]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'pneumact.io' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs
    from pneumact.io.records import Record, read_record, read_records, read_signal_csv
    from pneumact.io.tables import UNITS_METADATA_KEY, atomic_write, read_table, write_table
    from pneumact.io.units import KNOWN_SIGNALS
