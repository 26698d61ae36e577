"""How a stage declares itself to the engine, and what it is handed when it runs.

A stage is a pure function ``compute(StageInput) -> xarray.Dataset`` plus declarations:
its name and version, the upstream stages it needs, the scene keys it reads, the files it
needs read, and its output variables with units and long names. The engine does planning,
hashing, caching, I/O, chunking and scheduling; a stage does none of these.

This module is the whole API a stage module uses (with :mod:`roughcontact.physics` for the
numbers): :class:`Stage`, :class:`Var`, :class:`FileInput`, :class:`Figure`,
:class:`StageInput`, :class:`Shape`, :class:`ByKind`, :class:`Upstream`, :class:`Param`,
:class:`Section`, :func:`register`, :func:`register_section`, :func:`register_params`,
:func:`register_coords`, the errors (and
:class:`SceneWarning`) and :func:`readable` (a quantity in SI units as a short string, for
messages and figures).

Metadata has one source. A variable's units and long name are written once, in its
:class:`Var` (a stage's ``outputs`` or ``coords``, or a coordinate shared by several stages
through :func:`register_coords`); the engine stamps them on the result and rejects a result
whose stage set ``units`` or ``long_name`` itself.

Register a stage with :func:`register` at import time of its module in
:mod:`roughcontact.stages`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np
import xarray as xr

from .errors import ComputationError, SceneWarning, UserError
from .schema import MISSING, REQUIRED, Param, Section
from .units import readable

__all__ = [
    "ByKind", "ComputationError", "FileInput", "Figure", "MISSING", "Param", "REQUIRED", "SceneWarning", "Section",
    "SectionKeys", "Shape", "Stage", "StageInput", "UserError", "Var", "coords", "readable", "register",
    "register_coords", "register_params", "register_section", "Upstream",
]


@dataclass(frozen=True)
class Var:
    """An output variable (or coordinate) of a stage: its units and long name, written here only.

    ``optional`` variables are produced only when the scene asks for them by name;
    ``standard_name`` is the CF standard name where CF has one; ``comment`` the CF comment (what
    the value is, its equation, where it is NaN); ``attrs`` are further fixed attributes, all
    stamped with the units. A ``tolerance`` makes the variable
    one that ``roughcontact accuracy`` measures: the error (relative to the variable's scale,
    docs/accuracy.md) the default preset must reach.
    """

    units: str
    long_name: str
    optional: bool = False
    standard_name: str | None = None
    attrs: Mapping[str, str] = field(default_factory=dict)
    tolerance: float | None = field(default=None, compare=False)
    comment: str | None = None

    def stamp(self) -> dict[str, str]:
        """The attributes the engine writes on the variable (the tolerance is the accuracy's)."""
        out = {"units": self.units, "long_name": self.long_name, **self.attrs}
        if self.comment:
            out["comment"] = self.comment
        if self.standard_name:
            out["standard_name"] = self.standard_name
        return out


@dataclass(frozen=True)
class FileInput:
    """A file the engine must read for the stage.

    ``param`` is the dotted scene key holding the path (e.g. ``substrate.path``); ``reader``
    names a reader of :data:`roughcontact.readers.READERS` (``"table"``, ``"netcdf"``,
    ``"auto"``, ``"topography"``, ...). ``options(params) -> dict`` gives the reader's keyword
    arguments from the stage's parameters (e.g. the column units the scene sets), so that the
    reader hands the stage arrays in SI units.
    """

    param: str
    reader: str = "auto"
    options: Callable[[Mapping[str, Any]], Mapping[str, Any]] | None = None


@dataclass(frozen=True)
class Figure:
    """A figure a stage can draw from stored results.

    ``make(results) -> matplotlib.figure.Figure`` where ``results[variant][stage]`` is a
    Dataset (``variant`` is ``"base"`` or a name from the scene's ``[variants]``); it returns
    None when the scene has nothing for it to draw (no blank figures).
    ``stages`` are the stages it needs; the engine makes sure they are up to date.
    """

    name: str
    title: str
    stages: tuple[str, ...]
    make: Callable[[Mapping[str, Mapping[str, xr.Dataset]]], Any]
    variants: tuple[str, ...] = ()
    #: optional outputs the figure needs; it is not drawn (and not announced) when the scene does not ask for them
    outputs: tuple[str, ...] = ()


@dataclass(frozen=True)
class ByKind:
    """Of a scene section whose tables have a ``kind`` (``[substrate]``, ``[solid]``), the keys a
    stage reads for each kind: ``ByKind("substrate", {"topography": ("files", ...), "*": ()})``
    ("*": every kind not listed; a kind in neither: every key). The stage is handed, and its
    content key covers, only these keys and ``kind``: the topography stage reads a measured
    surface's map keys, not its ``extend``, which only the psd stage reads."""

    section: str
    keys: Mapping[str, tuple[str, ...]]


@dataclass(frozen=True)
class Upstream:
    """An upstream stage a stage needs only when the scene says so, as data: when the scene value
    of any key in ``when`` is (or, for a list such as ``outputs.variables``, contains) one of the
    listed values. ``Upstream("topography", when={"substrate.kind": ("topography", "container"),
    "solid.kind": ("topography", "container")})``: only for measured surfaces."""

    stage: str
    when: Mapping[str, tuple] = field(default_factory=dict)

    def applies(self, values: Mapping[str, Any]) -> bool:
        """Whether the scene (its section values) needs this upstream stage."""
        for dotted, wanted in self.when.items():
            value: Any = values
            for part in dotted.split("."):
                value = value.get(part) if isinstance(value, Mapping) else None
            found = value if isinstance(value, (list, tuple)) else (value,)
            if any(isinstance(v, str) and v in wanted for v in found):
                return True
        return False


@dataclass(frozen=True)
class Stage:
    """Declaration of one stage of the pipeline: what it reads, what it needs, what it writes, and
    at most three functions.

    ``compute(inp) -> Dataset`` computes the result (bare arrays: the engine stamps every
    variable with its :class:`Var`). ``describe(inp) -> Shape`` says, before anything computes,
    the dimensions the stage adds, their sizes and (small) coordinate values, from the scene and
    the upstream results' shapes (``inp.upstream[name]`` is a :class:`Shape` there); the preflight
    sizes results and memory with it, downstream stages check against it, ``compute`` reads it as
    ``inp.shape`` and the engine refuses a computed result that differs from it, so the two cannot
    drift; it raises :class:`UserError` where the scene does not fit the upstream shapes (a
    magnification beyond the q grid). ``check(inp)`` raises :class:`UserError` for rules between
    the stage's keys and files that the schema's bounds and types cannot express (``inp.upstream``
    is empty there); the engine runs every stage's check first, then the describes, upstream
    first, all before anything is computed or written.
    """

    name: str
    version: str
    compute: Callable[["StageInput"], xr.Dataset]
    outputs: Mapping[str, Var]
    coords: Mapping[str, Var] = field(default_factory=dict)
    #: the scene keys it reads: dotted keys (``"load.p"``), whole sections (``"substrate"``), or
    #: :class:`ByKind` selections of a section with kinds
    reads: tuple[str | ByKind, ...] = ()
    #: the upstream stages it needs: names, or :class:`Upstream` for one needed only by some scenes
    needs: tuple[str | Upstream, ...] = ()
    files: tuple[FileInput, ...] = ()
    figures: tuple[Figure, ...] = ()
    describe: Callable[["StageInput"], "Shape"] | None = None
    check: Callable[["StageInput"], None] | None = None
    doc: str = ""

    @property
    def keys(self) -> tuple[str, ...]:
        """The scene keys (dotted, or whole sections) the stage reads."""
        return tuple(r.section if isinstance(r, ByKind) else r for r in self.reads)

    @property
    def requires(self) -> tuple[str, ...]:
        """Every upstream stage it may need."""
        return tuple(u.stage if isinstance(u, Upstream) else u for u in self.needs)

    def upstream_for(self, values: Mapping[str, Any]) -> tuple[str, ...]:
        """The upstream stages a scene (its section values) needs."""
        return tuple(u if isinstance(u, str) else u.stage for u in self.needs
                     if isinstance(u, str) or u.applies(values))

    @property
    def measured(self) -> dict[str, float]:
        """The outputs whose error ``roughcontact accuracy`` measures, with their tolerance."""
        return {name: var.tolerance for name, var in self.outputs.items() if var.tolerance is not None}

    def section_view(self, name: str, value):
        """What the stage is handed of the scene value ``value`` of its declared key ``name``:
        the value itself, or, for a :class:`ByKind` section, a :class:`SectionKeys` of the keys
        the stage reads."""
        by_kind = next((r.keys for r in self.reads if isinstance(r, ByKind) and r.section == name), None)
        if by_kind is None or not isinstance(value, Mapping):
            return value
        keys = by_kind.get(value.get("kind"), by_kind.get("*"))
        if keys is None:
            return value
        return SectionKeys({k: v for k, v in value.items() if k == "kind" or k in keys},
                           hidden=frozenset(value) - set(keys) - {"kind"}, where=f"stage {self.name}, [{name}]")


class SectionKeys(dict):
    """The keys of a scene section a stage declared it reads (:attr:`Stage.reads`); reading one
    it did not declare is an error (a bug in the stage), so a stage's key covers what it reads."""

    def __init__(self, values, hidden=frozenset(), where=""):
        super().__init__(values)
        self.hidden, self.where = hidden, where

    def _refuse(self, key):
        raise KeyError(f"{self.where} reads key {key!r} that it does not declare in its reads (a bug in the stage)")

    def __missing__(self, key):
        if key in self.hidden:
            self._refuse(key)
        raise KeyError(key)

    def get(self, key, default=None):
        if key in self.hidden:
            self._refuse(key)
        return super().get(key, default)

    def __reduce__(self):  # picklable for process and distributed schedulers
        return (SectionKeys, (dict(self), self.hidden, self.where))


@dataclass(frozen=True)
class Shape:
    """What a stage's result looks like, known before it computes (no data): the one description
    of it that the preflight, the downstream stages' checks, the size estimates and the stage's
    own ``compute`` (as ``inp.shape``) share; the engine refuses a computed result that differs.

    A stage's ``describe`` returns the dimensions it adds itself (the scene's sweep dimensions it
    spans are added by the engine); a stored result's shape is :meth:`of` its file.
    """

    #: dimension -> length
    sizes: Mapping[str, int] = field(default_factory=dict)
    #: coordinate or small 1-D variable -> (lowest, highest finite value)
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    #: the data variables it will hold (of a stored result)
    variables: frozenset = frozenset()
    #: global attributes known in advance (``attrs["note"]``: a line ``plan`` and ``run`` print)
    attrs: Mapping[str, Any] = field(default_factory=dict)
    #: the scene key that sets the size of each dimension the stage adds (e.g. {"q":
    #: "numerics.points_per_decade"}), named when a result would be too large for the machine
    keys: Mapping[str, str] = field(default_factory=dict)
    #: the values of (small) 1-D coordinates, where known in advance (e.g. the magnifications)
    coords: Mapping[str, np.ndarray] = field(default_factory=dict)
    #: finite values of (small) 1-D data variables known in advance (e.g. measured bins' mean q)
    values: Mapping[str, np.ndarray] = field(default_factory=dict)
    #: the sizes of the largest arrays one point of the scene's sweep holds while it computes, as
    #: factors (e.g. {"temporaries": 6, "quadrature_node": 4000}): working memory per sweep point
    #: = 8 bytes times their product (empty: a few temporaries of every output value)
    work: Mapping[str, int] = field(default_factory=dict)
    #: sweep dimensions the computation couples (e.g. a derivative along ``p``): never chunked
    coupled: tuple[str, ...] = ()
    #: dimensions whose length depends on the data (an adaptive grid): ``sizes`` holds an estimate,
    #: used for the size checks; the engine holds the computed result to every other size
    approximate: tuple[str, ...] = ()
    #: output variable -> the dimensions it does not span (of the sweep's and the stage's own;
    #: default: every output spans every dimension), for the size of the stored result; a
    #: coordinate over more than its own dimension (a stress grid per point) counts when named here
    #: (with the dimensions it does not span, if any)
    lacks: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    #: each block is long work (a BEM solve): the engine keeps every finished block in the output
    #: folder, under the result's content key, until the result is written, so that a run that is
    #: killed resumes where it stopped (docs/reliability.md)
    keep_blocks: bool = False
    #: sweep dimensions along which a block's work grows with the coordinate's value (e.g. a BEM
    #: map's pixels per wavelength): the engine computes the blocks with the largest product of
    #: these values first, so that on several workers the long ones do not come last and leave the
    #: others idle (longest first); the result is the same in any order
    costlier_with: tuple[str, ...] = ()

    @classmethod
    def of(cls, ds: xr.Dataset, small: int = 10**6, values_up_to: int = 10**4) -> "Shape":
        """The shape of a stored (or computed) result (its coordinates and small 1-D variables are read)."""
        ranges, coords, data = {}, {}, {}
        for name, var in ds.variables.items():
            if var.ndim == 1 and var.size <= small and var.dtype.kind in "fiu":
                values = np.asarray(var.values, dtype=float)
                finite = values[np.isfinite(values)]
                if finite.size:
                    ranges[str(name)] = (float(finite.min()), float(finite.max()))
                if name in ds.coords and var.dims == (name,):
                    coords[str(name)] = values
                elif name in ds.data_vars and var.size <= values_up_to:
                    data[str(name)] = finite
        return cls(sizes={str(k): int(v) for k, v in ds.sizes.items()}, ranges=ranges,
                   variables=frozenset(str(v) for v in ds.data_vars), attrs=dict(ds.attrs), coords=coords,
                   values=data)


#: largest dask-backed intermediate :meth:`StageInput.shared` computes at once (bytes)
SHARED_BYTES = 64 * 2**20


@dataclass
class StageInput:
    """What the engine hands a stage's ``compute``.

    Attributes
    ----------
    params
        The values of the declared scene keys, in SI, keyed by dotted path.
    upstream
        Results of the upstream stages, keyed by stage name.
    files
        Loaded input files keyed by the scene key of their path (see :class:`FileInput`).
    wanted
        Names of the optional output variables the scene asked for.
    chunks
        Dask chunk sizes per sweep dimension (from the scene's numerics); 0 or absent: unchunked.
    shape
        In ``compute``: the :class:`Shape` the stage's ``describe`` gave (with the sweep
        dimensions it spans), e.g. the q grid or the magnifications; in ``describe``,
        ``upstream`` holds the upstream results' shapes instead of Datasets (in ``check``, none).
    """

    params: Mapping[str, Any]
    upstream: Mapping[str, xr.Dataset] = field(default_factory=dict)
    files: Mapping[str, Any] = field(default_factory=dict)
    wanted: frozenset[str] = frozenset()
    chunks: Mapping[str, int] = field(default_factory=dict)
    stage: str = "?"
    shape: "Shape | None" = None
    #: the engine's :class:`roughcontact.progress.Reporter` (None: no progress shown)
    reporter: Any = None

    def progress(self, what: str, total: int | None = None, unit: str = "step") -> Callable[..., None]:
        """A callable ``tick(n=1)`` advancing a progress bar of ``what`` (on a terminal; a no-op
        elsewhere and in worker processes): hand it to a long kernel as its ``progress``."""
        from .progress import Tick

        return Tick() if self.reporter is None else self.reporter.bar(f"{self.stage}: {what}", total, unit)

    def __getitem__(self, key: str):
        try:
            return self.params[key]
        except KeyError:
            raise KeyError(f"stage {self.stage} reads scene key {key!r} that it does not declare in its params "
                           f"(a bug in the stage)") from None

    def shared(self, value: xr.DataArray) -> xr.DataArray:
        """``value`` computed now if it is dask-backed and at most :data:`SHARED_BYTES` (in the
        same chunks, now slices of the values in memory), else as it is: a small intermediate that
        every block of a larger result needs (G for every block of pressures). The engine computes
        a result's blocks a few at a time, and a lazy intermediate would be computed again for
        every few (the large sweep's G 512 times, 2.7 of its 4.5 s). Values are the same either way.

        The one computation a stage may start while it builds its graph (docs/scale-out.md): on
        this process's threads, whatever scheduler computes the blocks."""
        if value.chunks is None or value.nbytes > SHARED_BYTES:
            return value
        return value.compute(scheduler="threads").chunk(value.chunksizes)

    def sweep(self, dim: str, values) -> xr.DataArray:
        """A sweep coordinate as a DataArray: a 1-D array becomes dimension ``dim`` (dask-chunked
        when the scene sets a chunk size for it); a scalar stays a scalar coordinate. Units and
        long name come from the coordinate's declaration."""
        values = np.asarray(values, dtype=float)
        if values.ndim == 0:
            return xr.DataArray(values, name=dim)
        da = xr.DataArray(values, dims=(dim,), coords={dim: (dim, values)}, name=dim)
        size = int(self.chunks.get(dim, 0) or 0)
        if 0 < size < values.size:
            da = da.chunk({dim: size})
        return da


_STAGES: dict[str, Stage] = {}
_SECTIONS: dict[str, Section] = {}
_COORDS: dict[str, Var] = {}
_LOADED = False  # True once every built-in stage module is imported and the declarations checked


def register_coords(**declared: Var) -> None:
    """Declare coordinates shared by several stages (``p``, ``eta``, ``zeta``, ``q``, ...) once.

    A stage's own ``coords`` may not redeclare them."""
    for name, var in declared.items():
        if name in _COORDS and _COORDS[name] != var:
            raise ValueError(f"coordinate {name!r} declared twice")
        _COORDS[name] = var


def coords() -> dict[str, Var]:
    """The shared coordinates declared by :func:`register_coords`."""
    _load_plugins()
    return dict(_COORDS)


def register(stage: Stage) -> Stage:
    """Add a stage to the registry (at import of its module). Names are unique.

    A stage registered after the registry has loaded (a user's own stage) is checked at once;
    the built-in ones are checked together when the registry loads."""
    if stage.name in _STAGES and _STAGES[stage.name] is not stage:
        raise ValueError(f"stage {stage.name!r} registered twice")
    if _LOADED:
        check_declarations({**_STAGES, stage.name: stage}, _SECTIONS, _COORDS)
    _STAGES[stage.name] = stage
    return stage


def register_section(section: Section) -> Section:
    """Add a scene section to the schema. Names are unique."""
    if section.name in _SECTIONS and _SECTIONS[section.name] is not section:
        raise ValueError(f"scene section {section.name!r} registered twice")
    _SECTIONS[section.name] = section
    return section


def register_params(section_name: str, *params: Param, doc: str = "") -> None:
    """Add parameters to a shared section (e.g. ``numerics``), creating it if needed.

    Several stages put their resolution settings in ``[numerics]``; names must not clash.
    """
    import dataclasses

    current = _SECTIONS.get(section_name, Section(section_name, doc=doc))
    names = {p.name for p in current.params}
    for p in params:
        if p.name in names:
            if any(q == p for q in current.params):
                continue
            raise ValueError(f"parameter {section_name}.{p.name} registered twice")
        names.add(p.name)
    new = tuple(p for p in params if p not in current.params)
    _SECTIONS[section_name] = dataclasses.replace(current, params=current.params + new, doc=current.doc or doc)


def stages() -> dict[str, Stage]:
    _load_plugins()
    return dict(_STAGES)


def sections() -> dict[str, Section]:
    _load_plugins()
    return dict(_SECTIONS)


def producer_of(variable: str) -> Stage:
    """The stage that outputs ``variable`` (or is named ``variable``)."""
    all_stages = stages()
    if variable in all_stages:
        return all_stages[variable]
    candidates = [st for st in all_stages.values() if variable in st.outputs]
    if candidates:  # a variable several stages output (E_star, say): the cheapest, nearest the inputs
        return min(candidates, key=lambda st: (len(_upstream_closure(st, all_stages)), st.name))
    known = sorted(set(all_stages) | {v for s in all_stages.values() for v in s.outputs})
    from .schema import did_you_mean

    raise UserError(f"no stage produces {variable!r}{did_you_mean(variable, known)}", key="outputs.variables")


def _upstream_closure(st: Stage, all_stages: dict[str, Stage]) -> set[str]:
    seen: set[str] = set()
    todo = list(st.requires)
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo.extend(all_stages[name].requires)
    return seen


def _load_plugins() -> None:
    """Import every module of :mod:`roughcontact.stages` so that it registers itself, then
    check the declarations against each other (once)."""
    global _LOADED
    if _LOADED:
        return
    import importlib
    import pkgutil

    pkg = importlib.import_module(f"{__package__}.stages")
    for mod in pkgutil.iter_modules(pkg.__path__):
        if not mod.name.startswith("_") and not mod.ispkg:
            importlib.import_module(f"{pkg.__name__}.{mod.name}")
    _LOADED = True
    check_declarations(_STAGES, _SECTIONS, _COORDS)


def check_declarations(all_stages: Mapping[str, Stage], all_sections: Mapping[str, Section],
                       shared_coords: Mapping[str, Var]) -> None:
    """Every scene key a stage declares exists in the schema, every upstream stage exists, and no
    stage redeclares a shared coordinate. Raises ValueError (a bug in a stage) otherwise."""
    for st in all_stages.values():
        for dotted in st.keys:
            section, _, key = dotted.partition(".")
            if section not in all_sections:
                raise ValueError(f"stage {st.name} reads {dotted!r}: there is no scene section [{section}]")
            sec = all_sections[section]
            names = {p.name for p in sec.params} | {p.name for ps in sec.variants.values() for p in ps}
            if sec.discriminator:
                names.add(sec.discriminator)
            if key and key not in names:
                raise ValueError(f"stage {st.name} reads {dotted!r}: [{section}] has no key {key!r}")
        for f in st.files:
            if f.param not in st.keys and f.param.partition(".")[0] not in st.keys:
                raise ValueError(f"stage {st.name} reads the file of {f.param!r} without declaring that key in params")
        for up in st.requires:
            if up not in all_stages:
                raise ValueError(f"stage {st.name} needs {up!r}, which is not a stage")
        for when in (u.when for u in st.needs if isinstance(u, Upstream)):
            unknown = [k for k in when if k.partition(".")[0] not in {*all_sections, "outputs"}]
            if unknown:
                raise ValueError(f"stage {st.name} needs an upstream stage when {unknown[0]!r}: no such scene section")
        _check_reads(st, all_sections)
        shared = sorted(set(st.coords) & set(shared_coords))
        if shared:
            raise ValueError(f"stage {st.name} redeclares the shared coordinate(s) {shared}")


def _check_reads(st: Stage, all_sections: Mapping[str, Section]) -> None:
    """Every :class:`ByKind` selection names a section with kinds, and every key it names exists
    for that kind."""
    for selection in (r for r in st.reads if isinstance(r, ByKind)):
        name = selection.section
        if name not in all_sections or not all_sections[name].discriminator:
            raise ValueError(f"stage {st.name} selects keys of {name!r}, which is not a section with kinds")
        sec = all_sections[name]
        for kind, keys in selection.keys.items():
            if kind != "*" and kind not in sec.variants:
                raise ValueError(f"stage {st.name} reads keys of [{name}] kind {kind!r}, which does not exist")
            names = {p.name for p in sec.params}
            names |= {p.name for ps in sec.variants.values() for p in ps} if kind == "*" else {
                p.name for p in sec.variants[kind]}
            unknown = sorted(set(keys) - names)
            if unknown:
                raise ValueError(f"stage {st.name} reads {unknown} of [{name}] kind {kind!r}: no such key")
