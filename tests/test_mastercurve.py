"""Master curves from DMA sweeps (modulus source ``dma``; physics/mastercurve.py,
physics/relaxation_spectrum.py, pipeline/dma.py).

Synthetic sweeps are made from a known relaxation spectrum shifted by a known WLF law (and
optionally a known vertical shift), with 1 % multiplicative noise: the construction must give back
C1 and C2 (within 2 %), the shifts and the modulus; a data set whose E' does not follow from its
E'' must be flagged naming the temperature; bad files must give one-line errors naming the file
and the line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from roughcontact import engine, scene as scenes
from roughcontact.cli import main
from roughcontact.errors import UserError
from roughcontact.physics import mastercurve as mc, relaxation_spectrum as rs, viscoelastic as ve

QUIET = engine.Reporter(None)

#: the known material: a log-normal relaxation spectrum (glassy ~3 GPa, rubbery 5 MPa) and WLF about 0 degC
TAU = np.logspace(-12, 4, 49)
STRENGTH = 3e9 / 49 * 2.5 * np.exp(-0.5 * ((np.log10(TAU) + 5) / 3.0) ** 2)
E_RELAXED = 5e6
C1, C2, T_REF = 10.0, 60.0, 273.15


FREQS = np.logspace(-1, 2, 13)


def sweeps(temps_C, noise=0.01, seed=1, vertical=False, freqs=FREQS, law=None):
    """(T (K) per point, sweep index, omega (rad/s), E', E'' (Pa)) of synthetic DMA sweeps; ``law``:
    T -> log10 a_T (default WLF with C1, C2 about T_REF)."""
    rng = np.random.default_rng(seed)
    T = np.repeat(273.15 + np.asarray(temps_C, float), freqs.size)
    sweep = np.repeat(np.arange(len(temps_C)), freqs.size)
    omega = np.tile(2 * np.pi * freqs, len(temps_C))
    aT = 10.0 ** (law(T) if law is not None else ve.wlf_log10_shift(T, T_REF, C1, C2))
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
    E0, moduli, residual = rs.fit_prony(reduced, Ep, Epp, rs.relaxation_times(reduced, 4))
    assert residual < 0.01 and np.all(moduli >= 0) and E0 >= 0


# ----------------------------------------------------------------------------------------
# Kramers-Kronig
# ----------------------------------------------------------------------------------------


def test_causal_data_pass_and_noncausal_data_are_far_off():
    T, sweep, w, Ep, Epp = sweeps(np.arange(-30, 61, 10.0))
    reduced = w * 10.0 ** ve.wlf_log10_shift(T, T_REF, C1, C2)
    times = rs.relaxation_times(reduced, 4)
    rms = lambda d: np.array([np.sqrt(np.mean(d[sweep == j] ** 2)) for j in range(10)])  # noqa: E731
    _, good = rs.kramers_kronig_deviation(reduced, Ep, Epp, times, sweep)
    assert np.all(rms(good) < 0.03)
    flat = np.full_like(Ep, 5e7)  # E' without dispersion, though E'' shows strong loss: not causal
    _, bad = rs.kramers_kronig_deviation(reduced, flat, Epp, times, sweep)
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


# ----------------------------------------------------------------------------------------
# Overlap shifts on a glassy plateau; instrument files; two temperatures; long sweeps
# ----------------------------------------------------------------------------------------

#: a spectrum of long times only: the cold sweeps sit on the glassy plateau (E' flat within 5 %)
GLASSY_TAU = np.logspace(0, 7, 29)
GLASSY_STRENGTH = 2e9 / 29 * 2.5 * np.exp(-0.5 * ((np.log10(GLASSY_TAU) - 3.5) / 1.5) ** 2)
GLASSY_T = np.array([-18.0, -12, -6, 0, 10, 20, 30, 40, 50, 60])


def glassy_sweeps(seed, freqs=FREQS):
    rng = np.random.default_rng(seed)
    T = np.repeat(273.15 + GLASSY_T, freqs.size)
    sweep = np.repeat(np.arange(GLASSY_T.size), freqs.size)
    omega = np.tile(2 * np.pi * freqs, GLASSY_T.size)
    Ep, Epp = ve.prony_modulus(omega * 10.0 ** ve.wlf_log10_shift(T, T_REF, C1, C2), 5e6, GLASSY_STRENGTH, GLASSY_TAU)
    noisy = lambda E: E * (1 + 0.01 * rng.standard_normal(E.size))  # noqa: E731
    return np.unique(T), sweep, omega, noisy(Ep), noisy(Epp)


@pytest.mark.parametrize("quantity", ["moduli", "loss", "tan_delta"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_overlap_shifts_hold_on_a_glassy_plateau_with_noise(quantity, seed):
    """E' flat within 5 % over the four coldest sweeps, 1 % noise: shifting on what has structure
    there (E'', tan delta, or E' and E'' together) gives the shifts back within 0.2 decades and leaves
    every pair overlapping."""
    T, sweep, w, Ep, Epp = glassy_sweeps(seed)
    cold = sweep < 4
    flat = ve.prony_modulus(w[cold] * 10.0 ** ve.wlf_log10_shift(T[sweep[cold]], T_REF, C1, C2), 5e6,
                            GLASSY_STRENGTH, GLASSY_TAU)[0]
    assert max(np.ptp(np.log10(flat[sweep[cold] == j])) for j in range(4)) < np.log10(1.05)
    fit = mc.build_master_curve(T, sweep, w, Ep, Epp, T_REF, quantity=quantity)
    np.testing.assert_allclose(fit.log10_aT, ve.wlf_log10_shift(T, T_REF, C1, C2), atol=0.2)
    assert not fit.at_edge.any() and np.nanmin(fit.overlap) > 0.5
    assert np.nanmax(fit.misfit) < 0.02  # decades: the noise of two curves


def test_a_flat_storage_modulus_does_not_fix_a_shift_and_says_so():
    """Shifting on E' alone where E' is flat: the pairs concerned are flagged, not silently placed."""
    T, sweep, w, Ep, Epp = glassy_sweeps(2)
    fit = mc.build_master_curve(T, sweep, w, Ep, Epp, T_REF, quantity="storage")
    assert fit.at_edge[:3].any()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_overlap_shifts_never_run_against_the_temperature_order(seed):
    """Relaxation times shorten on heating, so log10 a_T does not increase with T, even where a flat E'
    (glassy plateau, 1 % noise) lets the overlap of two sweeps prefer the wrong sign."""
    T, sweep, w, Ep, Epp = glassy_sweeps(seed)
    fit = mc.build_master_curve(T, sweep, w, Ep, Epp, T_REF, quantity="storage")
    assert np.all(np.diff(fit.log10_aT) <= 0.0)


def test_a_pair_that_wants_the_wrong_sign_stays_unshifted_and_is_flagged():
    """Sweep b is sweep a moved 0.3 decades up in frequency: laid on a as a colder sweep (shift >= 0) it
    comes back at +0.3; as a warmer one (shift <= 0) it stays at 0 and is flagged."""
    x = np.linspace(0.0, 3.0, 31)
    curve = lambda x: np.tanh(x - 1.5)  # noqa: E731
    free = mc.pair_shift(x, (curve(x),), x, (curve(x + 0.3),), direction=+1)
    assert free.shift == pytest.approx(0.3, abs=0.01) and not free.at_edge
    held = mc.pair_shift(x, (curve(x),), x, (curve(x + 0.3),), direction=-1)
    assert held.shift == pytest.approx(0.0, abs=1e-9) and held.at_edge


def test_binned_long_sweeps_give_the_shifts_of_the_short_ones():
    """A sweep logged at 2000 points is averaged in bins (20 per decade): the fit sees ~60 points a
    sweep and gives the shifts of the 13-point sweeps."""
    T, sweep, w, Ep, Epp = glassy_sweeps(1, freqs=np.logspace(-1, 2, 2000))
    s, lw, (l1, l2), counts = mc.bin_sweeps(sweep, np.log10(w), (np.log10(Ep), np.log10(Epp)), 20.0)
    assert s.size <= 61 * T.size and counts.sum() == sweep.size
    fit = mc.build_master_curve(T, s, 10.0 ** lw, 10.0 ** l1, 10.0 ** l2, T_REF, quantity="moduli")
    np.testing.assert_allclose(fit.log10_aT, ve.wlf_log10_shift(T, T_REF, C1, C2), atol=0.05)


def test_two_temperatures_refuse_a_wlf_fit_and_hold_C2_with_overlap_shifts(tmp_path):
    T, sweep, w, Ep, Epp = sweeps(np.array([0.0, 10.0]))
    path = write_dma(tmp_path / "two.txt", T, w, Ep, Epp)
    with pytest.raises(UserError, match="two temperatures .* set fit = \"overlap\"") as err:
        _run(_scene(path, fit="wlf"), tmp_path)
    assert err.value.key == "modulus.fit"
    with pytest.warns(UserWarning, match="C2 held at modulus.C2 = 60 K"):
        mod = _run(_scene(path, C2="60 K"), tmp_path)
    assert float(mod["wlf_C2"]) == pytest.approx(60.0)
    assert float(mod["wlf_C1"]) == pytest.approx(C1, rel=0.05)


def test_stage_reports_overlap_and_misfit_per_sweep_and_can_refuse_a_gap(tmp_path):
    T, sweep, w, Ep, Epp = sweeps(TEN)
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    mod = _run(_scene(path, shift_on="moduli"), tmp_path)
    overlap = mod["sweep_overlap"].values
    assert np.isnan(overlap[1]) and np.nanmin(overlap) > 0.5 and mod["sweep_overlap"].attrs["units"] == "1"
    assert np.nanmax(mod["sweep_pair_misfit"].values) < 0.02
    # 40 K apart, 3-decade sweeps: the true shift leaves no overlap; refused naming both temperatures
    T, sweep, w, Ep, Epp = sweeps(np.array([-20.0, 20.0, 60.0]))
    path = write_dma(tmp_path / "gap.txt", T, w, Ep, Epp)
    with pytest.raises(UserError, match=r"20 °C on -20 °C") as err:
        _run(_scene(path, no_overlap="error", shift_on="moduli"), tmp_path / "b")
    assert err.value.key == "modulus.no_overlap"


def test_a_gap_refused_with_no_overlap_error_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    from roughcontact.stages.shared import mastercurve as shared

    T, sweep, w, Ep, Epp = sweeps(np.array([-20.0, 20.0, 60.0]))
    path = write_dma(tmp_path / "gap.txt", T, w, Ep, Epp)
    fitted = []
    monkeypatch.setattr(shared, "build_master_curve", lambda *a, **k: fitted.append(1))
    raw = _scene(path, no_overlap="error", shift_on="moduli")
    raw["outputs"]["variables"] += ["contact_area_ratio"]
    with pytest.raises(UserError, match=r"20 °C on -20 °C") as err:
        _run(raw, tmp_path)
    assert err.value.key == "modulus.no_overlap" and not fitted  # the preflight, not the fit, refused
    assert not [f for f in (tmp_path / "out").rglob("*") if f.is_file()]


# the same 6 points in every form an instrument writes
FORMS = {
    "comment_header.txt": "\n".join(GOOD) + "\n",
    "names_units.csv": "T,f,E',E''\nC,Hz,MPa,MPa\n" + "\n".join(",".join(r.split()) for r in GOOD[1:]) + "\n",
    "semicolon_comma.csv": "T;f;E';E''\n°C;Hz;MPa;MPa\n" + "\n".join(";".join(c.replace(".", ",") for c in r.split())
                                                                   for r in GOOD[1:]) + "\n",
    "tab_comma.txt": "T\tf\tE'\tE''\ndegC\tHz\tMPa\tMPa\n" + "\n".join("\t".join(c.replace(".", ",") for c in r.split())
                                                                        for r in GOOD[1:]) + "\n",
}


@pytest.mark.parametrize("name", list(FORMS) + ["sheet.xlsx"])
def test_every_file_form_reads_the_same_numbers(tmp_path, name):
    from roughcontact.readers import READERS

    path = tmp_path / name
    if name.endswith(".xlsx"):
        pd = pytest.importorskip("pandas")
        pytest.importorskip("openpyxl")
        rows = [r.split() for r in GOOD[1:]]
        frame = pd.DataFrame([["degC", "Hz", "MPa", "MPa"]] + [[float(c) for c in r] for r in rows],
                             columns=["T", "f", "E'", "E''"])
        frame.to_excel(path, index=False)
    else:
        path.write_text(FORMS[name], encoding="utf-8")
    base = tmp_path / "base.txt"
    base.write_text(FORMS["comment_header.txt"])
    want = READERS["dma"](base)
    for columns in ((0, 1, 2, 3), ("T", "f", "E'", "E''")):
        got = READERS["dma"](path, columns=columns)
        for field in ("temperatures", "omega", "storage", "loss"):
            np.testing.assert_allclose(getattr(got, field), getattr(want, field), rtol=1e-12)


@pytest.mark.parametrize("name, text, line, message", [
    ("bad.csv", "T;f;E';E''\nC;Hz;MPa;MPa\n0;0,1;10;1\n0;1;1x2;1,5\n", "line 4", "not a number"),
    ("bad.txt", "T\tf\tE'\tE''\nC\tHz\tMPa\tMPa\n0\t0,1\t10\t1\n0\t1\t12\n", "line 4", "3 column(s)"),
    ("bad_name.csv", "T,f,E',E''\nC,Hz,MPa,MPa\n0,0.1,10,1\n", "line 2", "no column named 'E_stor'"),
])
def test_bad_instrument_files_give_one_line_naming_file_and_line(tmp_path, name, text, line, message):
    from roughcontact.readers import READERS

    path = tmp_path / name
    path.write_text(text)
    columns = ("T", "f", "E_stor", "E''") if "name" in name else (0, 1, 2, 3)
    with pytest.raises(UserError) as err:
        READERS["dma"](path, columns=columns)
    assert err.value.file == str(path) and err.value.key == line and message in err.value.message
    assert "\n" not in str(err.value)


def test_a_bad_cell_in_a_spreadsheet_names_its_row(tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("openpyxl")
    from roughcontact.readers import READERS

    frame = pd.DataFrame([["degC", "Hz", "MPa", "MPa"], [0, 0.1, 10, 1], [0, 1, "12 MPa", 1.5]],
                         columns=["T", "f", "E'", "E''"])
    frame.to_excel(tmp_path / "bad.xlsx", index=False)
    with pytest.raises(UserError) as err:
        READERS["dma"](tmp_path / "bad.xlsx")
    assert err.value.key == "line 4" and "not a number" in err.value.message


REAL = Path(__file__).parent / "data" / "pyvisco"


def test_a_real_instrument_export_reads_the_same_as_csv_and_as_excel():
    """pyvisco's example measurement (BSD-3, tests/data/pyvisco/README.md): the Eplexor's Excel
    export (names row, units row with °C) and the CSV of it (units row with C) give the same 21 sweeps."""
    pytest.importorskip("pandas")
    pytest.importorskip("xlrd")
    from roughcontact.readers import READERS

    csv = READERS["dma"](REAL / "freq_user_raw.csv", columns=("T", "f", "E_stor", "E_loss"))
    xls = READERS["dma"](REAL / "freq_Eplexor_raw.xls", columns=("T", "f", "E'", "E''"))
    assert csv.temperatures.size == 21 and csv.temperatures[0] == pytest.approx(273.15 - 49.9, abs=0.1)
    for field in ("temperatures", "omega", "storage", "loss"):
        np.testing.assert_allclose(getattr(xls, field), getattr(csv, field), rtol=1e-8)
    assert csv.omega.min() == pytest.approx(2 * np.pi * 0.1) and csv.storage.max() > 8e9


# ----------------------------------------------------------------------------------------
# WLF above T_g, Arrhenius below (shift_law = "wlf_arrhenius")
# ----------------------------------------------------------------------------------------

#: the glassy branch of the known material: Arrhenius below -20 degC
T_G, E_A = 253.15, 200e3
STEP5 = np.arange(-40.0, 41.0, 5.0)


def wlf_arrhenius(T):
    return ve.wlf_arrhenius_log10_shift(T, T_REF, C1, C2, T_G, E_A)


@pytest.mark.parametrize("given", [None, T_G], ids=["T_g fitted", "T_g given"])
@pytest.mark.parametrize("noise", [0.0, 0.02])
def test_wlf_arrhenius_fit_recovers_the_law_from_its_shifts(given, noise):
    T = 273.15 + STEP5
    j0 = int(np.argmin(np.abs(T - T_REF)))
    L = wlf_arrhenius(T) + np.random.default_rng(3).normal(0.0, noise, T.size)
    law = mc.fit_wlf_arrhenius(T, L - L[j0], T_REF, anchor=j0, T_g=given)
    assert law.E_a == pytest.approx(E_A, rel=0.02)
    assert law.C1 == pytest.approx(C1, rel=0.02)
    assert law.C2 == pytest.approx(C2, rel=0.02)
    assert law.T_g == pytest.approx(T_G, abs=1.0)
    # continuous at T_g: the two branches meet there
    below = ve.wlf_arrhenius_log10_shift(law.T_g - 1e-9, T_REF, law.C1, law.C2, law.T_g, law.E_a)
    assert below == pytest.approx(ve.wlf_log10_shift(law.T_g, T_REF, law.C1, law.C2), abs=1e-6)
    if noise:
        assert np.sqrt(np.mean(law.residual ** 2)) < 2 * noise
    # WLF alone cannot follow the bend: its residual is far larger
    wlf_only = mc.fit_wlf(T, L - L[j0], T_REF, anchor=j0)[2]
    assert np.abs(wlf_only).max() > 5 * max(np.abs(law.residual).max(), noise)


def test_wlf_arrhenius_does_no_worse_than_wlf_on_pure_wlf_shifts():
    T = 273.15 + STEP5
    j0 = int(np.argmin(np.abs(T - T_REF)))
    L = ve.wlf_log10_shift(T, T_REF, C1, C2) + np.random.default_rng(4).normal(0.0, 0.02, T.size)
    wlf = mc.fit_wlf(T, L - L[j0], T_REF, anchor=j0)[2]
    law = mc.fit_wlf_arrhenius(T, L - L[j0], T_REF, anchor=j0)
    assert np.sum(law.residual ** 2) <= np.sum(wlf ** 2) * (1 + 1e-9)


def test_stage_fits_wlf_arrhenius_and_the_friction_law_reads_it_back(tmp_path):
    from roughcontact.stages.shared.flash import temperature_law

    T, sweep, w, Ep, Epp = sweeps(STEP5, noise=0.005, law=wlf_arrhenius)
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    mod = _run(_scene(path, shift_law="wlf_arrhenius", shift_on="moduli", T_ref="0 degC"), tmp_path)
    assert mod.attrs["horizontal_shift"] == "wlf_arrhenius"
    assert float(mod["arrhenius_activation_energy"]) == pytest.approx(E_A, rel=0.02)
    assert float(mod["wlf_C1"]) == pytest.approx(C1, rel=0.02)
    assert float(mod["wlf_C2"]) == pytest.approx(C2, rel=0.02)
    assert float(mod["glass_transition_temperature"]) == pytest.approx(T_G, abs=1.5)
    assert mod["arrhenius_activation_energy"].attrs["units"] == "J/mol"
    # the law the friction stage reads from the stored result is the fitted one, on both branches
    Ts = np.linspace(230.0, 320.0, 37)
    fitted = ve.wlf_arrhenius_log10_shift(Ts, float(mod["reference_temperature"]), float(mod["wlf_C1"]),
                                          float(mod["wlf_C2"]), float(mod["glass_transition_temperature"]),
                                          float(mod["arrhenius_activation_energy"]))
    np.testing.assert_allclose(temperature_law(mod)(Ts)[0], fitted, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(temperature_law(mod)(Ts)[0], wlf_arrhenius(Ts), atol=0.1)
    # and the residual per sweep is about the fitted law
    np.testing.assert_allclose(mod["sweep_log10_aT"].values - mod["sweep_wlf_residual"].values,
                               temperature_law(mod)(mod["shift_T"].values)[0], atol=1e-9)


@pytest.mark.parametrize("extra, key, message", [
    ({"fit": "wlf"}, "modulus.shift_law", "set fit = \"overlap\""),
    ({"T_g": "10 degC"}, "modulus.T_g", "above T_ref"),
    ({"T_g": "-60 degC"}, "modulus.T_g", "0 sweep.s. below it"),
])
def test_wlf_arrhenius_refusals_name_the_key_and_write_nothing(tmp_path, extra, key, message):
    T, sweep, w, Ep, Epp = sweeps(STEP5, law=wlf_arrhenius)
    path = write_dma(tmp_path / "dma.txt", T, w, Ep, Epp)
    with pytest.raises(UserError, match=message) as err:
        _run(_scene(path, shift_law="wlf_arrhenius", T_ref="0 degC", **extra), tmp_path)
    assert err.value.key == key
    assert not list((tmp_path / "out").rglob("*.nc"))
