"""One process compiles a kernel, the others wait and load it from the disk cache.

numba caches compiled code on disk, but processes that need the same kernel at the same
time (the workers of a Dask cluster or of a parallel test run, notebooks started
together) each compile it, since none finds the cache written yet. Each function of a
kernel therefore compiles under an exclusive lock on a file of its own beside the kernel
module: the first process compiles and writes the cache, the next ones find it there
when they get the lock and load it in a fraction of a second (different functions of one
kernel still compile at once).

The lock is taken inside numba's own compiler lock (one thread of a process compiles at
a time, so a thread never waits on a file another thread of its process holds) and is
re-entrant within the process. Compiling a function compiles the functions it calls,
each under its own lock: a process holds the locks along one path of the call graph,
which has no cycle, so two processes never wait on each other. Without ``fcntl``
(Windows) every process compiles, as before.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["announce_build", "compile_one_process_at_a_time", "file_lock", "on_first_compile"]

#: lock file -> (descriptor, depth) of the locks this process holds
_HELD: dict[Path, tuple[int, int]] = {}
#: called once, before the first compilation this process makes that the disk cache
#: cannot spare it (``on_first_compile``)
_NOTICE: list[Callable[[], None]] = []


def on_first_compile(notice: Callable[[], None] | None) -> None:
    """Call ``notice()`` once, before this process first compiles a kernel function the
    disk cache does not hold (a cold start takes a minute: the command line says so
    first); None removes it."""
    _NOTICE.clear()
    if notice is not None:
        _NOTICE.append(notice)


def announce_build() -> None:
    """Say (once per process, through ``on_first_compile``'s notice) that a build the disk
    cache cannot spare starts now: the C engine's, which does not go through numba."""
    if _NOTICE:
        _NOTICE.pop()()


def _in_disk_cache(dispatcher: Any, sig: Any) -> bool:
    """Whether numba's disk cache holds ``dispatcher`` compiled for ``sig`` (True when
    that cannot be told: no notice rather than a wrong one)."""
    try:
        cache = dispatcher._cache
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:
        return True


def _notice_cold(dispatcher: Any, sig: Any) -> None:
    if _NOTICE and not _in_disk_cache(dispatcher, sig):
        notice = _NOTICE.pop()
        notice()


@contextlib.contextmanager
def _file_lock(path: Path) -> Iterator[None]:
    """Exclusive lock on ``path`` across processes, re-entrant within this one (called
    under numba's compiler lock, so one thread at a time)."""
    if fcntl is None:
        yield
        return
    held = _HELD.get(path)
    if held is None:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(fd, fcntl.LOCK_EX)
        _HELD[path] = (fd, 1)
    else:
        _HELD[path] = (held[0], held[1] + 1)
    try:
        yield
    finally:
        fd, depth = _HELD[path]
        if depth > 1:
            _HELD[path] = (fd, depth - 1)
        else:
            del _HELD[path]
            fcntl.flock(fd, fcntl.LOCK_UN)
            os.close(fd)


def file_lock(path: Path) -> contextlib.AbstractContextManager[None]:
    """An exclusive lock on the file ``path`` across processes (re-entrant within this
    process; its callers hold a lock of their own against other threads)."""
    return _file_lock(path)


def compile_one_process_at_a_time(dispatcher: Any, lock_path: Path | Callable[[], Path]
                                  ) -> Any:
    """``dispatcher`` (a numba ``@njit`` function with ``cache=True``) compiling under
    the lock ``lock_path`` (or the path a callable gives when it first compiles): its
    ``compile`` (which numba calls on a call with new types, and when a function
    calling it compiles) first looks in the disk cache, so a process that waited finds
    what the first one wrote."""
    from numba.core.compiler_lock import global_compiler_lock

    compile_unlocked = dispatcher.compile

    def compile(sig):
        path = lock_path() if callable(lock_path) else lock_path
        with global_compiler_lock, _file_lock(path):
            _notice_cold(dispatcher, sig)
            return compile_unlocked(sig)

    dispatcher.compile = compile
    return dispatcher
