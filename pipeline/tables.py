"""The one reader of numeric text tables (every text input file goes through it).

:func:`read_table` reads whitespace- or comma-separated numeric columns, with ``#`` comments and
an optional header naming the columns and their units, e.g. ``# q [1/m]   C [m^4]`` or
``q (1/m), C (m^4)``. Every data row keeps its line number, so that a reader can name the
offending line (:func:`first_bad`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import UserError

_UNIT_IN_HEADER = re.compile(r"^\s*([^\[\(]*?)\s*[\[\(]\s*([^\]\)]*)\s*[\]\)]\s*$")


@dataclass
class Table:
    """Numeric columns read from a text file.

    Attributes
    ----------
    path
        The file.
    data
        (rows, columns) float array.
    lines
        1-based line number in the file of each data row.
    names, units
        Column names and units from the header (None where the header gives none).
    header_line
        1-based line number of the header (None without one).
    """

    path: Path
    data: np.ndarray
    lines: np.ndarray
    names: list[str | None] = field(default_factory=list)
    units: list[str | None] = field(default_factory=list)
    header_line: int | None = None
    #: why a header line was not used (it names another number of columns than the rows hold), or None
    header_note: str | None = None

    def column(self, index: int) -> np.ndarray:
        if not 0 <= index < self.data.shape[1]:
            raise UserError(
                f"column {index} requested but the file has {self.data.shape[1]} column(s)", file=str(self.path)
            )
        return self.data[:, index]


def _split(line: str) -> list[str]:
    return [t for t in re.split(r"[,;\s]+", line.strip()) if t]


def _parse_header(text: str) -> tuple[list[str | None], list[str | None]]:
    cells = [c for c in re.split(r",|;|\t|\s{2,}", text.strip()) if c.strip()]
    if len(cells) <= 1:
        # single spaces between "q [1/m] C [m^4]": split before each name followed by a bracket
        cells = re.findall(r"[^\s\[\(]+\s*[\[\(][^\]\)]*[\]\)]|[^\s\[\(]+", text.strip())
    names, units = [], []
    for c in cells:
        m = _UNIT_IN_HEADER.match(c)
        if m:
            names.append(m.group(1) or None)
            units.append(m.group(2).strip() or None)
        else:
            names.append(c.strip() or None)
            units.append(None)
    return names, units


def read_table(path: Path) -> Table:
    """Read a numeric text table. Errors name the file and the line."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise UserError(f"cannot read: {exc.strerror}", file=str(path)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise UserError("not a text file (is it binary or in another encoding?)", file=str(path)) from None
    rows, lines = [], []
    header: str | None = None
    header_line = None
    ncol = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith(("#", "%", "//")):
            body = stripped.lstrip("#%/ ").strip()
            if not rows and body and ("[" in body or "(" in body):
                header, header_line = body, number
            continue
        cells = _split(stripped)
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not rows and header is None:
                header, header_line = stripped, number
                continue
            raise UserError(f"not a number in {stripped[:60]!r}", file=str(path), key=f"line {number}") from None
        if ncol is None:
            ncol = len(values)
        elif len(values) != ncol:
            raise UserError(
                f"{len(values)} column(s) where earlier rows have {ncol}", file=str(path), key=f"line {number}"
            )
        rows.append(values)
        lines.append(number)
    if not rows:
        raise UserError("no data rows", file=str(path))
    names, units = _parse_header(header) if header else ([], [])
    note = None
    if names and len(names) != ncol:  # a header we cannot align with the columns names nothing
        note = f"the header (line {header_line}) names {len(names)} column(s) but the rows hold {ncol}"
        names, units, header_line = [], [], None
    return Table(path=path, data=np.array(rows, dtype=float), lines=np.array(lines), names=names, units=units,
                 header_line=header_line, header_note=note)


def first_bad(bad: np.ndarray, message, path: Path, where) -> None:
    """Raise a UserError naming the file and the row (``where(i)``) of the first True in ``bad``;
    ``message(i)`` says what is wrong there."""
    index = np.flatnonzero(bad)
    if index.size:
        raise UserError(message(index[0]), file=str(path), key=where(index[0]))
