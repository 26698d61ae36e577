"""Master curves from DMA sweeps (modulus source ``dma``; physics/mastercurve.py, pipeline/dma.py).

Synthetic sweeps are made from a known relaxation spectrum shifted by a known WLF law (and
optionally a known vertical shift), with 1 % multiplicative noise: the construction must give back
C1 and C2 (within 2 %), the shifts and the modulus; a data set whose E' does not follow from its
E'' must be flagged naming the temperature; bad files must give one-line errors naming the file
and the line.
"""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact import engine, scene as scenes
from roughcontact.cli import main
from roughcontact.errors import UserError
from roughcontact.physics import mastercurve as mc, viscoelastic as ve

QUIET = engine.Reporter(None)

#: the known material: a log-normal relaxation spectrum (glassy ~3 GPa, rubbery 5 MPa) and WLF about 0 degC
TAU = np.logspace(-12, 4, 49)
STRENGTH = 3e9 / 49 * 2.5 * np.exp(-0.5 * ((np.log10(TAU) + 5) / 3.0) ** 2)
E_RELAXED = 5e6
C1, C2, T_REF = 10.0, 60.0, 273.15


FREQS = np.logspace(-1, 2, 13)  # Hz, the frequencies of each synthetic sweep


def sweeps(temps_C, noise=0.01, seed=1, vertical=False, freqs=FREQS):
    """(T (K) per point, sweep index, omega (rad/s), E', E'' (Pa)) of synthetic DMA sweeps."""
    rng = np.random.default_rng(seed)
    T = np.repeat(273.15 + np.asarray(temps_C, float), freqs.size)
    sweep = np.repeat(np.arange(len(temps_C)), freqs.size)
    omega = np.tile(2 * np.pi * freqs, len(temps_C))
    aT = 10.0 ** ve.wlf_log10_shift(T, T_REF, C1, C2)
    Ep, Epp = ve.prony_modulus(omega * aT, E_RELAXED, STRENGTH, TAU)
    b = T / T_REF if vertical else 1.0
    Ep, Epp = b * Ep, b * Epp
    return (T, sweep, omega, Ep * (1 + noise * rng.standard_normal(Ep.size)),
            Epp * (1 + noise * rng.standard_normal(Ep.size)))


def write_dma(path, T, omega, Ep, Epp, header="# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]"):
    rows = [header] + [f"{t - 273.15:.3f} {w / (2 * np.pi):.6g} {a / 1e6:.8g} {b / 1e6:.8g}"
                       for t, w, a, b in zip(T, omega, Ep, Epp, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return path


# ----------------------------------------------------------------------------------------
# Kernels: recovery of the WLF constants and shifts
# ----------------------------------------------------------------------------------------


#: overlapping sweeps (each 3 decades, shifted by less than that between neighbours), and a set with gaps
FIVE, TEN, GAPPED = np.arange(-10, 31, 10.0), np.arange(-10, 81, 10.0), np.arange(-20, 61, 20.0)


@pytest.mark.parametrize("temps", [FIVE, TEN, GAPPED], ids=["5 T", "10 T", "5 T with gaps"])
@pytest.mark.parametrize("seed", [1, 2])
def test_wlf_fit_recovers_C1_C2_within_2_percent(temps, seed):
    T, sweep, w, Ep, Epp = sweeps(temps, seed=seed)
    fit = mc.build_master_curve(np.unique(T), sweep, w, Ep, Epp, T_REF, method="wlf")
    assert fit.C1 == pytest.approx(C1, rel=0.02)
    assert fit.C2 == pytest.approx(C2, rel=0.02)
    true = ve.wlf_log10_shift(np.unique(T), T_REF, C1, C2)
    np.testing.assert_allclose(fit.log10_aT, true, rtol=0.01, atol=0.02)
    assert np.all(fit.residual < 0.01)  # decades: 1 % noise is 0.004 decades


@pytest.mark.parametrize("temps", [FIVE, TEN], ids=["5 T", "10 T"])
@pytest.mark.parametrize("seed", [1, 2])
def test_free_shifts_follow_the_true_shifts_and_wlf_fits_them(temps, seed):
    """One shift per sweep (needs overlapping sweeps), then WLF fitted to them."""
    T, sweep, w, Ep, Epp = sweeps(temps, seed=seed)
    fit = mc.build_master_curve(np.unique(T), sweep, w, Ep, Epp, T_REF, method="free")
    true = ve.wlf_log10_shift(np.unique(T), T_REF, C1, C2)
    np.testing.assert_allclose(fit.log10_aT, true, atol=0.03)
    assert fit.C1 == pytest.approx(C1, rel=0.02) and fit.C2 == pytest.approx(C2, rel=0.02)
    assert np.max(np.abs(fit.wlf_residual)) < 0.03


def test_vertical_shifts_recover_the_entropic_factor():
    T, sweep, w, Ep, Epp = sweeps(TEN, vertical=True)
    temps = np.unique(T)
    fit = mc.build_master_curve(temps, sweep, w, Ep, Epp, T_REF, method="wlf", vertical=True)
    np.testing.assert_allclose(fit.log10_bT, np.log10(temps / T_REF), atol=0.01)
    assert fit.C1 == pytest.approx(C1, rel=0.03) and fit.C2 == pytest.approx(C2, rel=0.03)


def test_wlf_fit_of_exact_shifts_is_exact_and_moves_with_the_reference():
    """fit_wlf on exact shifts returns the constants; about another T_ref it returns the
    transformed constants C2' = C2 + T_ref' - T_ref, C1' = C1 C2 / C2' (the same law)."""
    T = 273.15 + np.arange(-30, 61, 10.0)
    L = ve.wlf_log10_shift(T, T_REF, C1, C2)
    c1, c2, res = mc.fit_wlf(T, L, T_REF)
    assert c1 == pytest.approx(C1, rel=1e-8) and c2 == pytest.approx(C2, rel=1e-8)
    c1, c2, _ = mc.fit_wlf(T, L - L[5], T[5], anchor=5)
    assert c2 == pytest.approx(C2 + T[5] - T_REF, rel=1e-7)
    assert c1 == pytest.approx(C1 * C2 / (C2 + T[5] - T_REF), rel=1e-7)


def test_prony_fit_reproduces_the_master_curve():
    T, sweep, w, Ep, Epp = sweeps(np.arange(-30, 61, 10.0), noise=0.0)
    reduced = w * 10.0 ** ve.wlf_log10_shift(T, T_REF, C1, C2)
    E0, moduli, residual = mc.fit_prony(reduced, Ep, Epp, mc.relaxation_times(reduced, 4))
    assert residual < 0.01 and np.all(moduli >= 0) and E0 >= 0


# ----------------------------------------------------------------------------------------
# Kramers-Kronig
# ----------------------------------------------------------------------------------------


def test_causal_data_pass_and_noncausal_data_are_far_off():
    T, sweep, w, Ep, Epp = sweeps(np.arange(-30, 61, 10.0))
    reduced = w * 10.0 ** ve.wlf_log10_shift(T, T_REF, C1, C2)
    times = mc.relaxation_times(reduced, 4)
    rms = lambda d: np.array([np.sqrt(np.mean(d[sweep == j] ** 2)) for j in range(10)])  # noqa: E731
    _, good = mc.kramers_kronig_deviation(reduced, Ep, Epp, times, sweep)
    assert np.all(rms(good) < 0.03)
    flat = np.full_like(Ep, 5e7)  # E' without dispersion, though E'' shows strong loss: not causal
    _, bad = mc.kramers_kronig_deviation(reduced, flat, Epp, times, sweep)
    assert np.max(rms(bad)) > 1.0


# ----------------------------------------------------------------------------------------
# The modulus stage with kind = "dma"
# ----------------------------------------------------------------------------------------


def _scene(path, **modulus):
    return {
        "name": "dma",
        "substrate": {"kind": "self_affine", "H": 0.8, "qL": "1e4 1/m", "q1": "1e6 1/m", "hrms": "1 um"},
        "material": {"E": "5 MPa", "nu": 0.5},
        "load": {"p": "0.4 MPa"},
        "modulus": {"kind": "dma", "sweeps": str(path), "T_ref": "0 degC", "T": "20 degC", **modulus},
        "outputs": {"variables": ["storage_modulus", "sweep_log10_aT"]},
    }


def _run(raw, tmp_path):
    sc = scenes.from_dict(raw, tmp_path / "scene.toml")
    return engine.run(sc, tmp_path / "out", report=QUIET)["base"]["modulus"]


def test_stage_builds_the_master_curve_from_a_file(tmp_path):
    T, sweep, w, Ep, Epp = sweeps(TEN)
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    mod = _run(_scene(path), tmp_path)
    assert float(mod["wlf_C1"]) == pytest.approx(C1, rel=0.02)
    assert float(mod["wlf_C2"]) == pytest.approx(C2, rel=0.02)
    assert float(mod["reference_temperature"]) == pytest.approx(T_REF)
    # the stored modulus at 20 degC is the true one (within the noise) over the measured range
    aT = 10.0 ** ve.wlf_log10_shift(293.15, T_REF, C1, C2)
    lo = 2 * np.pi * 0.1 * 10 ** ve.wlf_log10_shift(353.15, T_REF, C1, C2)
    hi = 2 * np.pi * 100 * 10 ** ve.wlf_log10_shift(263.15, T_REF, C1, C2)
    inside = ((mod["omega"] * aT > lo) & (mod["omega"] * aT < hi)).values
    assert inside.sum() > 100
    true, true_loss = ve.prony_modulus(mod["omega"].values[inside] * aT, E_RELAXED, STRENGTH, TAU)
    np.testing.assert_allclose(mod["storage_modulus"].values[inside], true, rtol=0.03)
    np.testing.assert_allclose(mod["loss_modulus"].values[inside], true_loss, rtol=0.05)
    assert mod.attrs["horizontal_shift"] == "wlf"
    assert mod["sweep_kk_deviation"].max() < 0.05


def test_stage_flags_a_noncausal_set_naming_the_temperature(tmp_path):
    T, sweep, w, Ep, Epp = sweeps(FIVE)
    Ep = np.where(sweep == 3, Ep[sweep == 3].min(), Ep)  # flat E' in the 20 degC sweep
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    with pytest.warns(UserWarning, match=r"Kramers-Kronig .* T = .*20 °C"):
        _run(_scene(path), tmp_path)


def test_shift_keys_are_refused_with_the_dma_source(tmp_path):
    T, sweep, w, Ep, Epp = sweeps(np.arange(-20, 61, 20.0))
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    with pytest.raises(UserError) as err:
        scenes.from_dict(_scene(path, shift="wlf"), tmp_path / "scene.toml")
    assert err.value.key == "modulus.shift"


# ----------------------------------------------------------------------------------------
# Bad files: one line naming the file and the line
# ----------------------------------------------------------------------------------------

GOOD = ["# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]", "0 0.1 10 1", "0 1 12 1.5", "0 10 15 2",
        "20 0.1 8 0.8", "20 1 9 1.0", "20 10 11 1.3"]


@pytest.mark.parametrize("lines, message, line", [
    (GOOD[:4], "only one temperature", "line 2"),
    (GOOD[:2] + ["0 10 15 2", "0 1 12 1.5"] + GOOD[4:], "frequencies not sorted", "line 4"),
    (GOOD[:5] + ["20 1 -9 1.0"] + GOOD[6:], "storage modulus E' must be positive", "line 6"),
    (GOOD[:3] + ["0 10 15 -2"] + GOOD[4:], "loss modulus E'' must be >= 0", "line 4"),
    (["# T  f  E'  E''"] + GOOD[1:], "unit of the temperature column unknown", None),
    (GOOD[:3] + ["0 nan 15 2"] + GOOD[4:], "frequency is NaN", "line 4"),
    (["# T [m]  f [Hz]  E' [MPa]  E'' [MPa]"] + GOOD[1:], "the file gives the temperature the unit 'm'", "line 1"),
])
def test_bad_dma_files_give_one_line_naming_file_and_line(tmp_path, capsys, lines, message, line):
    path = tmp_path / "bad.txt"
    path.write_text("\n".join(lines) + "\n")
    scene = tmp_path / "scene.toml"
    scene.write_text(
        'name = "bad"\n[substrate]\nkind = "self_affine"\nH = 0.8\nqL = "1e4 1/m"\nq1 = "1e6 1/m"\nhrms = "1 um"\n'
        '[material]\nE = "5 MPa"\nnu = 0.5\n[load]\np = "0.4 MPa"\n'
        f'[modulus]\nkind = "dma"\nsweeps = "{path.name}"\n[outputs]\nvariables = ["storage_modulus"]\n')
    code = main(["run", str(scene), "--outdir", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(path) in err and message in err
    assert line is None or f":{line}:" in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.nc"))


def test_dma_and_master_curve_tables_read_tan_delta_through_the_stages_kernel(tmp_path):
    """The one moduli reader: tan delta becomes E'' = E' tan delta through the function the stage
    passes (physics), the same in a DMA file and a master curve; without it the reader refuses."""
    from roughcontact.readers import READERS

    rows = [line.split() for line in GOOD[1:]]
    tan = [f"{r[0]} {r[1]} {r[2]} {float(r[3]) / float(r[2]):.17g}" for r in rows]
    dma = tmp_path / "tan.txt"
    dma.write_text("# T [degC]  f [Hz]  E' [MPa]  tan delta\n" + "\n".join(tan) + "\n")
    curve = tmp_path / "curve.txt"
    curve.write_text("# f [Hz]  E' [MPa]  tan delta\n" + "\n".join(" ".join(t.split()[1:]) for t in tan[:3]) + "\n")
    kernel = ve.loss_modulus_from_tan_delta
    sweeps = READERS["dma"](dma, loss_column="tan_delta", loss_from_tan_delta=kernel)
    master = READERS["master_curve"](curve, loss_column="tan_delta", loss_from_tan_delta=kernel)
    np.testing.assert_allclose(np.sort(sweeps.loss), np.sort([float(r[3]) * 1e6 for r in rows]), rtol=1e-12)
    np.testing.assert_array_equal(master.loss, sweeps.loss[:3])
    with pytest.raises(TypeError, match="loss_from_tan_delta"):
        READERS["dma"](dma, loss_column="tan_delta")
