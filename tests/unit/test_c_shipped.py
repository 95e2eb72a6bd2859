"""The shipped C translations (``core.c_shipped``): found by a key over what decides the C.

A shipped file is read only under the key of the code it was translated from: an edit
to a source, another numba, numpy or Python changes the key, and the file is not read
(a fresh translation is made instead). The key names no path, so an installed copy of
the package finds what the repository shipped.
"""

from __future__ import annotations

import importlib.metadata
import shutil

import pytest

from pneumact.core import c_shipped
from pneumact.core.c_shipped import read_shipped, translation_key, write_shipped


@pytest.fixture
def source(tmp_path):
    path = tmp_path / "a" / "kernel_functions.py"
    path.parent.mkdir()
    path.write_text("def rhs(y):\n    return -y\n", encoding="utf-8")
    return path


def test_the_key_follows_the_sources_and_not_their_folder(source, tmp_path):
    key = translation_key("lib run", [source])
    elsewhere = tmp_path / "b" / source.name
    elsewhere.parent.mkdir()
    shutil.copy(source, elsewhere)
    assert translation_key("lib run", [elsewhere]) == key  # an installed copy finds it
    assert translation_key("lib states", [source]) != key
    source.write_text("def rhs(y):\n    return -2.0 * y\n", encoding="utf-8")
    assert translation_key("lib run", [source]) != key


@pytest.mark.parametrize("package", ["numba", "numpy"])
def test_the_key_follows_numba_numpy_and_python(source, monkeypatch, package):
    key = translation_key("lib run", [source])
    real = importlib.metadata.version
    monkeypatch.setattr(importlib.metadata, "version",
                        lambda name: "0.1.0" if name == package else real(name))
    assert translation_key("lib run", [source]) != key
    monkeypatch.undo()
    monkeypatch.setattr(c_shipped.sys, "version_info", (3, 99, 0))
    assert translation_key("lib run", [source]) != key


def test_a_shipped_translation_is_read_under_its_key_only(tmp_path, monkeypatch):
    monkeypatch.setattr(c_shipped, "SHIPPED_DIR", tmp_path)
    old, new = "a" * 64, "b" * 64
    write_shipped("lib-run", old, "int f(void) { return 1; }\n", "int f(void);\n")
    assert read_shipped("lib-run", old) == ("int f(void) { return 1; }\n", "int f(void);\n")
    assert read_shipped("lib-run", new) is None  # the code changed: translated afresh
    written = write_shipped("lib-run", new, "int f(void) { return 2; }\n", "int f(void);\n")
    assert read_shipped("lib-run", old) is None  # the stale one is gone
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in written)


def test_the_same_translation_gives_the_same_bytes(tmp_path):
    """Regenerating unchanged code changes no shipped file (gzip without a time stamp)."""
    first = write_shipped("lib-run", "c" * 64, "double g(double x);\n" * 50, "", tmp_path)
    before = first[0].read_bytes()
    second = write_shipped("lib-run", "c" * 64, "double g(double x);\n" * 50, "", tmp_path)
    assert second[0].read_bytes() == before
