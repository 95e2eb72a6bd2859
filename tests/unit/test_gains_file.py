"""Gains files (issue 42, finding 5): a ``[units]`` table is honoured, and a file that
cannot be what it claims is refused naming the table and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from pneumact.control import load_gains
from pneumact.errors import DataError

HEAD = 'format = "pneumact-gains/1"\n'
BAD_GAINS = Path(__file__).resolve().parents[1] / "data" / "bad" / "gains"


def _file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "gains.toml"
    path.write_text(HEAD + text, encoding="utf-8")
    return path


def test_a_units_table_is_honoured(tmp_path):
    si = load_gains(_file(tmp_path, 'controller = "PID"\n[gains]\nkp = 5e6\nki = 5e7\n'))
    typed = load_gains(_file(tmp_path, 'controller = "PID"\n[gains]\nkp = 5\nki = 50\n'
                                       '[units]\nkp = "kPa/mm"\nki = "kPa/(mm*s)"\n'),
                       command_unit="Pa")
    assert typed.parameters() == pytest.approx(si.parameters(), rel=1e-12)
    assert typed.parameters()["kp"] == pytest.approx(5e6)


@pytest.mark.parametrize(("name", "words"), [
    ("no_gains_table.toml", "no [gains] table"),
    ("cascade_with_pid_gains.toml", "[gains] kp is not a gain of a Cascade"),
    ("unknown_option.toml", "[options] smoothing is not an option of a PID"),
    ("unit_not_a_gain.toml", '[units] kp = "kPa" does not measure kp'),
    ("unknown_unit.toml", '"kilofoo/mm" is not a unit'),
])
def test_a_gains_file_that_cannot_be_read_as_written_is_refused(name, words):
    with pytest.raises(DataError) as refused:
        load_gains(BAD_GAINS / name, command_unit="Pa")
    assert words in str(refused.value) and name in str(refused.value)
