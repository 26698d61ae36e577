"""Content-addressed reuse: what goes into a result's key, and the results kept for reuse.

A stage's key (:func:`roughcontact.store.content_key`) covers the SI values of the scene keys
it reads, its upstream stages' keys and the sha256 of each input file, never a file's path:
moving, copying or renaming a project folder (scene, input files, outputs) leaves every result
fresh. The paths are recorded in the provenance (``input_files``), relative to the scene's
folder where the file lies inside it.

Results whose key has been superseded are not thrown away: before a result file is replaced,
it is kept under its key in the output folder's ``.results/`` (a hard link, so it costs no
copy). A later plan that needs that key again (``--preset fast`` and back, an edit undone)
puts the stored file back in place instead of computing it, and a variant whose stage has the
same key as one already computed in the run (identical inputs) gets that file (linked or
copied) rather than a second computation. The store is bounded (:func:`prune`): the oldest
kept results go first once it outgrows the current results (and :data:`KEEP_BYTES`).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any, Mapping

from . import store
from .errors import UserError

#: folder of kept results inside an output folder
RESULTS = ".results"
#: the kept results may always use this much disk, and as much as the current results do
KEEP_BYTES = 256 * 2**20
#: what a file path becomes in a key (its content hash is part of the key instead)
FILE = "<file: see input_files>"


def key_parameters(value: Any):
    """``value`` (a stage's parameters) with every file path replaced by :data:`FILE`."""
    if isinstance(value, Path):
        return FILE
    if isinstance(value, Mapping):
        return {k: key_parameters(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)) and any(isinstance(v, Path) for v in value):
        return [key_parameters(v) for v in value]
    return value


def shown_path(path: Path, scene_path: Path | None) -> str:
    """How provenance records an input file: relative to the scene's folder if it lies inside it."""
    path = Path(path)
    if scene_path is not None:
        try:
            return path.relative_to(Path(scene_path).resolve().parent).as_posix()
        except ValueError:
            pass
    return str(path)


def input_entry(param: str, path: Path, scene_path: Path | None, key: str | None = None) -> dict:
    """One ``input_files`` record: the scene key, the path as shown, the content hash. An
    unreadable file is the user's error, naming the file and the scene key ``key``."""
    try:
        digest = store.file_sha256(Path(path))
    except OSError as exc:
        raise UserError(f"cannot read: {exc.strerror or exc}", file=str(path), key=key or param) from None
    return {"param": param, "path": shown_path(path, scene_path), "sha256": digest}


def _kept(outdir: Path, key: str) -> Path:
    return Path(outdir) / RESULTS / f"{key}.nc"


def stored(outdir: Path, key: str) -> Path | None:
    """A kept result with ``key`` in the output folder, or None."""
    path = _kept(outdir, key)
    attrs = store.read_attrs(path) if path.is_file() else None
    return path if attrs is not None and attrs.get("stage_key") == key else None


def retire(path: Path, outdir: Path) -> None:
    """Keep the valid result at ``path`` under its key before it is replaced (a hard link; a
    move where the file system has none)."""
    attrs = store.read_attrs(path)
    key = attrs.get("stage_key") if attrs else None
    if not key:
        return
    target = _kept(outdir, key)
    if target.exists():
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f"{store.TMP_PREFIX}{target.name}")
    tmp.unlink(missing_ok=True)
    try:
        os.link(path, tmp)
        os.replace(tmp, target)
    except OSError:
        tmp.unlink(missing_ok=True)
        os.replace(path, target)


def place(source: Path, path: Path, outdir: Path) -> None:
    """Put the identical result ``source`` at ``path``: a kept result is moved there, another
    current result is linked (or copied); whatever was at ``path`` is kept first."""
    source, path = Path(source), Path(path)
    if path.exists() and source.exists() and os.path.samefile(source, path):
        return
    retire(path, outdir)
    path.parent.mkdir(parents=True, exist_ok=True)
    if source.parent == Path(outdir) / RESULTS:
        os.replace(source, path)
        return
    tmp = path.with_name(f"{store.TMP_PREFIX}{path.name}.link")
    tmp.unlink(missing_ok=True)
    try:
        try:
            os.link(source, tmp)
        except OSError:
            shutil.copy2(source, tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def prune(outdir: Path, current: list[Path]) -> None:
    """Bound the kept results: oldest first, until they use at most as much disk as the
    ``current`` result files (and at least :data:`KEEP_BYTES` is allowed)."""
    folder = Path(outdir) / RESULTS
    if not folder.is_dir():
        return
    store.clean_temporaries(folder)
    in_use = {(s.st_dev, s.st_ino) for s in (p.stat() for p in current if p.is_file())}
    kept = [(p, p.stat()) for p in folder.glob("*.nc")]
    kept = [(p, s) for p, s in kept if (s.st_dev, s.st_ino) not in in_use]
    budget = max(KEEP_BYTES, sum(p.stat().st_size for p in current if p.is_file()))
    total = sum(s.st_size for _, s in kept)
    for p, s in sorted(kept, key=lambda item: item[1].st_ctime):
        if total <= budget:
            break
        p.unlink(missing_ok=True)
        total -= s.st_size
