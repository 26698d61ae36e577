"""Tests of the modulus stage (stages/modulus.py): complex modulus E(omega, T)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import roughcontact as rc
from roughcontact import cli, engine, scene as scenes, store
from roughcontact.errors import UserError
from roughcontact.physics import viscoelastic as ve
from roughcontact.stages import modulus as md

QUIET = engine.Reporter(None)


def _raw(modulus, **extra):
    raw = {
        "name": "m",
        "substrate": {"kind": "self_affine", "H": 0.8, "qL": "1e4 1/m", "q1": "1e6 1/m", "hrms": "1 um"},
        "material": {"E": "5 MPa", "nu": 0.5},
        "load": {"p": "0.4 MPa"},
        "modulus": modulus,
        "outputs": {"variables": ["storage_modulus"]},
    }
    raw.update(extra)
    return raw


def _modulus(modulus, tmp_path, **extra):
    sc = scenes.from_dict(_raw(modulus, **extra), tmp_path / "scene.toml")
    return engine.run(sc, tmp_path / "out", report=QUIET)["base"]["modulus"]


BOX = {"kind": "box", "E0": "5 MPa", "E_inf": "3 GPa", "tau1": "1e-6 s", "tau2": "1e4 s"}

# ----------------------------------------------------------------------------------------
# Model moduli: symmetry, sign, limits, against the textbook complex formulas
# ----------------------------------------------------------------------------------------

omegas = st.lists(st.floats(-30, 30), min_size=1, max_size=20).map(lambda xs: 10.0 ** np.asarray(xs))


@settings(max_examples=50, deadline=None)
@given(w=omegas, E0=st.floats(1e4, 1e9), ratio=st.floats(1.0001, 1e5), t1=st.floats(-15, 3),
       decades=st.floats(0.01, 20))
def test_box_conjugate_symmetry_and_positive_loss(w, E0, ratio, t1, decades):
    tau1 = 10.0**t1
    tau2 = tau1 * 10.0**decades
    Ep, Epp = ve.box_spectrum_modulus(w, E0, E0 * ratio, tau1, tau2)
    Em, Emm = ve.box_spectrum_modulus(-w, E0, E0 * ratio, tau1, tau2)
    assert np.all(np.isfinite(Ep)) and np.all(np.isfinite(Epp))
    np.testing.assert_array_equal(Em, Ep)
    np.testing.assert_array_equal(Emm, -Epp)
    assert np.all(Epp >= 0)
    assert np.all((Ep >= E0 * (1 - 1e-12)) & (Ep <= E0 * ratio * (1 + 1e-12)))


@settings(max_examples=50, deadline=None)
@given(w=omegas, E0=st.floats(1e4, 1e9),
       terms=st.lists(st.tuples(st.floats(1e3, 1e10), st.floats(-12, 6)), min_size=1, max_size=8))
def test_prony_conjugate_symmetry_positive_loss_and_monotone_storage(w, E0, terms):
    Ek = np.array([t[0] for t in terms])
    tk = 10.0 ** np.array([t[1] for t in terms])
    w = np.sort(w)
    Ep, Epp = ve.prony_modulus(w, E0, Ek, tk)
    Em, Emm = ve.prony_modulus(-w, E0, Ek, tk)
    np.testing.assert_array_equal(Em, Ep)
    np.testing.assert_array_equal(Emm, -Epp)
    assert np.all(Epp >= 0)
    assert np.all(np.diff(Ep) >= -1e-9 * Ep[1:])  # E' never decreases with frequency


def test_box_matches_complex_log_formula_and_limits():
    """docs/theory.md, section "Viscoelasticity" written with complex logarithms, at moderate omega tau."""
    E0, Ei, t1, t2 = 2e6, 1e9, 1e-5, 1e2
    w = np.geomspace(1e-3, 1e6, 41)
    E = E0 + (Ei - E0) / np.log(t2 / t1) * (np.log(1 + 1j * w * t2) - np.log(1 + 1j * w * t1))
    Ep, Epp = ve.box_spectrum_modulus(w, E0, Ei, t1, t2)
    np.testing.assert_allclose(Ep, E.real, rtol=1e-12)
    np.testing.assert_allclose(Epp, E.imag, rtol=1e-12)
    lo = ve.box_spectrum_modulus(1e-12, E0, Ei, t1, t2)
    hi = ve.box_spectrum_modulus(1e20, E0, Ei, t1, t2)
    assert lo[0] == pytest.approx(E0, rel=1e-12) and hi[0] == pytest.approx(Ei, rel=1e-12)
    # terminal behaviours: E'' ~ omega (tau2 - tau1) D at low, ~ D (1/tau1 - 1/tau2)/omega at high
    D = (Ei - E0) / np.log(t2 / t1)
    assert lo[1] == pytest.approx(D * 1e-12 * (t2 - t1), rel=1e-9)
    assert hi[1] == pytest.approx(D * (1 / t1 - 1 / t2) / 1e20, rel=1e-9)


def test_prony_matches_complex_formula():
    E0, Ek, tk = 1e6, np.array([3e6, 5e7, 2e8]), np.array([1e-4, 1e-1, 10.0])
    w = np.geomspace(1e-4, 1e7, 23)
    E = E0 + (Ek * 1j * w[:, None] * tk / (1 + 1j * w[:, None] * tk)).sum(-1)
    Ep, Epp = ve.prony_modulus(w, E0, Ek, tk)
    np.testing.assert_allclose(Ep, E.real, rtol=1e-12)
    np.testing.assert_allclose(Epp, E.imag, rtol=1e-12)


# ----------------------------------------------------------------------------------------
# Interpolation and extrapolation of the stored grid
# ----------------------------------------------------------------------------------------


def test_modulus_at_reproduces_the_box_to_1e5_at_20_points_per_decade():
    E0, Ei, t1, t2 = 5e6, 3e9, 1e-16, 1e-6
    grid = np.geomspace(1e-6, 1e19, 25 * 20 + 1)
    Sp, Sl = ve.box_spectrum_modulus(grid, E0, Ei, t1, t2)
    w = np.geomspace(1e-12, 1e25, 5001)
    a, b = ve.modulus_at(w, grid, Sp, Sl)
    ea, eb = ve.box_spectrum_modulus(w, E0, Ei, t1, t2)
    assert np.max(np.abs(a / ea - 1)) < 2e-5
    assert np.max(np.abs(b / eb - 1)) < 2e-5
    # nodes are reproduced exactly; negative frequency gives the conjugate
    np.testing.assert_allclose(ve.modulus_at(grid, grid, Sp, Sl)[0], Sp, rtol=1e-13)
    na, nb = ve.modulus_at(-w, grid, Sp, Sl)
    np.testing.assert_array_equal(na, a)
    np.testing.assert_array_equal(nb, -b)


def test_extrapolation_follows_the_physical_asymptotes():
    grid = np.geomspace(1.0, 1e4, 41)
    Sp = np.linspace(1e6, 1e9, grid.size)
    Sl = np.linspace(1e5, 1e8, grid.size)
    low = np.array([1e-6, 1e-3])
    high = np.array([1e6, 1e9])
    a, b = ve.modulus_at(low, grid, Sp, Sl)
    np.testing.assert_allclose(a, Sp[0])
    np.testing.assert_allclose(b, Sl[0] * low / grid[0])
    a, b = ve.modulus_at(high, grid, Sp, Sl)
    np.testing.assert_allclose(a, Sp[-1])
    np.testing.assert_allclose(b, Sl[-1] * grid[-1] / high)


# ----------------------------------------------------------------------------------------
# Temperature: WLF identity, tables, vertical shift
# ----------------------------------------------------------------------------------------


def test_wlf_identity_through_the_stage(tmp_path):
    """E(omega, T) = E(omega a_T, T_ref): the stage's modulus at T equals its modulus at T_ref
    evaluated at the reduced frequency."""
    spec = dict(BOX, T_ref="-40 degC", T=["-40 degC", "-20 degC", "25 degC", "80 degC"], shift="wlf", C2="51.6 K")
    ds = _modulus(spec, tmp_path)
    aT = ds["shift_factor"].values
    assert aT[0] == 1.0 and np.all(np.diff(aT) < 0)  # hotter relaxes faster
    grid = ds["omega"].values
    ref_p, ref_l = ds["storage_modulus"].values[0], ds["loss_modulus"].values[0]
    for i in range(1, aT.size):
        reduced = grid * aT[i]
        inside = (reduced > grid[0]) & (reduced < grid[-1])
        a, b = ve.modulus_at(reduced[inside], grid, ref_p, ref_l)
        np.testing.assert_allclose(ds["storage_modulus"].values[i][inside], a, rtol=3e-5)
        np.testing.assert_allclose(ds["loss_modulus"].values[i][inside], b, rtol=3e-5)


def test_entropic_vertical_shift_scales_by_T_over_Tref(tmp_path):
    spec = dict(BOX, T_ref="300 K", T=["300 K", "330 K"], shift="wlf", C2="51.6 K", vertical_shift="entropic")
    plain = _modulus({**spec, "vertical_shift": "none"}, tmp_path / "a")
    shifted = _modulus(spec, tmp_path / "b")
    np.testing.assert_allclose(shifted["storage_modulus"].values[1], plain["storage_modulus"].values[1] * 1.1,
                               rtol=1e-13)
    np.testing.assert_allclose(shifted["vertical_shift_factor"].values, [1.0, 1.1], rtol=1e-13)


def test_shift_table_interpolates_log10_aT_linearly(tmp_path):
    spec = dict(BOX, T_ref="0 degC", T=["0 degC", "5 degC"], shift="table",
                shift_T=["-10 degC", "0 degC", "10 degC"], shift_log10_aT=[2.0, 0.0, -3.0])
    ds = _modulus(spec, tmp_path)
    np.testing.assert_allclose(np.log10(ds["shift_factor"].values), [0.0, -1.5], atol=1e-12)


# ----------------------------------------------------------------------------------------
# NetCDF round trip of the complex modulus
# ----------------------------------------------------------------------------------------


def test_complex_modulus_survives_netcdf_round_trip(tmp_path):
    import netCDF4

    spec = dict(BOX, T_ref="-40 degC", T=["-40 degC", "25 degC"], shift="wlf", C2="51.6 K")
    ds = rc.compute(_raw(spec, numerics={"modulus_points_per_decade": 20}), outputs="modulus",
                    progress=False)["base"]["modulus"]
    before = md.complex_modulus(ds)
    path = tmp_path / "modulus.nc"
    store.write(ds, path)
    after = md.complex_modulus(store.open_result(path))
    assert after.dtype == np.complex128
    np.testing.assert_array_equal(after.values, before.values)
    np.testing.assert_array_equal(after["omega"].values, before["omega"].values)
    with netCDF4.Dataset(path) as nc:  # stored as plain real variables: readable anywhere
        assert nc["storage_modulus"].dtype == np.float64 and nc["loss_modulus"].dtype == np.float64


# ----------------------------------------------------------------------------------------
# Measured master curves
# ----------------------------------------------------------------------------------------


def _write(path, text):
    path.write_text(text)
    return path


def _power_law_file(path, header="# f [Hz]  E' [MPa]  E'' [MPa]"):
    f = np.geomspace(1e-2, 1e6, 9)
    lines = [header] + [f"{x:.17g}  {3.0 * (x / 1e-2) ** 0.1:.17g}  {0.5 * (x / 1e-2) ** 0.3:.17g}" for x in f]
    return _write(path, "\n".join(lines) + "\n")


def test_master_curve_file_is_interpolated_in_log_log_and_extrapolated_physically(tmp_path):
    path = _power_law_file(tmp_path / "curve.txt")
    with pytest.warns(UserWarning, match="extrapolated"):
        ds = _modulus({"kind": "file", "path": str(path), "T_ref": "25 degC"}, tmp_path)
    w = ds["omega"].values
    f = w / (2 * np.pi)  # Hz column: omega = 2 pi f
    inside = (f >= 1e-2) & (f <= 1e6)
    np.testing.assert_allclose(ds["storage_modulus"].values[inside], 3e6 * (f[inside] / 1e-2) ** 0.1, rtol=1e-12)
    np.testing.assert_allclose(ds["loss_modulus"].values[inside], 0.5e6 * (f[inside] / 1e-2) ** 0.3, rtol=1e-12)
    below, above = f < 1e-2, f > 1e6
    np.testing.assert_allclose(ds["storage_modulus"].values[below], 3e6, rtol=1e-12)
    np.testing.assert_allclose(ds["loss_modulus"].values[below], 0.5e6 * f[below] / 1e-2, rtol=1e-12)
    Epp_top = 0.5e6 * (1e8) ** 0.3
    np.testing.assert_allclose(ds["loss_modulus"].values[above], Epp_top * 1e6 / f[above], rtol=1e-12)
    assert "0.06283" in ds.attrs["extrapolation"] and "E'' ~ omega" in ds.attrs["extrapolation"]


def test_master_curve_with_tan_delta_and_units_from_the_scene(tmp_path):
    path = _write(tmp_path / "c.csv", "1, 2.0, 0.5\n10, 4.0, 0.25\n100, 8.0, 0.125\n")
    with pytest.warns(UserWarning, match="extrapolated"):
        ds = _modulus({"kind": "file", "path": str(path), "T_ref": "25 degC", "loss_column": "tan_delta",
                       "frequency_unit": "rad/s", "modulus_unit": "MPa"}, tmp_path)
    w = ds["omega"].values
    inside = (w >= 1) & (w <= 100)
    np.testing.assert_allclose(ds["storage_modulus"].values[inside], 2e6 * w[inside] ** np.log10(2), rtol=1e-12)
    np.testing.assert_allclose(ds["loss_modulus"].values[inside], 1e6 * np.ones(inside.sum()), rtol=1e-12)


@pytest.mark.parametrize(
    "body, line, words",
    [
        ("1 1 0.1\n3 1 0.1\n2 1 0.1\n", 4, "not strictly increasing"),
        ("1 1 0.1\n2 -1 0.1\n3 1 0.1\n", 3, "E'"),
        ("1 1 0.1\n2 1 0.1\n3 1 -0.1\n", 4, "E''"),
        ("1 1 0.1\n2 nan 0.1\n3 1 0.1\n", 3, "NaN"),
        ("1 1 0.1\n2 1 0.1\n2 1 0.1\n", 4, "not strictly increasing"),
    ],
)
def test_bad_master_curve_names_file_and_line(tmp_path, body, line, words):
    path = _write(tmp_path / "bad.txt", "# f [Hz]  E' [MPa]  E'' [MPa]\n" + body)
    with pytest.raises(UserError) as err:
        _modulus({"kind": "file", "path": str(path), "T_ref": "25 degC"}, tmp_path)
    assert err.value.file == str(path) and err.value.key == f"line {line}"
    assert words in err.value.message


def test_master_curve_without_units_is_a_user_error(tmp_path):
    path = _write(tmp_path / "nounits.txt", "1 1 0.1\n2 1 0.1\n")
    with pytest.raises(UserError) as err:
        _modulus({"kind": "file", "path": str(path), "T_ref": "25 degC"}, tmp_path)
    assert err.value.file == str(path) and err.value.key == "modulus.frequency_unit"
    path = _write(tmp_path / "half.txt", "# f [Hz]  E'  E''\n1 1 0.1\n2 1 0.1\n")
    with pytest.raises(UserError) as err:
        _modulus({"kind": "file", "path": str(path), "T_ref": "25 degC"}, tmp_path)
    assert err.value.key == "modulus.modulus_unit"


def test_cli_bad_master_curve_exits_2_and_writes_nothing(tmp_path, capsys):
    curve = _write(tmp_path / "bad.txt", "# f [Hz]  E' [MPa]  E'' [MPa]\n1 1 0.1\n3 1 0.1\n2 1 0.1\n")
    scene = _write(tmp_path / "scene.toml", f"""
[substrate]
kind = "self_affine"
H = 0.8
qL = "1e4 1/m"
q1 = "1e6 1/m"
hrms = "1 um"
[material]
E = "5 MPa"
nu = 0.5
[load]
p = "0.4 MPa"
[modulus]
kind = "file"
path = "{curve.name}"
T_ref = "25 degC"
[outputs]
variables = ["friction_coefficient"]
""")
    out = tmp_path / "out"
    assert cli.main(["run", str(scene), "--outdir", str(out), "--quiet"]) == 2
    message = capsys.readouterr().err
    assert "bad.txt" in message and "line 4" in message
    assert not out.exists() or not any(out.rglob("*.nc"))  # nothing written


# ----------------------------------------------------------------------------------------
# Scene validation
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "modulus, key",
    [
        (dict(BOX, tau1="1 s", tau2="1e-3 s"), "modulus.tau2"),
        (dict(BOX, E_inf="1 MPa"), "modulus.E_inf"),
        (dict(BOX, shift="wlf", T_ref="0 degC", T="-60 degC"), "modulus.T"),
        (dict(BOX, shift="wlf"), "modulus.T_ref"),
        ({"kind": "prony", "E0": "1 MPa", "prony_E": ["1 MPa", "2 MPa"], "prony_tau": ["1 s"]}, "modulus.prony_tau"),
        (dict(BOX, shift="table", T_ref="0 degC", T="50 degC", shift_T=["-10 degC", "10 degC"],
              shift_log10_aT=[1.0, -1.0]), "modulus.T"),
    ],
)
def test_inconsistent_modulus_section_names_the_key(modulus, key):
    with pytest.raises(UserError) as err:
        scenes.from_dict(_raw(modulus))
    assert err.value.key == key
