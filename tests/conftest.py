"""Shared fixtures and the test tiers.

Every test gets the marker of its directory (``unit``, ``integration``, ``validation``),
so ``pytest -m unit`` runs the fast tier; markers are strict and warnings are errors
(pyproject.toml), so a test that expects a warning says so.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from pneumact.errors import PassivityWarning
from pneumact.parameters import load_params

TIERS = ("unit", "integration", "validation")


def pytest_collection_modifyitems(config, items):
    for item in items:
        tier = Path(str(item.fspath)).parent.name
        if tier in TIERS:
            item.add_marker(getattr(pytest.mark, tier))


def load_quietly(name: str):
    """A shipped set without its passivity warning: both shipped sets knowingly break the
    LuGre passivity bound (they are the published values); the warning is tested in
    test_parameters.py, not repeated in every test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        return load_params(name)


@pytest.fixture(scope="session")
def vgt():
    """The seed paper's diaphragm actuator (Table I, delta = 1)."""
    return load_quietly("vgt-paper")


@pytest.fixture(scope="session")
def canudas():
    """Canudas de Wit et al. (1995) friction + stick-slip rig."""
    return load_quietly("canudas1995")
