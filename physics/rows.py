"""Kernels that work through the leading axes of their arrays a few rows at a time.

A kernel over (rows..., K) that makes many whole-array temporaries spends its time moving memory:
temporaries of megabytes are mapped fresh from the OS by glibc (above its mmap threshold) and
returned when freed, and none of them stays in a core's cache between the passes over it. Done a
few rows at a time, every temporary stays small, in the L2 cache, and the memory one chunk frees
is the memory the next one uses. Each row is computed as before, so no value changes
(docs/scale-out.md: the friction kernels; the separation kernel).
"""

from __future__ import annotations

import math

import numpy as np

#: elements of one temporary array of a chunk (125 KiB of float64: below glibc's mmap threshold)
CHUNK_ELEMENTS = 16_000


def row_chunks(lead: tuple, per_row: int, chunk_elements: int = CHUNK_ELEMENTS):
    """Index tuples of consecutive rows of the leading shape ``lead`` (each row ``per_row``
    elements of work), about ``chunk_elements`` elements a chunk; ``()`` for no leading axes."""
    if not lead:
        yield ()
        return
    rows = math.prod(lead)
    step = max(1, int(chunk_elements) // max(int(per_row), 1))
    for start in range(0, rows, step):
        yield np.unravel_index(np.arange(start, min(start + step, rows)), lead)
