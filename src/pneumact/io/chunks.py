"""The batch engine's store: a directory that makes a batch resumable.

    out_dir/manifest.json                  what the batch is (model, experiment, solver,
                                           table hash, outputs, chunk size)
    out_dir/chunks/chunk-00012.parquet     one finished chunk: row, features, status,
                                           error, steps (its presence marks it done)
    out_dir/chunks/chunk-00012.signals.parquet   its signals, long form (written first)
    out_dir/results.parquet, summary.csv, signals.parquet   the assembled batch

Every file is written atomically. The batch engine builds this folder in a staging
sibling (``pneumact.io.tables.staged_folder``): an interrupted batch is kept there and
resumed from there, and the folder is replaced only by a complete batch. A directory
holding a different batch is never mixed into; one holding the same batch is continued
only when asked to resume.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pneumact.errors import DataError
from pneumact.io.tables import atomic_write, write_table

__all__ = ["ChunkOutput", "ChunkStore"]


def _differences(old: dict, new: dict) -> list[str]:
    return sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))

MANIFEST = "manifest.json"


@dataclass
class ChunkOutput:
    """What one chunk of rows produced (features, status, error, signals, counters)."""

    start: int
    features: np.ndarray  # n × len(feature names)
    status: list[str]
    error: list[str]
    signals: dict[str, np.ndarray]  # name -> n × len(t_out)
    steps: np.ndarray  # n, integrator steps per row

    def __len__(self) -> int:
        return len(self.status)


class ChunkStore:
    """Manifest and chunks of one batch in ``out_dir``."""

    def __init__(self, out_dir: str | Path):
        self.root = Path(out_dir)

    # -- the manifest --------------------------------------------------------------------
    def saved_chunk_size(self) -> int | None:
        """The chunk size recorded by an earlier run in this directory, if any."""
        try:
            return int(json.loads((self.root / MANIFEST).read_text())["chunk_size"])
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def manifest(self) -> dict | None:
        """The manifest of the batch held here, or None."""
        path = self.root / MANIFEST
        if not path.exists():
            return None
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except ValueError as exc:
            raise DataError(f"{path}: is not a readable batch manifest ({exc})") from exc

    def check_previous(self, manifest: dict, resume: bool, overwrite: bool) -> None:
        """Whether the batch already in this folder may be continued (``resume``: the same
        batch only) or replaced (``overwrite``); a different batch is never mixed in."""
        old = self.manifest()
        if old is None or overwrite:
            return
        differs = _differences(old, manifest)
        if differs:
            raise DataError(
                f"{self.root} holds a different batch (its manifest differs in: "
                f"{', '.join(differs)}); use another directory, or overwrite it",
                api_hint="overwrite=True", cli_hint="--overwrite")
        if not resume:
            raise DataError(f"{self.root} already holds this batch",
                            api_hint="resume it (resume=True) or start it again "
                                     "(overwrite=True)",
                            cli_hint="resume it (--resume) or start it again (--overwrite)")

    def open(self, manifest: dict) -> bool:
        """Write the manifest into this (staging) folder, or check the one a kept or
        seeded run left there; True if its finished chunks may be reused."""
        old = self.manifest()
        if old is not None:
            differs = _differences(old, manifest)
            if differs:
                raise DataError(
                    f"{self.root} holds an interrupted run of a different batch (its "
                    f"manifest differs in: {', '.join(differs)})",
                    api_hint="start again with overwrite=True",
                    cli_hint="start again with --overwrite")
            for stale in (self.root / "chunks").glob(".chunk-*.tmp-*"):  # a killed run's
                stale.unlink(missing_ok=True)
            return True
        with atomic_write(self.root / MANIFEST) as tmp:
            tmp.write_text(json.dumps(manifest, indent=1, sort_keys=True), encoding="utf-8")
        return False

    # -- chunks --------------------------------------------------------------------------
    def _chunk_path(self, index: int, signals: bool = False) -> Path:
        return self.root / "chunks" / f"chunk-{index:05d}{'.signals' if signals else ''}.parquet"

    def write_chunk(self, index: int, chunk: ChunkOutput, features: Sequence[str],
                    signals: Sequence[str], t_out: np.ndarray) -> None:
        """Signals first, then the chunk table: the table's presence marks the chunk done."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        n = len(chunk)
        rows = np.arange(chunk.start, chunk.start + n, dtype=np.int64)
        if signals:
            columns = {"row": np.repeat(rows, t_out.size), "time": np.tile(t_out, n)}
            for name in signals:
                columns[name] = chunk.signals[name].reshape(-1)
            with atomic_write(self._chunk_path(index, True)) as tmp:
                pq.write_table(pa.table(columns), tmp)
        columns = {"row": rows}
        for j, name in enumerate(features):
            columns[name] = chunk.features[:, j]
        columns["status"] = pa.array(chunk.status, type=pa.string())
        columns["error"] = pa.array(chunk.error, type=pa.string())
        columns["steps"] = np.asarray(chunk.steps, dtype=np.int64)
        with atomic_write(self._chunk_path(index)) as tmp:
            pq.write_table(pa.table(columns), tmp)

    def read_chunk(self, index: int, start: int, n: int, features: Sequence[str],
                   signals: Sequence[str], n_t: int) -> ChunkOutput | None:
        """A finished chunk, or None if missing or unreadable (then computed again)."""
        import pyarrow.parquet as pq

        path = self._chunk_path(index)
        if not path.exists():
            return None
        try:
            frame = pq.read_table(path).to_pandas()
            if len(frame) != n or int(frame["row"].iloc[0]) != start:
                return None
            feats = (frame[list(features)].to_numpy(dtype=float) if features
                     else np.empty((n, 0)))
            sigs = {}
            if signals:
                sframe = pq.read_table(self._chunk_path(index, True)).to_pandas()
                if len(sframe) != n * n_t:
                    return None
                sigs = {name: sframe[name].to_numpy(dtype=float).reshape(n, n_t)
                        for name in signals}
        except Exception:  # a damaged chunk is simply computed again
            return None
        return ChunkOutput(start, np.ascontiguousarray(feats), frame["status"].tolist(),
                           frame["error"].tolist(), sigs, frame["steps"].to_numpy())

    # -- the assembled batch ------------------------------------------------------------
    def write_final(self, table, units: dict[str, str], signals: dict[str, np.ndarray],
                    time: np.ndarray) -> None:
        """results.parquet and summary.csv (one row per set), signals.parquet if any."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        frame = table.reset_index(drop=True)
        frame.insert(0, "row", np.arange(len(frame), dtype=np.int64))
        units = {k: v for k, v in units.items() if k in frame.columns and v}
        write_table(frame, self.root / "results.parquet", units)
        write_table(frame, self.root / "summary.csv", units)
        if signals:
            n, n_t = len(frame), time.size
            columns = {"row": np.repeat(np.arange(n, dtype=np.int64), n_t),
                       "time": np.tile(time, n)}
            columns.update({name: arr.reshape(-1) for name, arr in signals.items()})
            with atomic_write(self.root / "signals.parquet") as tmp:
                pq.write_table(pa.table(columns), tmp)
