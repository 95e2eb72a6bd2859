"""The pressure's name, said once by the components that own it (issue 41, item 2: no
``"pressure"`` literal outside them).

A record's measured chamber pressure is ``io.records.PRESSURE_SIGNAL``, the actuator's
chamber pressure in a run ``models.actuator.CHAMBER_PRESSURE`` (the template's output and
the valves' state, which keep their literal in their kernel sources so that their kernels'
keys stay), a valve's drive ``models.valves.PRESSURE_INPUT``. They are one name: a record's
pressure drives a pressure source and is compared with the run's.
"""

from __future__ import annotations

import ast
from collections import Counter
from pathlib import Path

import pneumact
from pneumact.core.units import SIGNAL_UNITS
from pneumact.io.records import PRESSURE_SIGNAL
from pneumact.models import VALVES
from pneumact.models.actuator import CHAMBER_PRESSURE
from pneumact.models.actuator_template import OUTPUT_NAMES
from pneumact.models.valves import PRESSURE_INPUT

SOURCE = Path(pneumact.__file__).parent
#: where the literal may stand, and how often: its owners (the valves: their declared
#: input's name, record signal and label, their chamber states, the suffix of their kernel
#: function ``valve_pressure``; the template's output; the two constants), the unit
#: vocabularies keyed by signal name (``core.units``, ``io.units``: a table of names is
#: where names are said), the figures (``plotting`` sits below ``io`` and ``models``, whose
#: constants it cannot import)
ALLOWED = {
    "models/valves.py": 6, "models/actuator_template.py": 1, "models/actuator.py": 1,
    "io/records.py": 1, "core/units.py": 2, "io/units.py": 1, "plotting.py": 3,
}


def pressure_literals(root: Path = SOURCE) -> Counter[str]:
    """How many string constants ``"pressure"`` each module under ``root`` holds (a
    docstring or a longer text that mentions the word is not one)."""
    found: Counter[str] = Counter()
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        n = sum(isinstance(node, ast.Constant) and node.value == "pressure"
                for node in ast.walk(tree))
        if n:
            found[path.relative_to(root).as_posix()] = n
    return found


def test_the_pressure_is_one_name_for_its_owners():
    """The record's pressure, the run's chamber pressure (the template's output, every
    valve's first state where it has states) and the pressure input are one name, in Pa."""
    assert PRESSURE_SIGNAL == CHAMBER_PRESSURE == PRESSURE_INPUT.name
    assert PRESSURE_SIGNAL in PRESSURE_INPUT.record_signals
    assert CHAMBER_PRESSURE in OUTPUT_NAMES
    for cls in VALVES.values():
        if cls.states:
            assert cls.states[0].name == CHAMBER_PRESSURE, cls.__name__
            assert cls.states[0].unit == "Pa"
    assert SIGNAL_UNITS[PRESSURE_SIGNAL] == "Pa"


def test_no_pressure_literal_stands_outside_its_owners():
    """Any other module names the pressure by its owner's constant."""
    assert dict(pressure_literals()) == ALLOWED


def test_the_literal_check_finds_one_and_skips_texts(tmp_path):
    (tmp_path / "a.py").write_text('"""Reads the pressure."""\nX = {"pressure": 1}\n'
                                   'Y = f"the {X} pressure"\n')
    assert pressure_literals(tmp_path) == Counter({"a.py": 1})
