"""What this machine can hold: the memory available to the process and the free space of a
disk, and the one check of a sweep's length made when a scene is read. A leaf module: the
schema and the size estimates (:mod:`roughcontact.sizing`) both use it."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from .errors import UserError

#: bytes per value of the results (float64)
VALUE_BYTES = 8


def available_memory() -> int:
    """Bytes of memory available to this process: MemAvailable, capped by a cgroup limit."""
    avail = None
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            avail = 2**40  # unknown: do not refuse on memory
    for limit_file, usage_file in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                                   ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                                    "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            limit = Path(limit_file).read_text().strip()
            used = int(Path(usage_file).read_text().strip())
        except (OSError, ValueError):
            continue
        if limit.isdigit() and int(limit) < 2**60:
            avail = min(avail, max(int(limit) - used, 0))
        break
    return int(avail)


def free_disk(path: Path) -> int:
    """Free bytes on the file system that holds ``path`` (or its nearest existing folder)."""
    path = Path(path).absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    try:
        return int(shutil.disk_usage(path).free)
    except OSError:
        return 2**62


def human(nbytes: float) -> str:
    """1.5 GB, 340 MB, 12 kB, ... (powers of 1000)."""
    for unit, scale in (("PB", 1e15), ("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{int(nbytes)} B"


def check_sweep_length(num: int, key: str) -> None:
    """Refuse a range whose values alone would take a quarter of the memory available."""
    need = num * VALUE_BYTES
    avail = available_memory()
    if need * 4 > avail:
        raise UserError(f"{num:.3g} values need {human(need)} just to be held, and every result over them far more; "
                        f"this machine has {human(avail)} of memory available: use fewer points", key=key)
