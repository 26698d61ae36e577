"""The results of a run: per variant, a mapping from stage name to its Dataset, each opened from
its file when first asked for.

A run with every result fresh therefore opens no file (the command line asks for none), and a
stage that computes opens only the upstream results it reads.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Iterator, Mapping

import xarray as xr


class StageResults(Mapping[str, xr.Dataset]):
    """``results[stage]`` -> the stage's Dataset, opened on first access (in memory if small, else
    lazily, with the file's chunks); :meth:`path` gives the file."""

    def __init__(self, opener: Callable[[Path], xr.Dataset]):
        self._opener = opener
        self._paths: dict[str, Path] = {}
        self._open: dict[str, xr.Dataset] = {}

    def add(self, stage: str, path: Path) -> None:
        """The result of ``stage`` is (now) the file ``path``."""
        self._paths[stage] = Path(path)
        self._open.pop(stage, None)

    def open_all(self) -> None:
        """Open every result now (small ones into memory, independent of their files)."""
        for stage in self._paths:
            self[stage]

    def path(self, stage: str) -> Path:
        return self._paths[stage]

    def __getitem__(self, stage: str) -> xr.Dataset:
        if stage not in self._open:
            self._open[stage] = self._opener(self._paths[stage])
        return self._open[stage]

    def __iter__(self) -> Iterator[str]:
        return iter(self._paths)

    def __len__(self) -> int:
        return len(self._paths)

    def __repr__(self) -> str:
        return f"StageResults({', '.join(f'{k}: {v}' for k, v in self._paths.items())})"
