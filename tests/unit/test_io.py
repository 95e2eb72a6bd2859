"""Tests of pneumact.io: tables with units, measured records in SI, atomic writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from pneumact.errors import DataError
from pneumact.io import (
    UNITS_METADATA_KEY,
    Record,
    atomic_write,
    read_record,
    read_records,
    read_signal_csv,
    read_table,
    write_table,
)
from pneumact.io.tables import write_columns
from reference import IO_ROUND_TRIP_RTOL

SHARED = Path(__file__).parents[2].parent / "shared"
TUDELFT = SHARED / "data" / "pneumatic_cylinder_friction_tudelft"


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def frame() -> pd.DataFrame:
    rng = np.random.default_rng(1)
    n = 50
    return pd.DataFrame(
        {
            "time": np.arange(n) * 1e-3,
            "pressure": 1e5 - rng.random(n) * 5e4 / 3.0,
            "position": rng.random(n) * 1.7e-3,
            "command": rng.random(n),
        }
    )


UNITS = {"time": "s", "pressure": "Pa", "position": "m", "command": "1"}


def _siblings(path: Path) -> list[str]:
    return sorted(p.name for p in path.parent.iterdir()) if path.parent.exists() else []


# --------------------------------------------------------------------------- tables


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_table_round_trip_is_exact_and_keeps_units(tmp_path, frame, suffix):
    path = tmp_path / "sub" / f"run{suffix}"
    assert write_table(frame, path, UNITS) == path
    back, units = read_table(path)
    assert units == UNITS
    assert list(back.columns) == list(frame.columns)
    for name in frame.columns:
        np.testing.assert_array_equal(back[name].to_numpy(), frame[name].to_numpy())
    assert _siblings(path) == [path.name]  # no temporary left behind


def test_csv_header_cells_carry_units(tmp_path, frame):
    path = write_table(frame, tmp_path / "run.csv", UNITS)
    header = path.read_text().splitlines()[0]
    assert header == "time [s],pressure [Pa],position [m],command [1]"


def test_parquet_stores_units_in_schema_metadata(tmp_path, frame):
    path = write_table(frame, tmp_path / "run.parquet", UNITS)
    schema = pq.read_schema(path)
    assert schema.names == list(frame.columns)
    assert UNITS_METADATA_KEY in schema.metadata


def test_named_index_is_written_as_a_column(tmp_path, frame):
    path = write_table(frame.set_index("time"), tmp_path / "run.csv", UNITS)
    back, units = read_table(path)
    assert back.columns[0] == "time" and units["time"] == "s"


def test_a_csv_written_without_pandas_is_byte_for_byte_pandas_to_csv(tmp_path):
    """``write_columns`` (a run's CSV, no pandas import) and pandas' ``to_csv`` are two paths
    to one file: special values, 30 decades of magnitude, integers and flags."""
    rng = np.random.default_rng(3)
    n = 500
    columns = {
        "time": np.linspace(0.0, 20.0, n),
        "wide": rng.normal(size=n) * 10.0 ** rng.integers(-30, 30, n),
        "special": np.r_[np.nan, np.inf, -np.inf, -0.0, 1e16, 1e-5, 0.1, rng.random(n - 7)],
        "count": np.arange(n), "flag": np.arange(n) % 3 == 0,
        "single": rng.random(n).astype(np.float32),  # written by pandas itself
    }
    units = {"time": "s", "wide": "Pa"}
    ours = write_columns(columns, tmp_path / "ours.csv", units)
    pd.DataFrame(columns).to_csv(tmp_path / "pandas.csv", index=False, lineterminator="\n",
                                 header=["time [s]", "wide [Pa]", *list(columns)[2:]])
    assert ours.read_bytes() == (tmp_path / "pandas.csv").read_bytes()
    columns.pop("single")
    write_columns(columns, ours, units)
    pd.DataFrame(columns).to_csv(tmp_path / "pandas.csv", index=False, lineterminator="\n",
                                 header=["time [s]", "wide [Pa]", *list(columns)[2:]])
    assert ours.read_bytes() == (tmp_path / "pandas.csv").read_bytes()


def test_unsupported_suffix_is_refused_and_writes_nothing(tmp_path, frame):
    path = tmp_path / "out" / "run.xlsx"
    with pytest.raises(DataError, match=r"'\.xlsx'.*\.csv, \.parquet"):
        write_table(frame, path, UNITS)
    assert not path.exists()
    assert _siblings(path) == []


def test_units_for_a_missing_column_are_refused(tmp_path, frame):
    with pytest.raises(DataError, match="presure"):
        write_table(frame, tmp_path / "run.csv", {"presure": "Pa"})
    assert _siblings(tmp_path / "run.csv") == []


# --------------------------------------------------------------------------- atomic


def test_atomic_write_leaves_nothing_when_the_writer_fails(tmp_path):
    path = tmp_path / "deep" / "result.csv"
    with pytest.raises(RuntimeError, match="disk on fire"), atomic_write(path) as tmp:
        assert tmp.parent == path.parent and tmp.name.startswith(".result.csv.tmp-")
        tmp.write_text("half a fi")
        raise RuntimeError("disk on fire")
    assert not path.exists()
    assert _siblings(path) == []


@pytest.mark.parametrize("writer", ["numbers", "pandas"])
def test_atomic_write_keeps_the_old_file_when_the_writer_fails(tmp_path, frame, writer,
                                                               monkeypatch):
    """Both CSV writers (numbers without pandas; pandas' for a text column) fail after
    opening the file: the previous file stays, nothing else is left."""
    import pneumact.io.tables as tables

    if writer == "pandas":
        frame = frame.assign(note="x")
    units = {k: v for k, v in UNITS.items() if k in frame.columns}
    path = write_table(frame, tmp_path / "run.csv", units)
    before = path.read_bytes()

    class Boom(pd.DataFrame):
        def to_csv(self, *args, **kwargs):
            Path(args[0]).write_text("time [s]\n0.0\n")  # a partial write, then failure
            raise OSError("no space left on device")

    def header_then_failure(cells):
        raise OSError("no space left on device")

    monkeypatch.setattr(tables, "_csv_line", header_then_failure)
    with pytest.raises(OSError, match="no space"):
        write_table(Boom(frame), path, units)
    assert path.read_bytes() == before
    assert _siblings(path) == ["run.csv"]


def test_atomic_write_replaces_on_success(tmp_path):
    path = tmp_path / "x.txt"
    path.write_text("old")
    with atomic_write(path) as tmp:
        tmp.write_text("new")
    assert path.read_text() == "new"
    assert _siblings(path) == ["x.txt"]


# --------------------------------------------------------------------------- records


def test_record_converts_kpa_mm_ms_to_si(tmp_path):
    path = _write(
        tmp_path / "bench.csv",
        "time [ms],pressure [kPa],position (mm),command [%],extra [mbar]\n"
        "0,100,0.5,50,1\n"
        "10,80.5,1.25,60,2\n"
        "20,60,2,70,3\n",
    )
    record = read_record(path)
    assert isinstance(record, Record)
    np.testing.assert_allclose(record.time, [0.0, 0.01, 0.02])
    np.testing.assert_allclose(record["pressure"], [100e3, 80.5e3, 60e3])
    np.testing.assert_allclose(record["position"], [0.5e-3, 1.25e-3, 2e-3])
    np.testing.assert_allclose(record["command"], [0.5, 0.6, 0.7])
    np.testing.assert_allclose(record["extra"], [100.0, 200.0, 300.0])
    assert record.units == {"pressure": "Pa", "position": "m", "command": "1", "extra": "Pa"}
    assert record.source == str(path)
    frame = record.to_pandas()
    assert frame.index.name == "time"
    assert list(frame.columns) == ["pressure", "position", "command", "extra"]
    with pytest.raises(KeyError, match="force"):
        record["force"]


@pytest.mark.parametrize("bar_unit", ["bar", "mbar", "psi", "Pa"])
def test_pressure_units_are_read_as_absolute(tmp_path, bar_unit):
    value = {"bar": 1.0, "mbar": 500.0, "psi": 2.0, "Pa": 5e4}[bar_unit]  # 0.5 to 2 bar
    path = _write(tmp_path / "p.csv",
                  f"time [s],pressure [{bar_unit}]\n0,{value}\n1,{2 * value}\n")
    factor = {"bar": 1e5, "mbar": 100.0, "psi": 6894.757293168361, "Pa": 1.0}[bar_unit]
    np.testing.assert_allclose(read_record(path)["pressure"],
                               [value * factor, 2 * value * factor])


def test_whitespace_file_with_mapping_and_units_argument(tmp_path):
    path = _write(tmp_path / "bench.txt", "Time [ms]  p_act   x\n0  100 1\n5  90  2\n")
    record = read_record(
        path, columns={"pressure": "p_act", "position": "x"}, units={"pressure": "kPa", "x": "mm"}
    )
    np.testing.assert_allclose(record.time, [0.0, 0.005])
    np.testing.assert_allclose(record["pressure"], [1e5, 9e4])
    np.testing.assert_allclose(record["position"], [1e-3, 2e-3])


def test_parquet_record_round_trip(tmp_path, frame):
    in_ms = frame.assign(time=frame["time"] * 1e3)
    path = write_table(in_ms, tmp_path / "r.parquet", {**UNITS, "time": "ms"})
    record = read_record(path)
    np.testing.assert_allclose(record.time, frame["time"].to_numpy(), rtol=IO_ROUND_TRIP_RTOL)
    np.testing.assert_array_equal(record["pressure"], frame["pressure"].to_numpy())


def test_record_arrays_are_read_only(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [m]\n0,1\n1,2\n")
    record = read_record(path)
    with pytest.raises(ValueError, match="read-only"):
        record["position"][0] = 5.0


def test_record_name_drops_only_a_record_files_suffix(tmp_path):
    path = _write(tmp_path / "ramp_0.5mm_s.csv", "time [s],position [m]\n0,1\n1,2\n")
    assert read_record(path).name == "ramp_0.5mm_s"
    synthetic = Record.from_arrays([0.0, 1.0], {"position": [0.0, 1.0]},
                                   source="ramp_0.05mm_s")
    assert synthetic.name == "ramp_0.05mm_s"


# ------------------------------------------------------------------ spreadsheet habits
EXPECTED = {"time": [0.0, 0.5, 1.0], "pressure": [100.5e3, 90.25e3, 80e3],
            "position": [0.0, 1.5e-3, 3e-3]}


def _same(record: Record) -> None:
    np.testing.assert_allclose(record.time, EXPECTED["time"], rtol=IO_ROUND_TRIP_RTOL)
    for name in ("pressure", "position"):
        np.testing.assert_allclose(record[name], EXPECTED[name], rtol=IO_ROUND_TRIP_RTOL)


def test_semicolons_with_decimal_commas_are_read(tmp_path):
    """A German Excel CSV: ';' between cells, ',' as the decimal mark."""
    path = _write(tmp_path / "de.csv", "time [s];pressure [kPa];position [mm]\n"
                  "0;100,5;0\n0,5;90,25;1,5\n1;80;3\n")
    _same(read_record(path))
    table = _write(tmp_path / "table.csv", "Fc [N];Fs [N]\n2,6;3,2\n")
    frame, units = read_table(table)
    assert list(frame.columns) == ["Fc", "Fs"] and frame["Fs"].iloc[0] == pytest.approx(3.2)
    assert units == {"Fc": "N", "Fs": "N"}


def test_gzip_bom_and_trailing_empty_columns_are_read(tmp_path):
    import gzip

    text = "time [s],pressure [kPa],position [mm],,\n0,100.5,0,,\n0.5,90.25,1.5,,\n1,80,3,,\n"
    _same(read_record(_write(tmp_path / "trailing.csv", text)))
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    _same(read_record(bom))
    (tmp_path / "bench").mkdir()
    packed = tmp_path / "bench" / "ramp_1mm_s.csv.gz"
    packed.write_bytes(gzip.compress(text.encode()))
    record = read_record(packed)
    _same(record)
    assert record.name == "ramp_1mm_s"
    assert [r.name for r in read_records(tmp_path / "bench")] == ["ramp_1mm_s"]
    unnamed = _write(tmp_path / "unnamed.csv", "time [s],,position [mm]\n0,5,0\n1,,1\n")
    assert "column 2 has no name in the header but holds data" in _error(unnamed)


def test_excel_is_read_with_openpyxl_or_refused_naming_what_to_do(tmp_path, monkeypatch):
    import sys

    book = tmp_path / "bench.xlsx"
    try:
        import openpyxl
    except ImportError:
        book.write_bytes(b"not a workbook")
        message = _error(book)
        assert "Excel workbook (.xlsx)" in message and "pip install openpyxl" in message
        assert "save the sheet as CSV" in message
        return
    sheet = openpyxl.Workbook()
    rows = [["time [s]", "pressure [kPa]", "position [mm]", None],
            [0, 100.5, 0, None], [0.5, 90.25, 1.5, None], [1, 80, 3, None]]
    for row in rows:
        sheet.active.append(row)
    sheet.save(book)
    _same(read_record(book))
    monkeypatch.setitem(sys.modules, "openpyxl", None)  # as if it were not installed
    assert "pip install openpyxl" in _error(book)


# --------------------------------------------------------------------------- bad input


def _error(path: Path, **kwargs) -> str:
    with pytest.raises(DataError) as info:
        read_record(path, **kwargs)
    message = str(info.value)
    assert str(path) in message
    return message


def test_missing_file(tmp_path):
    assert "not found" in _error(tmp_path / "nope.csv")


def test_missing_required_column_lists_existing(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],p_act [kPa]\n0,1\n1,2\n")
    message = _error(path, required=("time", "pressure"))
    assert "'pressure'" in message and "p_act [kPa]" in message


def test_unknown_unit(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],pressure [kPA]\n0,1\n1,2\n")
    message = _error(path)
    assert "'pressure'" in message and "'kPA'" in message and "unknown unit" in message


def test_gauge_unit_is_refused_with_a_hint(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],pressure [barg]\n0,1\n1,2\n")
    message = _error(path)
    assert "'pressure'" in message and "absolute" in message


def test_wrong_dimension(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [kPa]\n0,1\n1,2\n")
    message = _error(path)
    assert "'position'" in message and "'kPa'" in message and "length" in message


def test_known_column_without_unit(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],pressure\n0,1\n1,2\n")
    assert "'pressure' has no unit" in _error(path)


def test_non_numeric_cell_reports_row(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],pressure [kPa]\n0,1\n1,2\n2,abc\n3,4\n")
    message = _error(path)
    assert "'pressure'" in message and "'abc'" in message and "data row 3" in message


@pytest.mark.parametrize("cell", ["", "NaN", "nan"])
def test_nan_or_empty_cell_reports_first_row_and_count(tmp_path, cell):
    path = _write(tmp_path / "r.csv", f"time [s],position [mm]\n0,1\n1,{cell}\n2,3\n3,{cell}\n")
    message = _error(path)
    assert "'position'" in message and "data row 2" in message and "2 empty" in message


def test_time_not_strictly_increasing(tmp_path):
    path = _write(tmp_path / "r.csv", "time [ms],position [mm]\n0,1\n10,2\n10,3\n5,4\n")
    message = _error(path)
    assert "'time'" in message and "data row 3" in message and "10 ms after 10 ms" in message


def test_too_few_rows(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [mm]\n0,1\n")
    assert "1 data row" in _error(path)


def test_column_mapping_to_absent_column(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [mm]\n0,1\n1,2\n")
    message = _error(path, columns={"pressure": "p_act"})
    assert "'p_act'" in message and "position [mm]" in message


def test_header_and_units_argument_disagree(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [mm]\n0,1\n1,2\n")
    message = _error(path, units={"position": "m"})
    assert "'position'" in message and "'mm'" in message


def test_ragged_row(tmp_path):
    path = _write(tmp_path / "r.csv", "time [s],position [mm]\n0,1\n1,2,3\n")
    assert "malformed" in _error(path)


def test_headerless_file_hints_at_names(tmp_path):
    path = _write(tmp_path / "r.txt", "0 1\n1 2\n")
    assert "names=" in _error(path)


# --------------------------------------------------------------------------- input signal


def test_read_signal_csv(tmp_path):
    path = _write(tmp_path / "in.csv", "time [ms],pressure [kPa]\n0,100\n100,20\n")
    name, time, values = read_signal_csv(path)
    assert name == "pressure"
    np.testing.assert_allclose(time, [0.0, 0.1])
    np.testing.assert_allclose(values, [1e5, 2e4])


@pytest.mark.parametrize(
    ("header", "expected"),
    [("time [s],temp [K]", "no input signal"), ("time [s],pressure [Pa],command", "2 input")],
)
def test_read_signal_csv_needs_exactly_one_signal(tmp_path, header, expected):
    plausible = {"pressure [Pa]": "5e4", "command": "0.5"}  # values the physics allows
    cells = header.split(",")[1:]
    rows = "\n".join(",".join([str(i), *(plausible.get(c, "1") for c in cells)])
                     for i in range(2))
    path = _write(tmp_path / "in.csv", f"{header}\n{rows}\n")
    with pytest.raises(DataError, match=expected):
        read_signal_csv(path)


# --------------------------------------------------------------------------- real data


@pytest.mark.skipif(not TUDELFT.is_dir(), reason="shared TU Delft data set not available")
def test_reads_tudelft_headerless_file():
    names = ["time", "laser", "pressure_v", "force_v", "position", "pressure_gauge", "force"]
    units = {"time": "ms", "laser": "V", "pressure_v": "V", "force_v": "V", "position": "mm",
             "pressure_gauge": "bar", "force": "N"}  # fmt: skip
    record = read_record(TUDELFT / "O-ring_1bar.csv", names=names, units=units,
                         p_atm=101325.0)
    assert len(record.time) > 5000
    assert np.all(np.diff(record.time) > 0)
    assert 50.0 < record.time[-1] < 120.0  # about one to two minutes, in s
    assert -0.01 < record["position"].min() and record["position"].max() < 0.05  # m
    assert 1.5e5 < np.median(record["pressure"]) < 2.5e5  # ~1 bar gauge = ~2 bar absolute
    assert record.units["force"] == "N" and record.units["laser"] == "V"


def test_gauge_column_becomes_absolute_pressure_with_p_atm(tmp_path):
    path = _write(tmp_path / "g.csv", "time [s],pressure_gauge [kPa]\n0,-10\n1,-80\n")
    with pytest.raises(DataError, match="p_atm"):
        read_record(path)
    record = read_record(path, p_atm=101325.0, required=("pressure",))
    np.testing.assert_allclose(record["pressure"], [91325.0, 21325.0])
    assert record.units["pressure"] == "Pa" and "pressure_gauge" not in record


def test_repeated_time_is_named_as_a_duplicate_sample(tmp_path):
    path = _write(tmp_path / "d.csv", "time [s],position [mm]\n0,1\n1,2\n1,2\n")
    assert "repeats" in _error(path)


def test_figures_do_not_pass_on_the_slow_legend_warning_but_others():
    import warnings

    import matplotlib
    import matplotlib.artist
    from matplotlib.figure import Figure

    from pneumact.io.report import figure_png

    matplotlib.use("Agg")

    class Warns(matplotlib.artist.Artist):
        def __init__(self, message):
            super().__init__()
            self.message = message

        def draw(self, renderer):
            warnings.warn(self.message, UserWarning, stacklevel=1)

    fig = Figure()
    fig.add_artist(Warns('Creating legend with loc="best" can be slow with large amounts '
                         'of data.'))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert figure_png(fig).startswith(b"\x89PNG")
    fig = Figure()
    fig.add_artist(Warns("something else"))
    with pytest.warns(UserWarning, match="something else"):
        figure_png(fig)


def test_a_clipped_position_is_a_saturated_sensor_a_stick_at_the_turn_is_not():
    """issue 42, finding 6: held at its top while the pressure goes on past the hold's
    start and comes back: clipped; held from the pressure's turn on: a stick."""
    from pneumact.io.records import Record

    t = np.linspace(0.0, 2.0, 201)
    pressure = 1e5 - 6e4 * (1.0 - np.abs(t - 1.0))  # 100 -> 40 -> 100 kPa
    travel = 0.011 * (1.0 - np.abs(t - 1.0))  # up to 11 mm at the turn
    clipped = Record.from_arrays(t, {"pressure": pressure,
                                     "position": np.minimum(travel, 0.006)}, source="c")
    assert "saturated position sensor" in clipped.saturation()
    stick = np.where(t < 1.0, travel, np.maximum(travel[100] - 0.02 * (t - 1.3), 0.0))
    stick = np.minimum(stick, travel[100])  # held from the turn (t = 1 s) to 1.3 s
    stuck = Record.from_arrays(t, {"pressure": pressure, "position": stick}, source="s")
    assert int(np.sum(stick == stick.max())) >= 30  # a long hold at the top
    assert stuck.saturation() is None


def test_a_hold_on_the_end_stop_is_not_a_saturated_sensor():
    from pneumact.io.records import Record

    t = np.linspace(0.0, 2.0, 201)
    pressure = 1e5 - 6e4 * (1.0 - np.abs(t - 1.0))
    on_stop = np.minimum(0.011 * (1.0 - np.abs(t - 1.0)), 0.006)  # a 6 mm stroke's stop
    record = Record.from_arrays(t, {"pressure": pressure, "position": on_stop}, source="s")
    assert record.saturation() is not None  # without the stroke: looks clipped
    assert record.saturation(x_max=0.006) is None
