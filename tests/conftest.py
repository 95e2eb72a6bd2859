"""Shared fixtures: the shipped parameter sets (loaded once per session)."""

from __future__ import annotations

import warnings

import pytest

from pneumact.errors import PassivityWarning
from pneumact.parameters import load_params


def _load_quietly(name: str):
    # Both shipped sets knowingly break the LuGre passivity bound (they are the published
    # values); the warning is tested in test_parameters.py, not repeated in every test.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        return load_params(name)


@pytest.fixture(scope="session")
def vgt():
    """The seed paper's diaphragm actuator (Table I, delta = 1)."""
    return _load_quietly("vgt-paper")


@pytest.fixture(scope="session")
def canudas():
    """Canudas de Wit et al. (1995) friction + stick-slip rig."""
    return _load_quietly("canudas1995")
