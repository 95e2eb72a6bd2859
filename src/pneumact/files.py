"""Files written atomically: every output file of pneumact goes to a temporary file
beside its target and is moved over it only on success, so a failed or interrupted
write never leaves a half-written file (an existing one stays intact).

A base module (it imports nothing of pneumact): ``io`` writes tables and reports through
it, ``plotting`` writes figures.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_write"]

PathLike = str | os.PathLike[str]


@contextlib.contextmanager
def atomic_write(path: PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; move it onto ``path`` only on success.

    The temporary file (``.<name>.tmp-<random>`` in the same directory, so the final
    ``os.replace`` is atomic) is deleted if the block raises, so a failed or interrupted
    write never leaves a half-written file at ``path`` (an existing file stays intact).
    Parent directories are created first.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.tmp-{secrets.token_hex(6)}")
    try:
        yield tmp
        if not tmp.exists():
            raise FileNotFoundError(f"atomic_write: nothing was written to {tmp} for {target}")
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise
