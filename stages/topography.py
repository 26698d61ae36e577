"""Stage ``topography``: measured height maps and line scans -> isotropic PSDs; paired
surfaces -> cross-spectrum and coherence eta(q) (seed eqs 4, 41).

Kernels: :mod:`roughcontact.physics.estimators`. The files are read (in metres) by the
engine's topography reader and checked and prepared by :mod:`roughcontact.stages.shared.maps`.
Figures: :mod:`roughcontact.stages.figures.topography`. See docs/topography.md.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from roughcontact.physics.estimators import (
    binned_spectra_area,
    binned_spectra_profiles,
    hurst_from_spectrum,
    log_bin_edges,
    merge_spectra,
    pooled_coherence,
    second_surface_hurst,
)
from roughcontact.physics.lattice import binned_wavenumbers
from roughcontact.physics.spectra import isotropic_factor
from roughcontact.stage import Figure, Param, Shape, Stage, StageInput, UserError, Var, register, register_params

from .figures.topography import figure_coherence, figure_measured_psd
from .shared.maps import topography_files
from .shared.measured import (
    bin_covariance,
    container_files,
    measurements_entered,
    merged_correlation,
    merged_psd,
    mode_factor,
    prepared_files,
    unbias_processing,
)
from .shared.surfaces import CONTAINER_KEYS, MAP_KEYS, SURFACES, measured_spec, surface_reads

register_params(
    "numerics",
    Param("topography_bins_per_decade", "int", default=20, lo=2, hi=200,
          doc="logarithmic wavenumber bins per decade for the radial average of measured PSDs"),
)


def _spectra(p, edges, spec, other=None):
    """Binned spectra of one prepared file (and of its partner ``other`` of the second surface)."""
    h2 = other["h"] if other is not None else None
    if p["analysis"] == "profiles":
        s = binned_spectra_profiles(p["h"], p["sizes"][0], edges, p["q_max"], spec["hurst"], h2)
    else:
        s = unbias_processing(p, edges, binned_spectra_area(p["h"], p["sizes"][0], p["sizes"][1], edges, p["q_max"],
                                                            h2))
    s["n"] = s["n"] / mode_factor(p, edges)  # a window correlates neighbouring modes
    s["K"] = bin_covariance(p, edges, s["n"], s.pop("model", None))  # within a bin and across neighbouring bins
    with np.errstate(divide="ignore"):  # the lowest bins' variance computed exactly
        s["n"] = np.where(np.diag(s["K"]) > 0, 1.0 / np.where(np.diag(s["K"]) > 0, np.diag(s["K"]), 1.0), s["n"])
    return s


def _fitted_hurst(name, spec, prepared, edges):
    """The line scans' H: as given, or fitted to the slope of their spectrum (bins of at least 5
    modes above 4 times each scan's lowest wavenumber, where its window and detrending bias it);
    returns the spec with it, and what the result says about it. Maps (no conversion): unchanged."""
    if not any(p["analysis"] == "profiles" for p in prepared):
        return spec, None
    if spec.get("hurst") is not None:
        return spec, {"value": spec["hurst"], "source": "given", "error": None}
    spectra = []
    for p in prepared:
        if p["analysis"] == "profiles":
            s = _spectra(p, edges, dict(spec, hurst=0.5))
            spectra.append(dict(s, n=np.where(s["q"] >= 4.0 * p["q_min"], s["n"], 0.0)))
    q, C, n, _ = merge_spectra(spectra)
    H, err, used = hurst_from_spectrum(q, C, n)
    if not np.isfinite(H) or not 0.0 < H <= 1.0:
        why = f"fitted H = {H:.3g} is outside (0, 1]" if np.isfinite(H) else f"only {used} bin(s) with 5 modes or more"
        raise UserError(f"the line scans' Hurst exponent cannot be fitted to their spectrum ({why}); give "
                        f"{name}.hurst for the conversion of the 1D spectra to the isotropic PSD",
                        key=f"{name}.hurst")
    return dict(spec, hurst=H), {"value": H, "source": f"fitted to the slope of the scans' spectrum over {used} bins",
                                 "error": err}


def _hurst_note(hurst) -> str:
    """The attribute saying which H converted the line scans and that its uncertainty is not in the bands."""
    H, err = hurst["value"], hurst["error"]
    if err is None:
        return (f"H = {H:g}, given; the conversion C = c(H) C1D / q is exact only for an isotropic self-affine surface "
                "with that H; its uncertainty is not in the errors or the bands")
    dc = abs(float(np.log(isotropic_factor(min(H + err, 1.0)) / isotropic_factor(max(H - err, 1e-3))))) / 2.0
    return (f"H = {H:.3f} +- {err:.3f}, {hurst['source']}; c(H) is uncertain by {100 * dc:.1f} % (common to every bin "
            "the line scans carry), which is NOT in the errors or the bands (the draws keep H fixed); the error of H "
            "counts the profiles as independent and so is a lower bound")


def _describe(p, spec):
    """What the result records about one file (JSON-able)."""
    d = {k: p[k] for k in ("path", "format", "unit", "size_source", "periodic", "detrend", "window", "analysis",
                           "cutoff")}
    d.update(shape=list(p["h"].shape), sizes_m=list(p["sizes"]), q_range_per_m=[p["q_min"], p["q_max"]],
             rms_height_after_detrend_m=p["rms"])
    if "member" in p:  # a measurement of a contact.engineering container
        d["container_measurement"] = p["member"]
    if p.get("filled"):  # undefined heights filled (fill_undefined): how many, where
        d["undefined_filled"] = p["filled"]
    if p["analysis"] == "profiles":
        d["isotropic_conversion"] = (f"C(q) = c(H) C1D(q) / q with c(H) = Gamma(1+H)/(2 pi^1.5 Gamma(H+1/2)), "
                                     f"H = {spec['hurst']:g}; exact only for an isotropic self-affine surface with "
                                     "that H (roll-off and band edges bias it)")
    return d


def _pairing_problem(a, b) -> str | None:
    """Why file i of the substrate cannot be paired with file i of the solid, or None."""
    if len(a) != len(b):
        return (f"the substrate has {len(a)} file(s) and the solid {len(b)}; pairs need one solid file per "
                "substrate file")
    for i, (p, r) in enumerate(zip(a, b, strict=True)):
        if p["h"].shape != r["h"].shape:
            return f"file pair {i}: grids differ ({p['h'].shape} vs {r['h'].shape} points)"
        if not np.allclose(p["sizes"], r["sizes"], rtol=1e-6):
            return f"file pair {i}: physical sizes differ ({p['sizes']} vs {r['sizes']} m)"
        if p["analysis"] != r["analysis"] or p["window"] != r["window"]:
            return f"file pair {i}: analysis/window differ"
    return None


def _paired_spectra(prepared, specs, edges):
    """Joint spectra of the file pairs: a pair uses the modes reliable in both files; each
    surface keeps its own line-scan H."""
    joint = []
    for p, r in zip(prepared["substrate"], prepared["solid"], strict=True):
        both = dict(p, q_max=min(p["q_max"], r["q_max"]))
        s = _spectra(both, edges, specs["substrate"], r)
        if p["analysis"] == "profiles":
            s = second_surface_hurst(s, specs["substrate"]["hurst"], specs["solid"]["hurst"])
        joint.append(s)
    return {"substrate": joint, "solid": [{"n": s["n"], "q": s["q"], "C11": s["C22"], "K": s["K"]} for s in joint]}


def _surface_vars(name, spectra, described, bpd, entered):
    """The merged PSD of one surface with its error, mean wavenumbers and modes per bin
    (``entered``: :func:`measurements_entered`)."""
    q, C, n, err, ratio = merged_psd(spectra)
    filled = [f"{d['path']}: {d['undefined_filled']['points']} points" for d in described if "undefined_filled" in d]
    common = {"surface": name, "files": json.dumps(described), **entered,
              **({"undefined_filled": "; ".join(filled)} if filled else {}),
              "convention": "Persson, C(q) = (2 pi)^-2 int d^2x <hh> e^-iqx",
              "radial_average": f"mean over Fourier modes with |q| in log bins, {bpd} per decade",
              "merge": "in each bin, the files (measurements) with modes there averaged with weights n, their "
                       "effective independent modes (inverse-variance weights); each file's range in 'files' "
                       "(q_range_per_m)",
              "processing_bias": "removed: the bins of each non-periodic or windowed area map divided by the factor by "
                                 "which its detrending and window bias them, the expected periodogram of a roll-off "
                                 "fit to its bins over the fit (docs/measured-data.md); line scans and periodic "
                                 "unwindowed maps unchanged"}
    estimate = ("C / sqrt(n), n the independent modes (Gaussian random-phase statistics; a window's correlation "
                "of the modes within a bin counted; that across neighbouring bins is psd_<surface>_measured_"
                "correlation), times the Birge ratio where the files disagree beyond it (chi-square "
                "test at 1 %); correlated profiles make it an underestimate")
    return {f"psd_{name}_measured": (C, common), f"psd_{name}_measured_error": (err, {"estimate": estimate}),
            f"q_{name}_measured": (q, {}), f"modes_{name}": (n, {}), f"psd_{name}_measured_spread": (ratio, {}),
            f"psd_{name}_measured_correlation": (merged_correlation(spectra), {})}, n > 0


def _prepared(inp: StageInput):
    """The checked and prepared files of each measured surface, the bin edges and the pairing
    (why the files cannot be paired, or None)."""
    specs = {name: measured_spec(inp[name]) for name in SURFACES if measured_spec(inp[name]) is not None}
    if not specs:
        raise UserError("no surface has kind = 'topography' or 'container'", key="substrate.kind")
    prepared = {name: prepared_files(name, spec, inp.files) for name, spec in specs.items()}
    q_lo = min(p["q_min"] for ps in prepared.values() for p in ps)
    q_hi = max(p["q_max"] for ps in prepared.values() for p in ps)
    edges = log_bin_edges(q_lo, q_hi, inp["numerics.topography_bins_per_decade"])
    pair_note = _pairing_problem(prepared["substrate"], prepared["solid"]) if len(specs) == 2 else None
    return specs, prepared, edges, pair_note


def describe_topography(inp: StageInput) -> Shape:
    """Before anything computes: every file read, checked and prepared (units, sizes, missing
    points, flat maps, reliable band; a bad one is refused here); the bins, the measured
    wavenumber range of each surface (from the Fourier lattice alone, no FFT) and whether the
    pair gives a coherence."""
    specs, prepared, edges, pair_note = _prepared(inp)
    paired = len(specs) == 2 and pair_note is None
    ranges, values, bins = {}, {}, np.zeros(edges.size - 1, bool)
    for name in specs:
        other = prepared["solid" if name == "substrate" else "substrate"] if paired else [None] * len(prepared[name])
        lattice = [binned_wavenumbers(p["h"].shape, p["sizes"], edges, min(p["q_max"], r["q_max"]) if r else p["q_max"],
                                      profiles=p["analysis"] == "profiles")
                   for p, r in zip(prepared[name], other, strict=True)]
        q, _, n, _ = merge_spectra([{"n": n, "q": q, "C11": np.zeros_like(q)} for n, q in lattice])
        bins |= n > 0
        if np.count_nonzero(n > 0) < 2:
            raise UserError("the measured maps give fewer than two wavenumber bins",
                            key=f"{name}.{'container' if specs[name]['kind'] == 'container' else 'files'}")
        ranges[f"q_{name}_measured"] = (float(np.nanmin(q)), float(np.nanmax(q)))
        # the bins' mean wavenumbers from the lattice alone (the psd stage puts them in its q grid); the computed
        # ones weight the modes of several files by their spectra, so they are approximate here
        values[f"q_{name}_measured"] = q[np.isfinite(q)]
    variables = {f"{kind}_{name}_measured" for name in specs for kind in ("psd", "q")}
    variables |= {"coherence", "cross_psd_measured", "coherence_error"} if paired else set()
    pairing = "paired" if paired else f"not paired: {pair_note}" if pair_note else "not paired: one surface only"
    size = int(np.ptp(np.flatnonzero(bins))) + 1
    return Shape(sizes={"q_bin": size, "q_bin_pair": size}, ranges=ranges,
                 variables=frozenset(variables), attrs={"pairing": pairing}, values=values, approximate=tuple(values))


def compute_topography(inp: StageInput) -> xr.Dataset:
    bpd = inp["numerics.topography_bins_per_decade"]
    specs, prepared, edges, pair_note = _prepared(inp)
    hursts = {}
    for name in specs:
        specs[name], hursts[name] = _fitted_hurst(name, specs[name], prepared[name], edges)
    centres = np.sqrt(edges[1:] * edges[:-1])
    paired = len(specs) == 2 and pair_note is None
    if paired:
        spectra = _paired_spectra(prepared, specs, edges)
    else:
        spectra = {name: [_spectra(p, edges, specs[name]) for p in prepared[name]] for name in specs}
    data_vars, keep = {}, np.zeros(centres.size, bool)
    for name in specs:
        described = [_describe(p, specs[name]) for p in prepared[name]]
        found, has = _surface_vars(name, spectra[name], described, bpd, measurements_entered(prepared[name]))
        if hursts[name] is not None:
            found[f"psd_{name}_measured"][1]["line_scan_hurst"] = _hurst_note(hursts[name])
        data_vars.update(found)
        keep |= has
    if paired:
        C12, eta, eta_err = pooled_coherence(spectra["substrate"])
        data_vars.update(cross_psd_measured=(C12, {}), coherence=(eta, {}), coherence_error=(eta_err, {}))
    sel = np.flatnonzero(keep)
    sl = slice(sel[0], sel[-1] + 1)
    ds = xr.Dataset({k: (("q_bin", "q_bin_pair")[:np.ndim(v)], v[(sl,) * np.ndim(v)], a)
                     for k, (v, a) in data_vars.items()}, coords={"q_bin": centres[sl], "q_bin_pair": centres[sl]})
    ds.attrs["bins_per_decade"] = bpd
    ds.attrs["pairing"] = ("paired: file i of the substrate with file i of the solid" if paired else
                           f"not paired: {pair_note}" if pair_note else "not paired: one surface only")
    return ds



def _empty(surface: str, about: str = "") -> dict:
    """The comment on a per-bin variable: ``about`` it, then what its NaN mean (said in the file, for
    readers of it)."""
    return {"comment": f"{about}{'; ' if about else ''}NaN in the bins that hold no Fourier mode of the {surface}'s "
                       "maps (below their lowest or above their highest wavenumber, or between the modes of a small "
                       "map)"}


register(
    Stage(
        name="topography",
        version="5",
        compute=compute_topography,
        # of a measured surface the map keys and the line-scan H; of any other surface only its kind
        # (a fitted surface of maps or a container: the same keys, and what it is fitted to)
        reads=(*surface_reads({"topography": (*MAP_KEYS, "hurst"), "container": (*CONTAINER_KEYS, "hurst"),
                               "fit": ("of", *MAP_KEYS, "surface", "hurst"), "*": ()}),
               "numerics.topography_bins_per_decade"),
        describe=describe_topography,
        files=(topography_files("substrate"), topography_files("solid"), container_files("substrate"),
               container_files("solid")),
        outputs={
            **{f"psd_{s}_measured": Var("m^4", f"measured PSD of the {s}", attrs=_empty(s, "Persson convention"))
               for s in SURFACES},
            **{f"psd_{s}_measured_error": Var("m^4", f"standard error of the {s}'s measured PSD",
                                              attrs=_empty(s, "statistical standard error")) for s in SURFACES},
            **{f"q_{s}_measured": Var("1/m", f"mean wavenumber of the {s}'s modes",
                                      attrs=_empty(s, f"mean wavenumber of the {s}'s Fourier modes in the bin"))
               for s in SURFACES},
            **{f"modes_{s}": Var("1", f"independent Fourier modes of the {s}",
                                 comment=f"independent Fourier modes of the {s} in the bin (a window's "
                                         "correlations counted)") for s in SURFACES},
            **{f"psd_{s}_measured_spread": Var("1", f"Birge ratio of the {s}'s files",
                                               attrs=_empty(s, f"Birge ratio sqrt(chi^2/(k-1)) of the spread between "
                                                               f"the {s}'s k files in the bin (about 1 when they "
                                                               "agree within their errors)")) for s in SURFACES},
            **{f"psd_{s}_measured_correlation": Var(
                "1", f"{s}'s PSD error correlation between bins",
                attrs=_empty(s, "correlation of the statistical errors of the bins q_bin and q_bin_pair: a window "
                                "correlates the Fourier modes of neighbouring bins (2 S_bb' / (m_b m_b') over the "
                                "relative variances, merged over the files with their weights); the bands' draws "
                                "carry it")) for s in SURFACES},
            "cross_psd_measured": Var("m^4", "measured cross-spectrum Re C12 of the pair",
                                      attrs=_empty("pair", "Persson convention")),
            "coherence": Var("1", "measured coherence eta(q)",
                             attrs=_empty("pair", "eta(q) = Re C12 / sqrt(C11 C22), eq 41")),
            "coherence_error": Var("1", "standard error of the coherence",
                                   attrs=_empty("pair", "statistical standard error of the coherence, "
                                                        "(1 - eta^2) / sqrt(2 n)")),
        },
        coords={"q_bin": Var("1/m", "wavenumber (geometric bin centre)"),
                "q_bin_pair": Var("1/m", "wavenumber of the paired bin",
                                  comment="the second bin of a pair of bins q_bin (same lattice)")},
        figures=(
            Figure("measured_psd", "Measured PSDs", ("topography",), figure_measured_psd),
            Figure("coherence", "Measured coherence eta(q)", ("topography",), figure_coherence),
        ),
        doc="Isotropic PSDs from measured height maps / line scans; cross-spectrum and coherence of paired surfaces.",
    )
)
