"""A cache of parsed scenes, so that a rerun of an unchanged scene does not parse it again.

Parsing a scene converts every quantity with pint, whose import and unit registry take most of
a second: more than a rerun with every result fresh does otherwise. The parsed
:class:`~roughcontact.scene.Scene` is kept (pickled) in the user's cache folder
(``$XDG_CACHE_HOME/roughcontact/scenes``, default ``~/.cache/...``; ``ROUGHCONTACT_CACHE=off``
turns the cache off) under a key that covers everything the parse depends on: the scene file's
bytes and absolute path (relative input paths resolve against it), the preset, and the installed
roughcontact (its version and the size and modification time of each of its source files, so that
an edited declaration re-parses); the 200 most recent are kept. A hit whose input files no longer
all exist is ignored (the parse then says which one is missing). Anything unreadable is simply
parsed again.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
from pathlib import Path
from typing import Callable

from .version import __version__

#: parsed scenes kept (the most recent ones)
KEEP = 200


def folder() -> Path | None:
    """Where parsed scenes are kept, or None when the cache is off."""
    if os.environ.get("ROUGHCONTACT_CACHE", "").lower() in ("off", "0", "no"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "roughcontact" / "scenes"


@functools.cache
def code_fingerprint() -> str:
    """The installed package: its version and the size and mtime of every source file."""
    import importlib.util

    roots = {Path(__file__).resolve().parent}
    for sub in ("stages", "physics"):
        spec = importlib.util.find_spec(f"{__package__}.{sub}")
        roots |= {Path(p).resolve() for p in (spec.submodule_search_locations or ())}
    h = hashlib.sha256(__version__.encode())
    for root in sorted(roots):
        for path in sorted(root.rglob("*.py")):
            st = path.stat()
            h.update(f"{path}:{st.st_size}:{st.st_mtime_ns}".encode())
    return h.hexdigest()


def _paths(value):
    if isinstance(value, Path):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from _paths(v)
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _paths(v)


def load(path: Path, text: bytes, preset: str | None, parse: Callable[[], object]):
    """The parsed scene of file ``path`` with contents ``text``: from the cache, else ``parse()``
    (and kept for next time)."""
    where = folder()
    if where is None:
        return parse()
    key = hashlib.sha256(b"\0".join([text, str(Path(path).resolve()).encode(), str(preset).encode(),
                                     code_fingerprint().encode()])).hexdigest()
    entry = where / f"{key}.pickle"
    try:
        scene = pickle.loads(entry.read_bytes())
        scenes = [scene, *scene.variants.values()]
        if all(p.exists() for sc in scenes for p in _paths(sc.values)):
            return scene
    except Exception:  # missing, truncated or from another version: parse again
        pass
    scene = parse()
    try:
        where.mkdir(parents=True, exist_ok=True)
        tmp = entry.with_name(f".tmp-{os.getpid()}-{entry.name}")
        tmp.write_bytes(pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL))
        os.replace(tmp, entry)
        _prune(where)
    except OSError:  # a read-only home: no cache, no harm
        pass
    return scene


def _prune(where: Path, keep: int = KEEP) -> None:
    """Keep the ``keep`` most recently written entries."""
    entries = sorted(where.glob("*.pickle"), key=lambda p: p.stat().st_mtime_ns, reverse=True)
    for old in entries[keep:]:
        old.unlink(missing_ok=True)
