"""PSD stage: generated spectra carry the requested roughness; the pair combination obeys eq 52."""

import json

import numpy as np
import pytest
import xarray as xr
from conftest import SURFACE, make_scene
from hypothesis import given, settings, strategies as st

from roughcontact.errors import UserError
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.spectra import (
    CONVENTIONS,
    hrms_from_psd,
    psd_combined,
    self_affine_hrms_factor,
    self_affine_psd,
)


@pytest.mark.parametrize("q0", [None, "1e9 1/m"])
@pytest.mark.parametrize("H", [0.05, 0.5, 0.8, 1.0])
def test_hrms_of_generated_psd_matches_request(run_scene, q0, H):
    surf = dict(SURFACE, H=H, hrms="1.7 nm")
    if q0:
        surf["q0"] = q0
    res = run_scene(make_scene(substrate=surf, solid=None, outputs={"variables": ["psd_combined"]}))
    psd = res["base"]["psd"]
    assert float(psd["hrms_combined"]) == pytest.approx(1.7e-9, rel=1e-6)


def test_hrms_factor_is_stable_at_small_H():
    # (1 - (q0/q1)^(2H)) / H -> 2 ln(q1/q0) as H -> 0
    f = self_affine_hrms_factor(1e-9, 1.0, 1.0, 1e3)
    assert f == pytest.approx(np.pi * 2 * np.log(1e3), rel=1e-6)


def test_uncorrelated_identical_surfaces_equal_one_surface_with_sqrt2_hrms(run_scene, tmp_path):
    pair = run_scene(make_scene(interface={"eta": 0.0}), outdir=tmp_path / "pair")
    single = run_scene(make_scene(substrate=dict(SURFACE, hrms=f"{np.sqrt(2)} nm"), solid=None),
                       outdir=tmp_path / "one")
    a = pair["base"]["psd"]["psd_combined"].values
    b = single["base"]["psd"]["psd_combined"].values
    assert np.allclose(a, b, rtol=1e-12, atol=0)
    assert np.allclose(pair["base"]["contact"]["contact_area_ratio"], single["base"]["contact"]["contact_area_ratio"],
                       rtol=1e-12)


def test_fully_correlated_identical_surfaces_give_exactly_zero_and_full_contact(run_scene):
    res = run_scene(make_scene(interface={"eta": 1.0}))
    assert np.all(res["base"]["psd"]["psd_combined"].values == 0.0)
    assert np.all(res["base"]["contact"]["contact_area_ratio"].values == 1.0)


@given(c1=st.floats(0, 1e-30), c2=st.floats(0, 1e-30), eta=st.floats(-1, 1))
@settings(max_examples=200, deadline=None)
def test_combined_psd_is_non_negative_and_equals_eq52(c1, c2, eta):
    c = psd_combined(c1, c2, eta)
    assert c >= 0.0
    assert c == pytest.approx(c1 + c2 - 2 * eta * np.sqrt(c1) * np.sqrt(c2), abs=1e-12 * (c1 + c2) + 1e-300)


def test_minimum_of_combined_psd_is_at_eta_squared_c2():
    # docs/theory.md: the seed's eq 66 (C1 = eta C2) is a misprint; the minimum is at C1 = eta^2 C2.
    c2, eta = 1.0, 0.6
    c1 = np.linspace(0, 1, 100001)
    assert c1[np.argmin(psd_combined(c1, c2, eta))] == pytest.approx(eta**2 * c2, abs=1e-4)


def test_same_band_pair_hrms_follows_the_coherence_rule(run_scene):
    res = run_scene(make_scene(solid=dict(SURFACE, hrms="0.6 nm"), interface={"eta": [-1.0, -0.3, 0.0, 0.5, 1.0]},
                               outputs={"variables": ["psd_combined"]}))
    eta = res["base"]["psd"]["eta"].values
    h = res["base"]["psd"]["hrms_combined"].values
    expected = np.sqrt(1.0 + 0.36 - 2 * eta * 0.6) * 1e-9
    assert np.allclose(h, expected, rtol=1e-6)


def test_hrms_sweep_becomes_a_dimension(run_scene):
    res = run_scene(make_scene(substrate=dict(SURFACE, hrms=["0.5 nm", "1 nm", "2 nm"]), solid=None,
                               outputs={"variables": ["psd_combined"]}))
    psd = res["base"]["psd"]
    assert "hrms_substrate" in psd["psd_combined"].dims
    assert np.allclose(psd["hrms_combined"].values, psd["hrms_substrate"].values, rtol=1e-6)


def _write_table(path, q, c, header="# q [1/m]  C [m^4]"):
    lines = [header] + [f"{a:.17g} {b:.17g}" for a, b in zip(q, c, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _profile_psd(q, H, A):
    """C1D(q) = 2 pi int dq_y C(sqrt(q^2 + q_y^2)) for an unbounded power law C = A q^(-2(1+H)),
    by quadrature (independent of the closed form the stage uses)."""
    from scipy import integrate

    f = lambda qy, qx: A * (qx * qx + qy * qy) ** (-(1 + H))  # noqa: E731
    return np.array([2 * 2 * np.pi * integrate.quad(f, 0, np.inf, args=(qx,), epsrel=1e-12)[0] for qx in q])


def _profile_psd_persson(q, H, A):
    """Persson's 1D convention, C1D_P(q) = int dq_y C(sqrt(q^2 + q_y^2)) over the whole line (so that
    hrms^2 = int d^2q C = 2 int_0^inf C1D_P dq), for C = A q^(-2(1+H)), by quadrature."""
    from scipy import integrate

    f = lambda qy, qx: A * (qx * qx + qy * qy) ** (-(1 + H))  # noqa: E731
    return np.array([2 * integrate.quad(f, 0, np.inf, args=(qx,), epsrel=1e-12)[0] for qx in q])


@pytest.mark.parametrize("convention, H", [("persson", 0.8), ("contact.engineering", 0.8), ("1d", 0.5), ("1d", 0.8),
                                          ("1d_persson", 0.5), ("1d_persson", 0.8)])
def test_measured_psd_file_conventions_convert_to_persson(run_scene, tmp_path, convention, H):
    q = log_grid(1e8, 1e11, 40)
    A = 1e-36 * 1e8 ** (2 * (1 + H))
    C = A * q ** (-2 * (1 + H))
    given = {"persson": C, "contact.engineering": C * (2 * np.pi) ** 2, "1d": _profile_psd(q, H, A),
             "1d_persson": _profile_psd_persson(q, H, A)}[convention]
    unit = "m^3" if convention.startswith("1d") else "m^4"
    path = _write_table(tmp_path / "psd.txt", q, given, header=f"# q [1/m]  C [{unit}]")
    surf = {"kind": "psd_file", "path": str(path), "convention": convention, "hurst": H}
    res = run_scene(make_scene(substrate=surf, solid=None, grid={"q_min": "2e8 1/m", "q_max": "4e10 1/m"},
                               outputs={"variables": ["psd_combined"]}))
    psd = res["base"]["psd"]
    expected = A * psd["q"].values ** (-2 * (1 + H))
    assert np.allclose(psd["psd_substrate"].values, expected, rtol=1e-8)
    assert convention in psd["psd_substrate"].attrs["psd_convention"]
    # the file records the conversion that was applied, and only that one
    assert psd["psd_substrate"].attrs["conversion"] == CONVENTIONS[convention][1]
    assert len({text for _, text in CONVENTIONS.values()}) == len(CONVENTIONS)


def test_measured_psd_units_from_scene_and_header_agree(run_scene, tmp_path):
    q = log_grid(1e8, 1e11, 10)
    C = self_affine_psd(q, 0.8, 1e8, 1e8, 1e11, 1e-36)
    a = _write_table(tmp_path / "a.txt", q * 1e-6, C * 1e24, header="# q [1/um]  C [um^4]")
    b = _write_table(tmp_path / "b.txt", q, C, header="q C")
    grid = {"q_min": "2e8 1/m", "q_max": "4e10 1/m"}
    ra = run_scene(make_scene(substrate={"kind": "psd_file", "path": str(a)}, solid=None, grid=grid),
                   outdir=tmp_path / "a")
    rb = run_scene(make_scene(substrate={"kind": "psd_file", "path": str(b), "q_unit": "1/m", "C_unit": "m^4"},
                              solid=None, grid=grid), outdir=tmp_path / "b")
    assert np.allclose(ra["base"]["psd"]["psd_substrate"], rb["base"]["psd"]["psd_substrate"], rtol=1e-12)


def test_psd_file_outside_range_needs_an_extension_rule(run_scene, tmp_path):
    q = log_grid(1e9, 1e10, 10)
    path = _write_table(tmp_path / "psd.txt", q, 1e-36 * (q / 1e9) ** -3.6)
    surf = {"kind": "psd_file", "path": str(path)}
    only_psd = {"variables": ["psd_combined"]}
    with pytest.raises(UserError, match="extend"):
        run_scene(make_scene(substrate=surf, solid=None, grid={"q_min": "2e8 1/m"}, outputs=only_psd))
    res = run_scene(make_scene(substrate=dict(surf, extend="power_law"), solid=None, grid={"q_min": "2e8 1/m"},
                               outputs=only_psd))
    psd = res["base"]["psd"]
    assert np.allclose(psd["psd_substrate"].values, 1e-36 * (psd["q"].values / 1e9) ** -3.6, rtol=1e-9)


def test_netcdf_psd_from_an_earlier_run_is_accepted_with_its_provenance(run_scene, tmp_path):
    first = run_scene(make_scene(solid=None, interface={"eta": 0.0}), outdir=tmp_path / "first")
    nc = tmp_path / "first" / "psd.nc"
    ds = xr.open_dataset(nc)
    ds[["psd_substrate"]].to_netcdf(tmp_path / "collab.nc")
    with xr.open_dataset(tmp_path / "collab.nc") as check:
        assert "stage_key" in check.attrs
    res = run_scene(make_scene(substrate={"kind": "psd_file", "path": str(tmp_path / "collab.nc")}, solid=None),
                    outdir=tmp_path / "second")
    psd = res["base"]["psd"]
    assert np.allclose(psd["psd_substrate"].values, first["base"]["psd"]["psd_substrate"].values, rtol=1e-12)
    carried = json.loads(psd["psd_substrate"].attrs["source_provenance"])
    assert carried["stage_key"] == first["base"]["psd"].attrs["stage_key"]
    ds.close()


def test_kernel_hrms_of_power_law_band():
    q = log_grid(1e5, 1e9, 30, knots=[1e6])
    C = self_affine_psd(q, 0.7, 1e5, 1e6, 1e9, 1.0)
    assert hrms_from_psd(q, C) ** 2 == pytest.approx(self_affine_hrms_factor(0.7, 1e5, 1e6, 1e9), rel=1e-12)
