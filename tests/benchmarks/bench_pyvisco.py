"""Master curves from measured DMA sweeps: roughcontact's overlap shifts against pyvisco (PyPI, NREL)
and against the instrument software's own shifts, on real data and on synthetic sweeps.

    python tests/benchmarks/bench_pyvisco.py [--smoke]

Data (tests/data/pyvisco/README.md; BSD-3, from pyvisco 2.1.3's PyPI sdist):
  A  the Eplexor export freq_Eplexor_raw.xls / freq_user_raw.csv: 21 sweeps of a polymer, -50..100 degC,
     0.1-100 Hz. Peer: pyvisco's shifts on the same file (master.get_aT, T_ref -5 degC; it shifts E').
  B  the Eplexor software's master curve of another measurement (freq_Eplexor_master.xls), whose 21
     sweeps are rebuilt from it (points consecutive in time; f / a_T is 0.1-100 Hz again). Peer: the
     instrument's own shift list (WLF C1 = 13.50, C2 = 141.19 K about 25 degC), and pyvisco; and ours
     shifted on |E*| divided by the entropic vertical shift b_T = T / T_ref (Ferry, ch. 11), which the file
     does not name but which reproduces most of the instrument's list (its misfit, like every misfit, on
     the unscaled E').
  S  synthetic sweeps with a glassy plateau (tests/test_mastercurve.py, glassy_sweeps), 1 % noise,
     true shifts known.
  S' synthetic sweeps of the smooth spectrum of tests/test_mastercurve.py (10 temperatures), 1 % noise
     (Prony part only).
For every set of shifts it prints, per sweep, log10 a_T (decades) and, as a common yardstick, the
rms log10 distance between each sweep and its neighbour nearer T_ref after shifting (on E', over
their overlap; `misfit`, decades): shifts that superpose the data better give a smaller misfit.

Prony part: on one master curve per set (the same shifted points for every method: A our E' shifts,
B the instrument's shifts and, apart, ours, S and S' the true shifts) it fits the relaxation spectrum our way
(physics/relaxation_spectrum.py fit_prony: relaxation_times at n per decade, non-negative least squares on
relative residuals of E' and E'') and pyvisco's ways (prony.discretize "round" + prony.fit, the default
of its dashboard: one term per decade collocated at interpolated points; with opt=True: L-BFGS-B on
every point; opt.nprony: fewest terms within 1.5 times the least residual), and prints the rms log10
residual of E' and of E'' over all points of the master curve (decades), the number of terms (non-zero
/ offered) and the time. The floor is the rms about a cubic B-spline with 2 knots per decade fitted to
log E' and log E'' separately (not causal, not a Prony series): what the scatter of the shifted data
leaves to any smooth curve.
Prints ratios and differences only; asserts nothing (tests/test_benchmarks.py runs --smoke).
"""

from __future__ import annotations

import contextlib
import io
import time
import warnings

import numpy as np
from _bench import SMOKE, TESTS

from roughcontact.physics import mastercurve as mc, relaxation_spectrum as rs, viscoelastic as ve
from roughcontact.readers import READERS

DATA = TESTS / "data" / "pyvisco"


def pair_misfit(logw, l1, sweep, log_a, j0):
    """rms log10 E' distance of each sweep to its neighbour nearer j0 at the shifts log_a (decades)."""
    out = np.full(log_a.size, np.nan)
    for j in range(log_a.size):
        if j == j0:
            continue
        ref = j - 1 if j > j0 else j + 1
        a, b = sweep == ref, sweep == j
        lo = max(logw[a].min(), logw[b].min() + log_a[j] - log_a[ref])
        hi = min(logw[a].max(), logw[b].max() + log_a[j] - log_a[ref])
        if hi <= lo:
            continue  # no overlap at all
        out[j] = np.sqrt(mc._pair_cost(logw[a], (l1[a],), logw[b], (l1[b],), log_a[j] - log_a[ref], False)[0])
    return out


def ours(T, sweep, omega, Ep, Epp, T_ref, quantity="storage"):
    start = time.perf_counter()
    fit = mc.build_master_curve(T, sweep, omega, Ep, Epp, T_ref, quantity=quantity)
    return fit, time.perf_counter() - start


def pyvisco_shifts(T, sweep, omega, Ep, Epp, T_ref):
    """pyvisco 2.1.3's shifts (master.get_aT: power-law fits of E' of neighbours) and WLF fit, or None."""
    try:
        import pandas as pd
        from pyvisco import master, shift
    except ImportError:
        return None
    rows = pd.DataFrame({"f_set": omega / (2 * np.pi), "E_stor": Ep / 1e6, "E_loss": Epp / 1e6,
                         "T": T[sweep] - 273.15, "Set": sweep})
    rows["T_round"] = np.round(T[sweep] - 273.15).astype(int)
    rows["omega"], rows["E_comp"] = omega, np.hypot(Ep, Epp) / 1e6
    rows["tan_del"] = Epp / Ep
    rows.domain, rows.modul = "freq", "E"
    ref = int(round(T_ref - 273.15))
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df_aT, _ = master.get_aT(rows, ref)
        wlf = shift.fit_WLF(ref, df_aT)
    return df_aT["log_aT"].to_numpy(float), float(wlf["C1"].iloc[0]), float(wlf["C2"].iloc[0]), \
        time.perf_counter() - start


def log_rms(Ep, Epp, model):
    """rms log10 residual of a model (E', E'') against E', E'' (decades), each."""
    return tuple(float(np.sqrt(np.mean(np.log10(np.maximum(m, 1e-300) / d) ** 2)))
                 for m, d in zip(model, (Ep, Epp), strict=True))


def prony_ours(w, Ep, Epp, per_decade):
    """Our spectrum fit: (E', E'') at w, terms used, terms offered, seconds."""
    start = time.perf_counter()
    times = rs.relaxation_times(w, per_decade)
    E0, moduli, _ = rs.fit_prony(w, Ep, Epp, times)
    seconds = time.perf_counter() - start
    return ve.prony_modulus(w, E0, moduli, times), int(np.count_nonzero(moduli)), times.size, seconds


def prony_pyvisco(w, Ep, Epp, how):
    """pyvisco 2.1.3's Prony fit of the master curve (w, E', E''): ``default`` (discretize "round",
    one term per decade, collocation), ``opt`` (L-BFGS-B on all points) or ``nprony`` (fewest terms);
    (E', E'') at w, terms used, terms offered, seconds; None without pyvisco."""
    try:
        import pandas as pd
        from pyvisco import master, opt, prony
    except ImportError:
        return None
    order = np.argsort(w)
    df = pd.DataFrame({"E_stor": Ep[order] / 1e6, "E_loss": Epp[order] / 1e6, "f": w[order] / (2 * np.pi),
                       "omega": w[order], "Set": 0})
    df["t"] = 1 / df["f"]
    df.RefT, df.domain, df.modul = 0, "freq", "E"
    start = time.perf_counter()
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        df = master.smooth(df, 1)
        series, _ = prony.fit(prony.discretize(df, "round"), df, opt=how != "default")
        if how == "nprony":
            fits, n_opt, _ = opt.nprony(df, series, window="min")
            series = fits[n_opt]
    seconds = time.perf_counter() - start
    alpha, tau = series["df_terms"]["alpha_i"].to_numpy(), series["df_terms"]["tau_i"].to_numpy()
    E_0 = series["E_0"] * 1e6
    return (ve.prony_modulus(w, E_0 * (1 - alpha.sum()), E_0 * alpha, tau), int(np.count_nonzero(alpha)), alpha.size,
            seconds)


def prony_report(name, w, Ep, Epp, full=True):
    """Print the spectrum-fit table of one master curve (reduced omega w, E', E'')."""
    r = mc._spline_residuals(np.log10(w), (np.log10(Ep), np.log10(Epp)), 2.0).reshape(2, -1)
    floor = np.sqrt(np.mean(r ** 2, axis=1))
    print(f"\n{name}: Prony fits of the master curve ({w.size} points, {np.log10(w.max() / w.min()):.1f} decades); "
          "rms log10 residual of E' and E'' (decades), terms (non-zero / offered), time")
    print(f"  {'smooth-curve floor (spline)':>34}: E' {floor[0]:.4f}  E'' {floor[1]:.4f}")
    rows = [(f"ours, {n} per decade", lambda n=n: prony_ours(w, Ep, Epp, n)) for n in ((4, 1, 2) if full else (4,))]
    rows += [(f"pyvisco {how}", lambda how=how: prony_pyvisco(w, Ep, Epp, how))
             for how in (("default", "opt", "nprony") if full else ("default",))]
    for label, run in rows:
        out = run()
        if out is None:
            print(f"  {label:>34}: pyvisco is not installed")
            continue
        model, used, offered, seconds = out
        e1, e2 = log_rms(Ep, Epp, model)
        print(f"  {label:>34}: E' {e1:.4f}  E'' {e2:.4f}  terms {used:3d} / {offered:3d}  {seconds:7.3f} s")


def rebuilt_eplexor_master():
    """The 21 sweeps behind freq_Eplexor_master.xls and the instrument's shifts (see the docstring)."""
    import pandas as pd

    path = DATA / "freq_Eplexor_master.xls"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = pd.read_excel(path, sheet_name="Exported Data", skiprows=[1]).sort_values("Time")
        listed = pd.read_excel(path, sheet_name="Shiftlist", skiprows=3, header=None)
    T_list, a_list = listed[0].to_numpy(float), listed[1].to_numpy(float)
    cluster = np.r_[0, np.cumsum(np.diff(data["Time"].to_numpy()) > 1500)]
    sweeps = []
    for k in range(cluster.max() + 1):
        part = data[cluster == k]
        f = part["f"].to_numpy()
        j = int(np.argmin([abs(np.log10(f.min() / 10 ** s / 0.1)) for s in a_list]))
        order = np.argsort(f)
        sweeps.append((T_list[j] + 273.15, a_list[j], f[order] / 10 ** a_list[j], part["E'"].to_numpy()[order] * 1e6,
                       part["E''"].to_numpy()[order] * 1e6))
    sweeps.sort(key=lambda s: s[0])
    T = np.array([s[0] for s in sweeps])
    sweep = np.concatenate([[i] * s[2].size for i, s in enumerate(sweeps)])
    cat = lambda k: np.concatenate([s[k] for s in sweeps])  # noqa: E731
    return T, sweep, 2 * np.pi * cat(2), cat(3), cat(4), np.array([s[1] for s in sweeps])


def report(name, T, sweep, omega, Ep, Epp, T_ref, peers, quantities):
    """Print the table of one data set: shifts of each method about the sweep nearest T_ref, the
    difference to each peer, and the misfit yardstick."""
    j0 = int(np.argmin(np.abs(T - T_ref)))
    logw, l1 = np.log10(omega), np.log10(Ep)
    rows = dict(peers)
    times = {}
    for q in quantities:
        fit, seconds = ours(T, sweep, omega, Ep, Epp, T[j0], q)
        rows[f"ours ({q})"] = (fit.log10_aT - fit.log10_aT[j0], fit.C1, fit.C2)
        times[f"ours ({q})"] = seconds
        flagged = ", ".join(f"{t - 273.15:.0f}" for t in T[fit.at_edge]) or "none"
        print(f"  ours ({q}): {seconds:.2f} s; pairs flagged as not fixed by the overlap at T = {flagged} degC")
    print(f"\n{name}: log10 a_T about {T[j0] - 273.15:.1f} degC (decades) and misfit to the neighbour (decades)")
    names = list(rows)
    print("  T (degC) | " + " | ".join(f"{n:>22}" for n in names))
    misfit = {n: pair_misfit(logw, l1, sweep, rows[n][0] - rows[n][0][j0], j0) for n in names}
    for j, t in enumerate(T):
        cells = [f"{rows[n][0][j] - rows[n][0][j0]:8.2f} ({misfit[n][j]:.4f})" for n in names]
        print(f"  {t - 273.15:8.1f} | " + " | ".join(f"{c:>22}" for c in cells))
    print("  WLF C1, C2 (K) about the T_ref of each: " + "; ".join(
        f"{n}: {rows[n][1]:.4g}, {rows[n][2]:.4g}" for n in names))
    print("  median misfit (decades): " + "; ".join(f"{n}: {np.nanmedian(misfit[n]):.4f}" for n in names))
    pairs = [(n, names[0]) for n in names[1:]]
    if names[0] != "pyvisco 2.1.3" and "pyvisco 2.1.3" in names:
        pairs += [(n, "pyvisco 2.1.3") for n in names if n.startswith("ours")]
    for n, base in pairs:
        d = (rows[n][0] - rows[n][0][j0]) - (rows[base][0] - rows[base][0][j0])
        inside = np.abs(d) <= 0.3
        print(f"  {n} - {base}: max |diff| {np.max(np.abs(d)):.2f} decades; within 0.3 decades at "
              f"{inside.sum()}/{d.size} sweeps ({', '.join(f'{t - 273.15:.0f}' for t in T[inside])} degC)")
    return rows, times


def main() -> None:
    quantities = ("storage",) if SMOKE else ("storage", "moduli", "tan_delta")
    data = READERS["dma"](DATA / "freq_user_raw.csv", columns=("T", "f", "E_stor", "E_loss"))
    T, sweep, omega, Ep, Epp = data.temperatures, data.sweep, data.omega, data.storage, data.loss
    T_ref = T[np.argmin(np.abs(T - 268.15))]
    peers = {}
    pv = pyvisco_shifts(T, sweep, omega, Ep, Epp, T_ref)
    if pv is None:
        print("pyvisco is not installed (pip install --no-deps pyvisco==2.1.3): its column is left out")
    else:
        peers["pyvisco 2.1.3"] = pv[:3]
        print(f"A: pyvisco get_aT + fit_WLF: {pv[3]:.2f} s")
    report("A (Eplexor export, 21 sweeps)", T, sweep, omega, Ep, Epp, T_ref, peers, quantities)
    fit = mc.build_master_curve(T, sweep, omega, Ep, Epp, T_ref, quantity="storage")
    prony_report("A (our E' shifts)", omega * 10.0 ** fit.log10_aT[sweep], Ep, Epp, full=not SMOKE)
    if SMOKE:
        return
    try:
        T, sweep, omega, Ep, Epp, listed = rebuilt_eplexor_master()
    except ImportError:
        print("pandas/xlrd missing: set B left out")
    else:
        peers = {"instrument (Eplexor)": (listed, 13.50, 141.19)}
        pv = pyvisco_shifts(T, sweep, omega, Ep, Epp, 298.15)
        if pv is not None:
            peers["pyvisco 2.1.3"] = pv[:3]
        # the quantity the instrument may have shifted: |E*| divided by the entropic vertical shift T / T_ref
        b = (T / 298.15)[sweep]
        vert = mc.build_master_curve(T, sweep, omega, Ep / b, Epp / b, 298.15, quantity="complex")
        peers["ours (complex, b=T/Tref)"] = (vert.log10_aT, vert.C1, vert.C2)
        report("B (Eplexor master rebuilt into its 21 sweeps)", T, sweep, omega, Ep, Epp, 298.15, peers, quantities)
        prony_report("B (the instrument's shifts: its own master curve)", omega * 10.0 ** listed[sweep], Ep, Epp)
        fit = mc.build_master_curve(T, sweep, omega, Ep, Epp, 298.15, quantity="storage")
        prony_report("B (our E' shifts)", omega * 10.0 ** fit.log10_aT[sweep], Ep, Epp)
    from test_mastercurve import C1, C2, T_REF, TEN, glassy_sweeps, sweeps

    T, sweep, omega, Ep, Epp = glassy_sweeps(1)
    peers = {"truth (WLF 10, 60 K)": (ve.wlf_log10_shift(T, T_REF, C1, C2), C1, C2)}
    pv = pyvisco_shifts(T, sweep, omega, Ep, Epp, T_REF)
    if pv is not None:
        peers["pyvisco 2.1.3"] = pv[:3]
    report("S (synthetic, glassy plateau, 1 % noise)", T, sweep, omega, Ep, Epp, T_REF, peers,
           ("storage", "moduli", "tan_delta"))
    prony_report("S (true shifts)", omega * 10.0 ** ve.wlf_log10_shift(T[sweep], T_REF, C1, C2), Ep, Epp)
    T_points, sweep, omega, Ep, Epp = sweeps(TEN)
    prony_report("S' (smooth spectrum, 10 sweeps, true shifts)",
                 omega * 10.0 ** ve.wlf_log10_shift(T_points, T_REF, C1, C2), Ep, Epp)


if __name__ == "__main__":
    main()
