"""Reading and writing files: the edge where users' units become SI and back.

- ``tables``: CSV with ``name [unit]`` headers and Parquet with units in the metadata,
  written atomically (``atomic_write``);
- ``records``: measured bench records, checked and converted to SI (``read_record``);
- ``quantities``: values with units ("60 cm^3") to SI, the one pint registry;
- ``units``: the unit conversion of record columns (pint);
- ``chunks``: the batch engine's resumable chunk store.
"""

from pneumact.io.records import Record, read_record, read_records, read_signal_csv
from pneumact.io.tables import UNITS_METADATA_KEY, atomic_write, read_table, write_table
from pneumact.io.units import KNOWN_SIGNALS

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
