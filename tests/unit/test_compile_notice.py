"""A cold start says so first (issue #42): the first compilation the disk cache cannot
spare is announced once, before it starts ("compiling the model ...")."""

from __future__ import annotations

import numba
import pytest

from pneumact.core import compile_lock


@numba.njit(cache=True)
def _twice(x):
    return 2 * x


def test_the_disk_cache_is_read_right():
    _twice(1.5)  # compiled (or loaded) for float64: in the disk cache now
    float64 = next(s for s in _twice.signatures if str(s[0]) == "float64")
    assert compile_lock._in_disk_cache(_twice, float64)
    assert not compile_lock._in_disk_cache(_twice, (numba.types.complex128,))


def test_a_cold_compilation_is_announced_once_before_it_starts(tmp_path, monkeypatch):
    said = []
    monkeypatch.setattr(compile_lock, "_in_disk_cache", lambda dispatcher, sig: False)
    compile_lock.on_first_compile(lambda: said.append(len(add.signatures)))
    try:
        add = compile_lock.compile_one_process_at_a_time(
            numba.njit(lambda x: x + 1), tmp_path / "lock")
        assert add(1) == 2 and add(1.5) == pytest.approx(2.5)
    finally:
        compile_lock.on_first_compile(None)
    assert said == [0]  # once, before the first compilation was done
