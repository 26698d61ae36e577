"""The one reader of numeric tables (every text input file, and spreadsheets, go through it).

:func:`read_table` reads whitespace-, comma-, semicolon- or tab-separated numeric columns (with
semicolons or tabs, decimal commas too), or a sheet of an Excel file through pandas, with ``#``
comments and an optional header naming the columns and their units, e.g. ``# q [1/m]   C [m^4]``,
``q (1/m), C (m^4)``, or a names row with a units row under it as instruments write them. Every
data row keeps its line number (a spreadsheet's row number), so that a reader can name the
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

    def index(self, name) -> int:
        """The column of ``name`` (an index, or a name of the header, ignoring case and spaces)."""
        if not isinstance(name, str):
            return int(name)
        wanted = name.strip().lower()
        for i, have in enumerate(self.names):
            if have is not None and have.strip().lower() == wanted:
                return i
        where = f"the header (line {self.header_line}) names {[n for n in self.names if n]}" if self.names else \
            "the file has no header naming its columns"
        raise UserError(f"no column named {name!r}: {where}", file=str(self.path),
                        key=f"line {self.header_line}" if self.header_line else None)

    def column(self, index: int) -> np.ndarray:
        if not 0 <= index < self.data.shape[1]:
            raise UserError(
                f"column {index} requested but the file has {self.data.shape[1]} column(s)", file=str(self.path)
            )
        return self.data[:, index]


def _split(line: str) -> list[str]:
    return [t for t in re.split(r"[,;\s]+", line.strip()) if t]


#: file endings read as spreadsheets (pandas.read_excel)
EXCEL = (".xls", ".xlsx", ".xlsm", ".ods")


def _parse_header(text: str) -> tuple[list[str | None], list[str | None]]:
    cells = [c for c in re.split(r",|;|\t|\s{2,}", text.strip()) if c.strip()]
    if len(cells) <= 1:
        # single spaces between "q [1/m] C [m^4]": split before each name followed by a bracket
        cells = re.findall(r"[^\s\[\(]+\s*[\[\(][^\]\)]*[\]\)]|[^\s\[\(]+", text.strip())
    return _names_units(cells)


def _names_units(cells) -> tuple[list[str | None], list[str | None]]:
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


def _text_rows(path: Path):
    """(line number, stripped text, cells or None for a comment) of each non-blank line of a text
    table. A file whose first line holds ';' (or else a tab) is split there, and commas in its cells
    are decimal commas; otherwise cells are split at commas, semicolons and whitespace."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise UserError(f"cannot read: {exc.strerror}", file=str(path)) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise UserError("not a text file (is it binary or in another encoding?)", file=str(path)) from None
    sep = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith(("#", "%", "//")):
            yield number, stripped, None
            continue
        if sep is None:
            sep = ";" if ";" in stripped else "\t" if "\t" in stripped else ""
        if sep:
            cells = [c.strip() for c in stripped.split(sep)]
            while cells and not cells[-1]:
                cells.pop()
        else:
            cells = _split(stripped)
        yield number, stripped, cells


def _excel_rows(path: Path, sheet: str | None):
    """(row number, text, cells) of each non-empty row of a spreadsheet's sheet (the first by default),
    read by pandas (the ``dma`` extra: pandas, openpyxl for .xlsx, xlrd for .xls)."""
    try:
        import pandas as pd
    except ImportError:
        raise UserError("reading spreadsheets needs pandas: pip install 'roughcontact[dma]'", file=str(path)) from None
    try:
        frame = pd.read_excel(path, sheet_name=sheet if sheet is not None else 0, header=None, dtype=object)
    except ImportError as exc:
        raise UserError(f"reading this spreadsheet needs {exc.name or 'an Excel engine'}: pip install "
                        "'roughcontact[dma]'", file=str(path)) from None
    except (ValueError, KeyError) as exc:
        raise UserError(f"cannot read the sheet {sheet or 'first'!s}: {exc}", file=str(path)) from None
    except OSError as exc:
        raise UserError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None
    for index, row in enumerate(frame.itertuples(index=False), start=1):
        cells = ["" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v).strip() for v in row]
        while cells and not cells[-1]:
            cells.pop()
        if cells:
            yield index, " ".join(cells), cells


def _number(cell: str, decimal_comma: bool) -> float:
    if cell == "":
        return float("nan")
    return float(cell.replace(",", ".") if decimal_comma else cell)


def read_table(path: Path, sheet: str | None = None) -> Table:
    """Read a numeric table: text (whitespace, comma, semicolon or tab separated; with ';' or tab,
    decimal commas are read) or a spreadsheet (.xls, .xlsx: ``sheet``, default the first). A header
    names the columns, with units in brackets (``# T [degC]  f [Hz]``) or in a units row right
    under a names row (``f, E', T`` then ``Hz, MPa, C``; ``-`` or an empty cell: no unit). Errors
    name the file and the line (the row of a spreadsheet)."""
    path = Path(path)
    excel = path.suffix.lower() in EXCEL
    rows, lines = [], []
    header: str | None = None
    names_row = units_row = None
    header_line = None
    ncol = None
    source = _excel_rows(path, sheet) if excel else _text_rows(path)
    decimal_comma = False
    for number, stripped, cells in source:
        if cells is None:  # a comment; one with brackets before the data is the header
            body = stripped.lstrip("#%/ ").strip()
            if not rows and body and ("[" in body or "(" in body):
                header, header_line = body, number
            continue
        if not rows and ncol is None and not excel:
            decimal_comma = ";" in stripped or "\t" in stripped
        try:
            values = [_number(c, decimal_comma or excel) for c in cells]
        except ValueError:
            if not rows and header is None and names_row is None:
                names_row, header_line = cells, number
                continue
            if not rows and names_row is not None and units_row is None and len(cells) <= len(names_row):
                units_row, header_line = cells, number
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
    if names_row is not None:
        names, units = _names_units(names_row)
        for i, unit in enumerate((units_row or [])[:len(names)]):
            units[i] = None if unit in ("", "-") else unit
    else:
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
