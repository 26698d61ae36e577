"""Tables for engineers: a scene's results as tidy CSV or Excel tables (``roughcontact export``).

One table per stage and variant, from the stored results (computing what is missing or stale,
as ``run`` does): one row per point of the stage's dimensions, one column per coordinate and per
variable, the units in the header row (``p [Pa]``). A stage whose variables span different
dimensions (the contact stage's area over ``p, eta, zeta`` and its stress distribution over
``p, eta, zeta, sigma``, say) gets one table per set of dimensions, named after them; its
dimensionless scalars (0-d variables such as ``E_star``) get a one-row table of their own.

* CSV: ``<stage>.csv`` (or ``<stage>-<dims>.csv``), comment lines (``#``) with the provenance
  first, then the header row, then the rows; numbers are written in Python's shortest round-trip
  form, so reading them back gives the NetCDF values bit for bit.
* xlsx: one workbook per stage, one sheet per table and a ``provenance`` sheet (through pandas and
  openpyxl: ``pip install roughcontact[export]``). openpyxl writes a number with 16 significant
  digits (Excel shows 15), so a value read back from a sheet can differ from the NetCDF one in
  its last bits (relative 5e-16 at most); the CSV tables are the exact ones.

Everything that can be refused (an unknown format or variable, a table folder that is a file, a
table too long for a sheet) is refused before anything is computed or written; each file is
written to a temporary beside it and renamed, so a table is there whole or not at all.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

import numpy as np
import xarray as xr

from . import engine, store
from .errors import UserError
from .schema import did_you_mean

FORMATS = ("csv", "xlsx")
#: rows of one Excel sheet (header row included)
XLSX_ROWS = 1_048_576
#: characters of one Excel cell (longer provenance values are split over several rows)
XLSX_CELL = 32_767
#: the provenance attributes of a result written with each table, in this order
PROVENANCE = ("stage_name", "stage_version", "stage_key", "scene", "scene_variant", "software_version", "git_commit",
              "date_created", "parameters", "upstream_keys", "input_files", "optional_outputs")


@dataclass
class Table:
    """One tidy table: ``columns`` (name -> 1-d values, all of one length) and their units."""

    name: str
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    @property
    def rows(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def header(self) -> list[str]:
        return [f"{n} [{self.units[n]}]" if self.units.get(n) else n for n in self.columns]


def tables(ds: xr.Dataset, stage: str, variables: Iterable[str] | None = None) -> list[Table]:
    """The tidy tables of one result: per set of dimensions, the dimension coordinates as key
    columns (one row per point of their product, the last dimension fastest) and the variables
    and other coordinates over exactly those dimensions; ``variables`` limits the variables."""
    keep = list(ds.data_vars) if variables is None else [v for v in ds.data_vars if v in set(variables)]
    groups: dict[tuple[str, ...], list[str]] = {}
    order = list(ds.dims)
    for name in keep:
        groups.setdefault(tuple(sorted(ds[name].dims, key=order.index)), []).append(name)
    for name, coord in ds.coords.items():  # coordinates that are not dimensions go with variables of their dims
        dims = tuple(sorted(coord.dims, key=order.index))
        if name not in ds.dims and dims in groups:
            groups[dims].append(name)
    out = []
    for dims, names in groups.items():
        suffix = "-".join(dims) if dims else "scalars"
        table = Table(stage if len(groups) == 1 else f"{stage}-{suffix}")
        grids = np.meshgrid(*(_values(ds, d) for d in dims), indexing="ij") if dims else []
        for dim, grid in zip(dims, grids, strict=True):
            table.columns[dim] = grid.ravel()
            table.units[dim] = ds[dim].attrs.get("units", "") if dim in ds.variables else ""
        for name in names:
            values = ds[name].transpose(*dims).values
            table.columns[name] = values.ravel() if values.ndim else values.reshape(1)
            table.units[name] = ds[name].attrs.get("units", "")
        out.append(table)
    return out


def _values(ds: xr.Dataset, dim: str) -> np.ndarray:
    """The values of a dimension's coordinate (0, 1, ... for a dimension without one)."""
    return ds[dim].values if dim in ds.variables else np.arange(ds.sizes[dim])


def provenance(ds: xr.Dataset, source: Path | None) -> list[tuple[str, str]]:
    """(attribute, value) pairs saying where a result came from, ``source`` its NetCDF file."""
    pairs = [("exported_from", str(source))] if source is not None else []
    return pairs + [(k, str(ds.attrs[k])) for k in PROVENANCE if k in ds.attrs]


def _text(value) -> str:
    """A cell of a CSV file: floats in their shortest round-trip form, so the file gives the
    NetCDF numbers back exactly."""
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (np.integer, np.bool_)):
        return str(value.item())
    return str(value)


def write_csv(table: Table, pairs: list[tuple[str, str]], path: Path) -> None:
    def write(fh):
        for key, value in pairs:
            fh.write(f"# {key}: {' '.join(value.splitlines())}\n")
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(table.header())
        columns = list(table.columns.values())
        for i in range(table.rows):
            out.writerow([_text(c[i]) for c in columns])

    def write_text(fh):
        text = io.TextIOWrapper(fh, encoding="utf-8", newline="")
        write(text)
        text.flush()
        text.detach()

    store.write_file(write_text, path, what="table")


def write_xlsx(tables_: list[Table], pairs: list[tuple[str, str]], path: Path) -> None:
    import pandas as pd

    rows = []
    for key, value in pairs:  # a cell holds at most XLSX_CELL characters: long values go on over rows
        pieces = [value[i:i + XLSX_CELL - 1] for i in range(0, len(value), XLSX_CELL - 1)] or [""]
        rows += [(key if i == 0 else f"{key} (continued)", piece) for i, piece in enumerate(pieces)]

    def write(fh):
        with pd.ExcelWriter(fh, engine="openpyxl") as xl:
            for table in tables_:
                frame = pd.DataFrame({h: c for h, c in zip(table.header(), table.columns.values(), strict=True)})
                frame.to_excel(xl, sheet_name=_sheet(table.name), index=False, inf_rep="inf")
            pd.DataFrame(rows, columns=["attribute", "value"]).to_excel(xl, sheet_name="provenance", index=False)

    store.write_file(write, path, what="table")


def _sheet(name: str) -> str:
    """An Excel sheet name (at most 31 characters, none of []:*?/\\)."""
    for ch in "[]:*?/\\":
        name = name.replace(ch, "_")
    return name[:31]


def check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise UserError(f"unknown table format {fmt!r}{did_you_mean(fmt, list(FORMATS))}: use csv or xlsx",
                        key="--format")
    if fmt == "xlsx":
        try:
            import openpyxl  # noqa: F401
            import pandas  # noqa: F401
        except ImportError:
            raise UserError("xlsx tables need pandas and openpyxl: pip install 'roughcontact[export]' "
                            "(or export --format csv)", key="--format") from None


def check_variables(scene, variables: Iterable[str] | None) -> list[str] | None:
    """The asked variables, each one of the scene's results (its stages' outputs, optional ones
    only where the scene asks for them), or a UserError naming the one that is not."""
    if variables is None:
        return None
    variables = list(variables)
    offered: dict[str, str] = {}
    for st in engine.needed_stages(scene, scene.outputs):
        for name, var in st.outputs.items():
            if not var.optional or name in scene.outputs:
                offered.setdefault(name, st.name)
    for name in variables:
        if name not in offered:
            hint = did_you_mean(name, sorted(offered))
            raise UserError(f"{name!r} is not among this scene's results{hint or ''} (they are: "
                            f"{', '.join(sorted(offered))}; add a variable to outputs.variables to compute it)",
                            key="--variables")
    return variables


def check_folder(folder: Path) -> None:
    """The table folder, or a folder on the way to it, must not be a file."""
    for where in (folder, *folder.parents):
        if where.exists() and not where.is_dir():
            raise UserError("exists and is not a folder: the tables go into a folder there "
                            "(give --outdir a folder)", file=str(where))


def export(scene, outdir: Path, fmt: str = "csv", variables: Iterable[str] | None = None,
           report=None, scheduler: str | None = None) -> list[Path]:
    """Write the tables of a scene's results into ``outdir/tables`` (computing what is missing or
    stale first, as ``run`` does) and return the files written. ``variables``: only those (and
    the tables they are in); default every variable of every stage the scene runs."""
    check_format(fmt)
    variables = check_variables(scene, variables)
    folder = Path(outdir) / "tables"
    check_folder(folder)
    results = engine.run(scene, outdir, report=report, scheduler=scheduler)
    written = []
    for variant, by_stage in results.items():
        where = folder if variant == "base" else folder / "variants" / variant
        for stage in by_stage:
            ds = by_stage[stage]
            made = tables(ds, stage, variables)
            if not made:
                continue
            pairs = provenance(ds, by_stage.path(stage))
            where.mkdir(parents=True, exist_ok=True)
            if fmt == "csv":
                for table in made:
                    written.append(where / f"{table.name}.csv")
                    write_csv(table, pairs, written[-1])
                continue
            too_long = [t for t in made if t.rows + 1 > XLSX_ROWS]
            if too_long:
                raise UserError(f"table {too_long[0].name} has {too_long[0].rows} rows, more than an Excel sheet "
                                f"holds ({XLSX_ROWS - 1}): export --format csv, or fewer --variables", key="--format")
            written.append(where / f"{stage}.xlsx")
            write_xlsx(made, pairs, written[-1])
    return written


def read_csv(path: Path) -> tuple[dict[str, str], dict[str, np.ndarray], dict[str, str]]:
    """A table written by :func:`write_csv`: its provenance, its columns (floats where every
    cell is a number) and their units; what the tests read back."""
    meta, lines = {}, []
    with open(path, encoding="utf-8", newline="") as fh:
        for line in fh:
            if line.startswith("# "):
                key, _, value = line[2:].rstrip("\n").partition(": ")
                meta[key] = value
            else:
                lines.append(line)
    rows = list(csv.reader(lines))
    columns, units = {}, {}
    for j, head in enumerate(rows[0]):
        name, _, unit = head.partition(" [")
        units[name] = unit.rstrip("]")
        cells = [r[j] for r in rows[1:]]
        try:
            columns[name] = np.array([float(c) for c in cells])
        except ValueError:
            columns[name] = np.array(cells)
    return meta, columns, units


__all__ = ["FORMATS", "Table", "export", "provenance", "read_csv", "tables", "write_csv", "write_xlsx"]
