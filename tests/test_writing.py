"""Writing computed results (issue 27): blocks compressed where they are computed and written as
HDF5 stores them read back bit for bit through netCDF4 and xarray; compression is chosen per
variable from a trial block and recorded; a failure while writing leaves nothing behind."""

from __future__ import annotations

import dask.array as da
import netCDF4
import numpy as np
import pytest
import xarray as xr
from scipy.special import erf

from roughcontact import store, writing


def _dataset(chunks=(48, 10)) -> xr.Dataset:
    """A contact-area-like field (smooth, in [0, 1], with NaN where undefined), a quantity of the
    load alone (the same along eta: compresses well), doubles over 600 decades (nothing to gain from
    compressing them) and small integers, chunked as a sweep is."""
    rng = np.random.default_rng(7)
    p = np.geomspace(1e6, 1e11, 200)
    eta = np.linspace(-1.0, 1.0, 23)
    area = erf(np.sqrt(p[:, None] / 1e9) * (1.5 + eta[None, :]))
    area[3, 4] = np.nan  # data variables of 16 KiB and more are compressed: these are 37 KiB and 18 KiB
    noise = rng.standard_normal(area.shape) * 10.0 ** rng.uniform(-300, 300, area.shape)
    counts = (np.arange(area.size).reshape(area.shape) % 7).astype(np.int32)
    lazy = {name: (("p", "eta"), da.from_array(v, chunks=chunks), {"units": "1", "long_name": name})
            for name, v in (("area", area), ("log_p", np.log10(p)[:, None] + 0.0 * eta), ("noise", noise),
                            ("counts", counts))}
    return xr.Dataset(lazy, coords={"p": ("p", p, {"units": "Pa"}), "eta": ("eta", eta, {"units": "1"})})


def _roundtrip(tmp_path, ds, **kw) -> xr.Dataset:
    path = tmp_path / "result.nc"
    store.write(ds, path, **kw)
    with xr.open_dataset(path) as back:
        return back.load()


@pytest.fixture(params=["direct chunks", "through netCDF4"])
def route(request, monkeypatch):
    if request.param == "through netCDF4":  # as where h5py is missing: HDF5 compresses in the writer
        monkeypatch.setattr(writing, "_h5py", lambda: None)
    return request.param


@pytest.mark.parametrize("chunks", [(48, 10), (200, 23), ((5, 10, 10, 175), (23,))], ids=["edges", "one", "irregular"])
def test_values_read_back_bit_for_bit(tmp_path, route, chunks):
    ds = _dataset(chunks)
    back = _roundtrip(tmp_path, ds)
    for name in ("area", "log_p", "noise", "counts"):
        expected = ds[name].values
        assert back[name].dtype == expected.dtype
        assert np.array_equal(back[name].values, expected, equal_nan=True)
        assert np.array_equal(back[name].values.view(np.uint8), expected.view(np.uint8))  # bits, NaN included
    with netCDF4.Dataset(tmp_path / "result.nc") as nc:  # the netCDF library itself, no xarray decoding
        nc.set_auto_mask(False)
        assert np.array_equal(nc["area"][:], ds["area"].values, equal_nan=True)
        assert np.array_equal(nc["log_p"][:], ds["log_p"].values)


def test_compression_is_chosen_per_variable_and_recorded(tmp_path, route):
    _roundtrip(tmp_path, _dataset())
    with netCDF4.Dataset(tmp_path / "result.nc") as nc:
        log_p, noise, counts = nc["log_p"], nc["noise"], nc["counts"]
        assert log_p.filters()["zlib"] and log_p.filters()["shuffle"] and log_p.chunking() == [48, 10]
        assert log_p.compression.startswith("zlib level 1 with shuffle")
        assert counts.filters()["zlib"]
        # random doubles do not shrink: stored as they are, and the reason is said
        assert not noise.filters()["zlib"] and noise.chunking() == "contiguous"
        assert noise.compression.startswith("none (zlib with shuffle left a trial block at")


def test_the_trial_decides_as_the_sizes_say():
    rng = np.random.default_rng(1)
    smooth = erf(np.linspace(0.0, 3.0, 4096))
    pays, note, packed, encoded = writing.choose(smooth, smooth.dtype)
    assert pays and len(encoded) <= writing.PAYS * smooth.nbytes and packed[-1]  # sign and exponent byte
    noise = rng.standard_normal(4096) * 10.0 ** rng.uniform(-300, 300, 4096)
    pays, note, packed, encoded = writing.choose(noise, noise.dtype)
    assert not pays and len(encoded) > writing.PAYS * noise.nbytes and not any(packed)


def test_a_chunk_is_encoded_as_hdf5_reads_it():
    """The stream inflates (any zlib reader) to HDF5's shuffled bytes of the padded chunk, whichever
    byte planes are compressed; the long runs of padding (rows of zeros beyond the block) too."""
    import zlib

    block = erf(np.linspace(0.0, 2.0, 1500)).reshape(5, 300)
    for packed in ([True] * 8, [False] * 6 + [True] * 2, [False] * 8):
        for chunk in ((5, 300), (8, 400)):  # a full chunk; an edge chunk: 100 zeros after each row, then 1300
            raw = zlib.decompress(writing.encode_chunk(block, chunk, block.dtype, 1, packed))
            planes = np.frombuffer(raw, np.uint8).reshape(8, -1)
            values = planes.T.copy().view(np.float64).reshape(chunk)
            assert np.array_equal(values[:5, :300], block)
            assert not values[5:].any() and not values[:, 300:].any()
    stored = writing.encode_chunk(block, (8, 400), block.dtype, 1, [False] * 8)
    assert len(stored) < 8 * 5 * 400  # the 1300 zeros of each plane compressed, the 100 stored


def test_uncompressed_results_have_no_filters(tmp_path, route):
    back = _roundtrip(tmp_path, _dataset(), compress=False)
    assert np.array_equal(back["area"].values, _dataset()["area"].values, equal_nan=True)
    with netCDF4.Dataset(tmp_path / "result.nc") as nc:
        assert not any(nc[n].filters()["zlib"] for n in ("area", "log_p", "noise", "counts"))
        assert "compression" not in nc["log_p"].ncattrs()


def test_a_failing_block_leaves_nothing(tmp_path, route):
    """A block that fails after others were written: the error reaches the caller, the temporary
    is removed and no result file appears."""
    ds = _dataset()

    def fail_late(x, block_info=None):
        if block_info[0]["chunk-location"] == (3, 1):  # the eleventh of 15 blocks
            raise ValueError("kernel failed")
        return x

    ds["area"] = ds["area"].copy(data=ds["area"].data.map_blocks(fail_late, dtype=float))
    with pytest.raises(ValueError, match="kernel failed"):
        store.write(ds, tmp_path / "result.nc")
    assert list(tmp_path.iterdir()) == []


def test_costliest_blocks_are_computed_first_and_write_the_same_values(tmp_path, monkeypatch):
    """Longest-first ordering (``Shape.costlier_with``): the blocks reach the scheduler in
    decreasing order of the product of their coordinates along those dimensions (a NaN coordinate
    counts 1, ties keep their order), and the file holds the same values as in the natural order."""
    ds = _dataset(chunks=(50, 6))  # p: 4 blocks, eta: 4 blocks
    group = writing._groups(ds, ["area"], None)[0]
    order = writing.costliest_first(ds, group, ("p",))
    largest_p = [np.abs(ds["p"].values[group.region(idx)[0]]).max() for idx in order]
    assert largest_p == sorted(largest_p, reverse=True) and sorted(order) == sorted(group.indices)
    assert [idx[0] for idx in order[:4]] == [3, 3, 3, 3] and [idx[1] for idx in order[:4]] == [0, 1, 2, 3]
    both = writing.costliest_first(ds, group, ("p", "eta"))
    work = [np.abs(ds["p"].values[group.region(i)[0]]).max() * np.abs(ds["eta"].values[group.region(i)[1]]).max()
            for i in both]
    assert work == sorted(work, reverse=True)
    assert writing.costliest_first(ds, group, ("not_a_dimension",)) == group.indices

    seen = []
    real = writing.computed_blocks

    def recording(tasks, *args, **kwargs):
        tasks = list(tasks)
        seen.extend(idx for idx, _ in tasks)
        return real(iter(tasks), *args, **kwargs)

    monkeypatch.setattr(writing, "computed_blocks", recording)
    back = _roundtrip(tmp_path, ds, costlier_with=("p",))
    assert seen[:4] == order[:4]
    assert np.array_equal(back["area"].values, ds["area"].values, equal_nan=True)
