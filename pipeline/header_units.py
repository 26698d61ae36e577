"""The length units of a measured surface file: the file's own, a text file's column header, or
the scene's ``height_unit`` (in that order).

Text line scans and xyz files often say their units only in a header line such as
``# x [um]  h [um]`` or ``x (mm), z (nm)``, which SurfaceTopography does not read: here the header
is read with the one table reader (:func:`roughcontact.tables.read_table`) so that such a file
needs no ``height_unit``. The last column is the height; the first the lateral position.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import UserError
from .tables import read_table
from .units import array_to_si

#: suffixes of files that may be text tables with a header
TEXT_SUFFIXES = (".txt", ".csv", ".dat", ".asc", ".xyz", ".tsv", "")


def header_units(path: Path) -> tuple[str | None, str | None]:
    """(lateral unit, height unit) from a text file's column header; (None, None) when the file
    is not a text table or its header gives no units."""
    if Path(path).suffix.lower() not in TEXT_SUFFIXES:
        return None, None
    try:
        table = read_table(Path(path))
    except UserError:
        return None, None
    units = table.units or []
    if len(units) < 2 or units[-1] is None:
        return None, None
    return (units[0] or units[-1]), units[-1]


def length_units(path: Path, file_unit: str | None, height_unit: str | None, key: str) -> tuple[str, str, float, float]:
    """(unit of the heights, where it comes from, factor to metres of the heights, of the sizes).

    The file's own unit applies to heights and sizes; a header's to its columns (lateral: the
    first, heights: the last); the scene's ``key.height_unit`` to both. Errors name the key."""
    def to_m(unit: str, where: str) -> float:
        return float(array_to_si(np.array(1.0), unit, "m", key=where))

    if file_unit is not None:
        factor = to_m(file_unit, f"unit {file_unit!r} in the file")
        return file_unit, "file", factor, factor
    lateral, height = header_units(path)
    if height is not None:
        where = f"the column header of {Path(path).name}"
        return height, "header", to_m(height, where), to_m(lateral, where)
    if height_unit is None:
        raise UserError("the file does not say the unit of its heights (no unit in the file, no header like "
                        f"'# x [um]  h [nm]'); set {key}.height_unit (e.g. \"nm\")", file=str(path),
                        key=f"{key}.height_unit")
    factor = to_m(height_unit, f"{key}.height_unit")
    return height_unit, "scene", factor, factor
