"""Writing the dask-computed variables of a result into its NetCDF file, block by block.

:func:`write_blocks` fills the lazily computed variables of a result file whose in-memory part is
already written (:func:`roughcontact.store.write`): the blocks are computed on the scene's
scheduler (:func:`roughcontact.scheduling.computed_blocks`, the next ones while this process
writes) and written by this process only, so that a sweep never has to fit in memory and no worker
ever writes to the file.

Compression is not done by the writer. A compressed variable is chunked in the blocks it is
computed in (:mod:`roughcontact.cf`); as soon as a batch of blocks is computed, threads of this
process encode each block as HDF5 stores such a chunk (the shuffle filter, then zlib:
:func:`encode_chunk`; numpy and zlib release the GIL), while the next batch is computed and the
writer hands the bytes to HDF5 as they are (h5py's ``write_direct_chunk``, into the variable
netCDF4 defined with the same chunk shape and filters). Reading is unchanged: every NetCDF reader
decompresses the chunks itself and gets the values computed, bit for bit. The blocks of a stage
that keeps them (long work, few blocks) are encoded by the writer. A block that is not exactly one
chunk (irregular chunks), a variable of another type, or a file h5py cannot write (h5py missing)
is written through the library, which compresses it in the writer as before.

Compression pays only for data that shrinks: the first block of every variable is compressed
before the variable is defined (:func:`choose`), and a variable whose trial block keeps more than
:data:`PAYS` of its size is written uncompressed (contact areas of a large sweep gain about a
quarter). The variable's ``compression`` attribute records what was chosen and why.

:class:`KeptBlocks`: for a stage whose blocks are long work (``Shape(keep_blocks=True)``, the
validation's BEM tasks), every finished block is also saved in the output folder under the
result's content key, as it arrives, so that a run that is killed resumes where it stopped.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import os
import struct
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from . import cf, ncio
from .progress import Tick
from .scheduling import computed_blocks

#: a variable whose trial block compresses to more than this fraction of its size is written uncompressed
PAYS = 0.8
#: attributes with which netCDF4 would change values on writing: such variables are written through it
_PACKING = ("scale_factor", "add_offset")


class KeptBlocks:
    """The finished blocks of one result being written, kept in ``folder`` (one ``.npz`` per
    block, named by the block's dimensions and index ranges, written atomically) so that a run
    that is killed resumes: the next run with the same content key reads them instead of
    computing them. The folder is the result's (:func:`roughcontact.store.kept_blocks_folder`),
    its name holds the key; the store removes it once the result is written."""

    def __init__(self, folder: Path, tmp_prefix: str = ".tmp-"):
        self.folder = Path(folder)
        self.tmp_prefix = tmp_prefix  # the store's: its clean-up removes what a kill leaves

    def _file(self, dims, region) -> Path:
        where = "_".join(f"{s.start}-{s.stop}" for s in region)
        return self.folder / f"{'.'.join(dims) or 'scalar'}@{where or '0'}.npz"

    def load(self, dims, names, region) -> list[np.ndarray] | None:
        """The block's values per variable of ``names``, or None if not kept (or unreadable)."""
        path = self._file(dims, region)
        if not path.is_file():
            return None
        shape = tuple(s.stop - s.start for s in region)
        try:
            with np.load(path, allow_pickle=False) as kept:
                values = [kept[name] for name in names]
        except (OSError, KeyError, ValueError, EOFError):
            return None
        return values if all(v.shape == shape for v in values) else None

    def save(self, dims, names, region, values) -> None:
        """Keep a block: a temporary in the folder, then a rename (a kill leaves no half block)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=self.tmp_prefix, suffix=".npz", dir=self.folder)
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **{name: np.asarray(v) for name, v in zip(names, values, strict=True)})
            os.replace(tmp, self._file(dims, region))
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise


def dask_variables(ds: xr.Dataset) -> list[str]:
    return [name for name, v in ds.variables.items() if v.chunks is not None]


def _shuffled(values, chunk: tuple[int, ...], dtype) -> np.ndarray:
    """The bytes of a chunk of shape ``chunk`` (the block at its origin, padded with zeros where it
    is smaller: an edge chunk, outside the data) as HDF5's shuffle filter orders them: each value's
    byte 0, then each one's byte 1, ... (one row per byte plane)."""
    values = np.asarray(values, dtype=dtype)
    if values.shape != tuple(chunk):
        padded = np.zeros(chunk, dtype=dtype)
        padded[tuple(slice(0, n) for n in values.shape)] = values
        values = padded
    flat = np.ascontiguousarray(values).reshape(-1).view(np.uint8)
    return np.ascontiguousarray(flat.reshape(-1, values.dtype.itemsize).T)


#: a zlib stream's header (deflate, 32 KiB window, fastest) and a final empty deflate block
_HEADER, _LAST = b"\x78\x01", b"\x03\x00"
#: runs of padding (values) from this length on are compressed in a stored byte plane
_LONG_PADDING = 64
#: deflate segments (byte-aligned, not final) that inflate to n zero bytes, by n
_ZEROS: dict[int, bytes] = {}


def _zeros(n: int) -> bytes:
    segment = _ZEROS.get(n)
    if segment is None:
        enc = zlib.compressobj(1, zlib.DEFLATED, -15)
        segment = enc.compress(bytes(n)) + enc.flush(zlib.Z_SYNC_FLUSH)
        if len(_ZEROS) > 1024:  # run lengths repeat from chunk to chunk; a few kinds of chunk
            _ZEROS.clear()
        _ZEROS[n] = segment
    return segment


def _stored(data: memoryview) -> list:
    """Deflate stored blocks (not final, byte-aligned) holding ``data`` as it is."""
    parts = []
    for start in range(0, len(data), 65535):
        piece = data[start:start + 65535]
        parts += [struct.pack("<BHH", 0, len(piece), len(piece) ^ 0xFFFF), piece]
    return parts


@functools.lru_cache(maxsize=64)
def _padding_runs(block: tuple[int, ...], chunk: tuple[int, ...]) -> tuple[tuple[int, int], ...] | None:
    """``(start, stop)`` (values, in the chunk's order) of the runs of padding of at least
    :data:`_LONG_PADDING` values in a chunk holding a block of shape ``block``; None if it is full."""
    if tuple(block) == tuple(chunk):
        return None
    real = np.zeros(chunk, dtype=np.int8)
    real[tuple(slice(0, n) for n in block)] = 1
    edges = np.flatnonzero(np.diff(np.concatenate([[1], real.reshape(-1), [1]])))
    return tuple((int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= _LONG_PADDING)


def _deflate(planes: np.ndarray, level: int, packed, padding=None) -> bytes:
    """The zlib stream of the byte planes ``planes`` (rows) in order: the planes ``packed`` marks
    compressed at ``level``, the others stored as they are (deflate's stored blocks: random low
    mantissa bytes do not shrink, and zlib takes most of its time trying), but for the long runs
    of ``padding`` (an edge chunk, zeros beyond the data: :func:`_padding_runs`), which are
    compressed. Any zlib reader (HDF5's deflate filter) inflates it to the same bytes as a stream
    compressed whole."""
    parts = [_HEADER]
    for plane, pack in zip(planes, packed, strict=True):
        if pack:
            enc = zlib.compressobj(level, zlib.DEFLATED, -15)
            parts += [enc.compress(plane), enc.flush(zlib.Z_SYNC_FLUSH)]
            continue
        data, at = memoryview(plane), 0
        for start, stop in padding or ():
            parts += _stored(data[at:start]) + [_zeros(stop - start)]
            at = stop
        parts += _stored(data[at:])
    parts += [_LAST, zlib.adler32(planes).to_bytes(4, "big")]
    return b"".join(parts)


def encode_chunk(values, chunk: tuple[int, ...], dtype, level: int = cf.LEVEL, packed=None) -> bytes:
    """The bytes HDF5 stores for one chunk of shape ``chunk`` of a variable of type ``dtype`` under
    the shuffle and deflate filters (:func:`_shuffled`, then zlib at ``level``; ``packed``: which
    byte planes are compressed, by default all)."""
    planes = _shuffled(values, chunk, dtype)
    padding = _padding_runs(tuple(np.shape(values)), tuple(chunk))
    return _deflate(planes, level, packed if packed is not None else [True] * len(planes), padding)


def _encoded(values, specs) -> list | None:
    """Per variable of a block, its chunk encoded as ``specs`` says (``(chunk, dtype, level, packed)``
    or None per variable; None: nothing encoded)."""
    if not specs or not any(specs):
        return None
    return [None if s is None else encode_chunk(v, *s) for v, s in zip(values, specs, strict=True)]


def _region(offsets, idx) -> tuple[slice, ...]:
    """The slices of block ``idx`` (one index per dimension) given each dimension's chunk offsets."""
    return tuple(slice(int(o[i]), int(o[i + 1])) for o, i in zip(offsets, idx, strict=True))


@dataclass
class _Group:
    """Variables with the same dimensions and dask chunks, computed and written together."""

    dims: tuple[str, ...]
    names: list[str]
    chunks: tuple[tuple[int, ...], ...]
    kept: dict = field(default_factory=dict)  # block index -> values, the blocks a killed run kept

    def __post_init__(self):
        self.offsets = [np.concatenate([[0], np.cumsum(c)]) for c in self.chunks]
        self.indices = list(itertools.product(*(range(len(c)) for c in self.chunks)))
        self.chunk = tuple(max(c) for c in self.chunks)  # the file's chunk shape (cf.lazy_variable)

    def region(self, idx) -> tuple[slice, ...]:
        return _region(self.offsets, idx)

    def fills_a_chunk(self, idx) -> bool:
        """Whether block ``idx`` is exactly one chunk of the file (an edge chunk: up to the edge)."""
        return all(s.start % c == 0 and (s.stop - s.start == c or s.stop == o[-1])
                   for s, c, o in zip(self.region(idx), self.chunk, self.offsets, strict=True))


def _groups(ds: xr.Dataset, names: list[str], keep: KeptBlocks | None) -> list[_Group]:
    """The variables ``names`` per group of the same dimensions and chunks, with the blocks ``keep`` holds."""
    by: dict[tuple, list[str]] = {}
    for name in names:
        var = ds[name].variable
        by.setdefault((var.dims, var.chunks), []).append(name)
    out = []
    for (dims, chunks), group in by.items():
        g = _Group(dims, group, chunks)
        for idx in g.indices if keep is not None else ():
            values = keep.load(dims, group, g.region(idx))
            if values is not None:
                g.kept[idx] = values
        out.append(g)
    return out


def costliest_first(ds: xr.Dataset, group: _Group, costlier_with: tuple[str, ...]) -> list[tuple]:
    """The group's block indices, those whose work is largest first: work taken as the product,
    over the dimensions ``costlier_with`` the group spans, of the largest |coordinate| in the block
    (a NaN or a dimension without coordinate counts 1); ties keep their order (a stable sort)."""
    along = [(axis, np.abs(np.asarray(ds[dim].values, dtype=float)))
             for axis, dim in enumerate(group.dims) if dim in costlier_with and dim in ds.coords]
    if not along:
        return group.indices

    def work(idx) -> float:
        region = group.region(idx)
        product = 1.0
        for axis, values in along:
            block = values[region[axis]]
            largest = np.nanmax(block) if np.isfinite(block).any() else 1.0
            product *= largest
        return product

    return sorted(group.indices, key=work, reverse=True)


def _candidate(var: xr.Variable, compress: bool) -> bool:
    """Whether the variable would be compressed (cf.lazy_variable) if compression pays."""
    return bool(compress and var.ndim and var.nbytes >= cf.COMPRESS_BYTES and var.dtype.kind in "fiu")


def choose(values, dtype) -> tuple[bool, str, tuple[bool, ...], bytes]:
    """Whether a variable whose first block is ``values`` is worth compressing, the ``compression``
    attribute saying so, which byte planes to compress (those that shrink to :data:`PAYS` or less),
    and the block encoded so (:func:`encode_chunk`, in its own shape)."""
    values = np.asarray(values)
    planes = _shuffled(values, values.shape, dtype)
    packed = tuple(len(zlib.compress(plane, cf.LEVEL)) <= PAYS * plane.nbytes for plane in planes)
    encoded = _deflate(planes, cf.LEVEL, packed)
    ratio = len(encoded) / max(1, values.nbytes)
    if ratio <= PAYS:
        return True, (f"zlib level {cf.LEVEL} with shuffle, {sum(packed)} of {len(packed)} byte planes compressed "
                      f"(a trial block took {ratio:.0%} of its size)"), packed, encoded
    return False, (f"none (zlib with shuffle left a trial block at {ratio:.0%} of its size; compression is used "
                   f"from {PAYS:.0%} down)"), packed, encoded


def define(path, ds: xr.Dataset, names: list[str], compress: dict[str, bool], notes: dict[str, str]) -> None:
    """Declare the lazily computed variables ``names`` in the file, with their attributes:
    compressed or not as ``compress`` says (per variable), ``notes`` as their ``compression``
    attribute; and the ``coordinates`` attribute of every data variable defined so far."""
    import netCDF4

    with ncio.locked(), netCDF4.Dataset(path, "a") as nc:
        for name in names:
            var = ds[name].variable
            for dim in var.dims:
                if dim not in nc.dimensions:
                    nc.createDimension(dim, ds.sizes[dim])
            target = nc.createVariable(name, var.dtype, var.dims, **cf.lazy_variable(ds, name, compress[name]))
            target.setncatts(dict(var.attrs) | ({"compression": notes[name]} if name in notes else {}))
        lazy = [n for n in dask_variables(ds) if n in ds.coords and n not in ds.dims]
        for name in ds.data_vars:
            extra = [c for c in lazy if set(ds[c].dims) <= set(ds[name].dims)]
            if extra and name in nc.variables:
                nc.variables[name].setncattr("coordinates", " ".join(extra))


def _h5py():
    try:
        import h5py
    except ImportError:  # written through netCDF4, HDF5 compressing in this process
        return None
    return h5py


def _direct(dset, dtype, chunk, packed) -> tuple | None:
    """``(chunk, dtype, level, packed)`` when the HDF5 dataset ``dset`` stores chunks of shape ``chunk`` and
    type ``dtype`` under exactly the shuffle and deflate filters (what :func:`encode_chunk` makes)."""
    if dset.chunks != tuple(chunk) or dset.dtype != dtype:
        return None
    plist = dset.id.get_create_plist()
    filters = [plist.get_filter(i) for i in range(plist.get_nfilters())]
    if [f[0] for f in filters] != [2, 1] or tuple(filters[1][2])[:1] != (cf.LEVEL,):
        return None
    return tuple(chunk), np.dtype(dtype).str, cf.LEVEL, packed


def _packed(ds: xr.Dataset, name: str) -> bool:
    """Whether variable ``name`` carries packing attributes (netCDF4 scales its values on writing)."""
    return bool(set(_PACKING) & set(ds[name].attrs))


@contextlib.contextmanager
def _target(path, ds: xr.Dataset, group: _Group, compress: dict[str, tuple | None]):
    """Yield ``(write, specs)`` for the group's variables defined in the file: ``write(name, region,
    values, encoded)`` writes a block (``encoded``: its chunk as HDF5 stores it, or None; ``compress``:
    per variable, the byte planes to compress, None: not compressed), ``specs``
    per variable what the blocks' computation is to encode (:func:`_prepared`; None: nothing).
    Through h5py where it can write compressed chunks as they are (never both libraries on the file
    at once), else through netCDF4."""
    h5py = _h5py()
    plain = (h5py is None or not any(p is not None for p in compress.values())  # nothing to compress: netCDF4
             or any(ds[n].dtype.kind not in "fiu" or _packed(ds, n) for n in group.names))
    if not plain:
        with ncio.locked():
            f = h5py.File(path, "r+")
        try:
            with ncio.locked():
                plain = any(n not in f for n in group.names)
                sets = {} if plain else {n: f[n] for n in group.names}
                specs = {n: _direct(d, ds[n].dtype, group.chunk, compress[n]) if compress[n] else None
                         for n, d in sets.items()}
            if not plain:
                def write(name, region, values, encoded):
                    with ncio.locked():
                        if encoded is not None:
                            sets[name].id.write_direct_chunk(tuple(s.start for s in region), encoded)
                        else:
                            sets[name][region] = values
                yield write, specs
                return
        finally:
            with ncio.locked():
                f.close()
    with ncio.dataset(path, "a") as nc:
        with ncio.locked():
            targets = {n: nc.variables[n] for n in group.names}
            for n, target in targets.items():  # the values as computed: netCDF4's masking pass cost 4x the write
                if not _packed(ds, n):  # (packed variables are scaled by netCDF4 on the way)
                    target.set_auto_maskandscale(False)

        def write(name, region, values, encoded):
            with ncio.locked():
                targets[name][region] = values

        yield write, dict.fromkeys(group.names)


def write_blocks(path, ds: xr.Dataset, names: list[str], compute_with, progress=None, in_flight: int | None = None,
                 checksums=None, keep: KeptBlocks | None = None, compress: bool = True,
                 costlier_with: tuple[str, ...] = ()) -> None:
    """Define the dask variables ``names`` of ``ds`` in the existing NetCDF file ``path`` (whose
    other variables are already written), compute them block by block on ``compute_with`` (what
    :func:`roughcontact.scheduling.scheduler` yields) and write them; ``progress`` (a
    :class:`roughcontact.progress.Reporter`) shows the blocks written, ``checksums`` (a
    :class:`roughcontact.integrity.Checksums`) hashes them, ``compress``: variables of
    :data:`roughcontact.cf.COMPRESS_BYTES` and more compressed where it pays (:func:`choose`).

    Variables with the same dimensions and chunks are computed together, so that work they share
    (an integral over q, say) is done once per block.

    With ``keep`` (:class:`KeptBlocks`), the blocks it holds are written without computing them,
    and every other block is computed on its own and kept as soon as it finishes (then written),
    so that a run killed at any moment loses at most the blocks being computed.

    ``costlier_with``: dimensions along which a block's work grows with the coordinate's value;
    the blocks are computed in decreasing order of the product of those values (longest first:
    :func:`costliest_first`), which changes no value written.
    """
    groups = _groups(ds, names, keep)
    for group in groups:
        group.indices = costliest_first(ds, group, costlier_with)
    total = sum(len(g.indices) for g in groups)
    done_before = sum(len(g.kept) for g in groups)
    if progress is not None and done_before:
        progress.note(f"    {done_before} of {total} blocks kept from an interrupted run: computing the other "
                      f"{total - done_before}")
    bar = progress.bar("writing", total, unit="block", initial=done_before) if progress is not None else Tick()
    for group in groups:
        _write_group(path, ds, group, compute_with, bar, in_flight, checksums, keep, compress)


def _write_group(path, ds, group: _Group, compute_with, bar, in_flight, checksums, keep, compress) -> None:
    """Compute, define (after the trial of its first block) and write the variables of one group."""
    arrays = [ds[name].data for name in group.names]
    trial = [n for n in group.names if _candidate(ds[n].variable, compress)]
    specs: dict[str, tuple | None] = {}  # set once the variables are defined: what the workers encode

    def tasks():
        for idx in group.indices:
            if idx not in group.kept:
                yield idx, [a.blocks[idx] for a in arrays]

    def encode(idx, values):  # in a thread beside the computation (zlib and numpy release the GIL)
        return values, _encoded(values, [specs.get(n) for n in group.names] if group.fills_a_chunk(idx) else None)

    one_by_one = keep is not None  # then encoded by the writer: long blocks, few of them
    blocks = computed_blocks(tasks(), compute_with, in_flight, one_by_one, finish=None if one_by_one else encode)
    computed = ((idx, (values, None)) for idx, values in blocks) if one_by_one else blocks
    arriving = itertools.chain(((idx, (values, None)) for idx, values in group.kept.items()), computed)
    first = group.indices[0]
    held: dict = {}  # blocks that arrived before the first one (whose trial decides the definition)
    with contextlib.ExitStack() as stack:
        stack.callback(blocks.close)  # on a failure too: no more blocks started
        write = None
        if not trial:  # nothing to decide: defined before anything is computed
            write, opened, _ = _open(stack, path, ds, group, trial, held, first)
            specs.update(opened)
        for idx, (values, encoded) in arriving:
            if keep is not None and idx not in group.kept:
                keep.save(group.dims, group.names, group.region(idx), values)
            if write is None:
                held[idx] = (values, encoded)
                if first not in held:
                    continue
                write, opened, held = _open(stack, path, ds, group, trial, held, first)
                specs.update(opened)
                todo, held = list(held.items()), {}
            else:
                todo = [(idx, (values, encoded))]
            for i, (vals, enc) in todo:
                _write_block(write, ds, group, specs, i, vals, enc, checksums)
                if i not in group.kept:
                    bar()


def _open(stack, path, ds, group: _Group, trial: list[str], held: dict, first):
    """Decide compression from the first block (in ``held``), define the group's variables and open
    the file for them: ``(write, specs, held)``, ``held`` with the first block's trial encodings kept
    where they are what the file stores."""
    packed, notes, trial_bytes = dict.fromkeys(group.names), {}, {}
    for name in trial:
        values = held[first][0][group.names.index(name)]
        pays, notes[name], planes, trial_bytes[name] = choose(values, ds[name].dtype)
        packed[name] = planes if pays else None
    define(path, ds, group.names, {n: p is not None for n, p in packed.items()}, notes)
    write, specs = stack.enter_context(_target(path, ds, group, packed))
    if first in held and held[first][1] is None and group.fills_a_chunk(first):
        values = held[first][0]
        shape = tuple(s.stop - s.start for s in group.region(first))
        reuse = [trial_bytes.get(n) if specs.get(n) and shape == group.chunk else None for n in group.names]
        held[first] = (values, reuse)
    return write, specs, held


def _write_block(write, ds, group: _Group, specs, idx, values, encoded, checksums) -> None:
    region = group.region(idx)
    for k, (name, value) in enumerate(zip(group.names, values, strict=True)):
        data = encoded[k] if encoded is not None else None
        if data is None and specs.get(name) is not None and group.fills_a_chunk(idx):
            data = encode_chunk(value, *specs[name])  # computed before the variable was defined
        write(name, region, None if data is not None else np.asarray(value), data)
        if checksums is not None:
            checksums.add(name, np.asarray(value), [s.start for s in region])
