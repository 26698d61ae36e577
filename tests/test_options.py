"""Options that every stage follows (issue 24, section 3).

The choice options (schema Param kind "choice") and the stages that read them are taken from the
stage registry: a stage depends on an option when it, or a stage upstream of it, declares the
key in its ``reads``. For every such (stage, option, value), on a small scene: the stage runs (or
refuses the value with a one-line UserError naming a key, in the preflight; never an internal
error), its content key differs from the default value's, and the result says which theory it
used (a global attribute named after the option, or that name + "_source"). Facts a user relies
on: an option accepted by one stage does not crash another, and a result computed under one
option value is never reused for another. Every stage with a choice option has a small scene here
(the BEM stages on 32^2 maps, one pair). The choices of a measured surface (map or container,
substrate or solid) and of a PSD file's convention are followed through to the contact stage.
"""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
from conftest import make_scene

from roughcontact import engine, scene as scenes
from roughcontact.stage import UserError, sections, stages

#: small scenes per stage (its main output asked for); stages not here are listed in NOT_COVERED
DATA = Path(__file__).resolve().parent.parent / "pipeline" / "scenes" / "data"
E_STAR = 77.2e9 / (1 - 0.42**2)
_SMALL = dict(interface={"eta": [0.0]}, load={"p": ["100 MPa", "3 GPa"]}, contact={"zeta": [4.0, 200.0]},
              numerics={"points_per_decade": 10})
_SEAL = {"viscosity": "1 mPa*s", "pressure_drop": "1 kPa", "seal_width": "1 mm", "seal_length": "1 mm"}
_BEM = {"grid": 32, "realizations": 1, "seed": 3, "pixels_per_wavelength": 4}
SCENES: dict[str, dict] = {
    "contact": dict(outputs={"variables": ["contact_area_ratio"]}),
    "separation": dict(outputs={"variables": ["mean_separation"]}),
    "stiffness": dict(outputs={"variables": ["contact_stiffness"]}),
    "conductance": dict(outputs={"variables": ["thermal_contact_conductance"]},
                        conductance={"thermal_conductivity_substrate": "50 W/(m*K)",
                                     "thermal_conductivity_solid": "1 W/(m*K)"}),
    "leakage": dict(outputs={"variables": ["leak_rate_critical_junction"]}, leakage=dict(_SEAL)),
    # a box modulus, flash temperature on (friction.background is read only with it) and the shear laws'
    # parameters given (each is used only under its friction.shear kind): the defaults stay none
    "friction": dict(outputs={"variables": ["friction_coefficient"]},
                     substrate={"kind": "self_affine", "H": 0.9, "qL": "1e4 1/m", "q1": "1e7 1/m", "hrms": "3 um"},
                     solid={"kind": "self_affine", "H": 0.8, "qL": "1e4 1/m", "q1": "1e7 1/m", "hrms": "4 um"},
                     material={"E": "5 MPa", "nu": 0.5}, load={"p": "0.4 MPa"},
                     modulus={"kind": "box", "E0": "5 MPa", "E_inf": "3 GPa", "tau1": "1e-6 s", "tau2": "1e4 s",
                              "T_ref": "-40 degC", "T": "20 degC", "shift": "wlf", "C2": "51.6 K"},
                     friction={"v": ["1e-3 m/s", "1 m/s"], "flash": True, "thermal_conductivity": "0.25 W/(m*K)",
                               "density": "1200 kg/m^3", "heat_capacity": "1500 J/(kg*K)",
                               "sliding_distance": "0.1 m", "shear_tau0": "1 MPa", "shear_v0": "1e-7 m/s",
                               "shear_c": 0.1, "shear_table_v": ["1e-8 m/s", "1 m/s"],
                               "shear_table_tau": ["1 MPa", "0.1 MPa"]},
                     numerics={"points_per_decade": 10, "friction_phi_nodes": 8}),
    # bands over a measured surface (the built-in container) and a few draws: the contact, separation
    # and friction bands, so every option of the stages it draws on is followed
    "bands": dict(outputs={"variables": ["contact_area_ratio_band", "mean_separation_band",
                                         "friction_coefficient_band"]},
                  substrate={"kind": "container", "container": str(DATA / "substrate.zip"), "extend": "power_law"},
                  solid={"kind": "smooth"}, interface={"eta": 0.0}, bands={"draws": 4}, contact={"zeta": [1.0, 100.0]},
                  numerics={"points_per_decade": 20, "friction_phi_nodes": 8}),
    "interface_bem": dict(outputs={"variables": ["exact_leak_rate"]}, leakage=dict(_SEAL), bem=dict(_BEM),
                          substrate={"q0": "8e8 1/m"}, solid={"q0": "8e8 1/m"},
                          numerics={"points_per_decade": 10, "interface_bem_bisections": 2}),
}
SCENES["bands"].update({k: SCENES["friction"][k] for k in ("material", "load", "modulus", "friction")})
#: the validation stages' cases, cut to one H, bandwidth 4 on 16^2 and 32^2 lattices, one pair, two loads
_VALIDATION = {"hurst": [0.8], "bandwidth": [4.0], "reduced_pressure": [0.01, 0.1], "pixels_per_wavelength": [4.0, 8.0],
               "max_grid": 32, "realizations": 1}
SCENES.update({
    # the BEM check of the contact stage on one 32^2 pair (bem.surfaces = measured has no measured maps here:
    # refused in the preflight)
    "bem": dict(outputs={"variables": ["bem_contact_area_ratio"]}, bem=dict(_BEM), contact={"zeta": [8.0]},
                substrate={"q0": "8e8 1/m"}, solid={"q0": "8e8 1/m"}),
    "validation_bem": dict(outputs={"variables": ["validation_deviation_max"]}, validation=dict(_VALIDATION)),
    "validation": dict(outputs={"variables": ["validation_deviation_max"]}, validation=dict(_VALIDATION)),
})
#: stages that depend on a choice option but need inputs this test does not build (say why)
NOT_COVERED: dict[str, str] = {}
#: stages that set every theory variant side by side (the coordinate theory): the option picks which
#: variant takes the scene's contact.gamma, said in the attribute theory_variants
VARIANTS_SIDE_BY_SIDE = {"validation"}
#: stages whose every case needs the optional BEM solver
NEEDS_TAMAAS = {"bem", "interface_bem", "validation_bem", "validation"}


def _choices() -> dict[str, tuple]:
    out = {}
    for name, sec in sections().items():
        for p in (*sec.params, *(p for ps in sec.variants.values() for p in ps)):
            if p.kind == "choice":
                out[f"{name}.{p.name}"] = tuple(p.choices)
    return out


def _closure(name: str, all_stages) -> set[str]:
    seen, todo = set(), [name]
    while todo:
        st = todo.pop()
        if st not in seen:
            seen.add(st)
            todo.extend(all_stages[st].requires)
    return seen


def options_of(name: str) -> dict[str, tuple]:
    """The choice options (dotted keys named in ``reads``) that stage ``name`` or its upstream reads."""
    all_stages, choices = stages(), _choices()
    keys = {k for st in _closure(name, all_stages) for k in all_stages[st].keys if k in choices}
    return {k: choices[k] for k in sorted(keys)}


CASES = [(st, key, value) for st in SCENES for key, values in options_of(st).items() for value in values]


def test_every_stage_with_a_choice_option_is_covered_or_says_why():
    dependent = {name for name in stages() if options_of(name)}
    assert dependent - set(SCENES) - set(NOT_COVERED) == set()
    assert {"stiffness", "conductance", "leakage", "interface_bem", "friction", "bands"} <= set(SCENES)
    assert ("leakage", "contact.correction", "yang_persson") in CASES  # found from the registry, not listed here


def _scene(stage: str, key: str | None = None, value=None) -> dict:
    raw = make_scene(**copy.deepcopy(_SMALL))
    for table, content in copy.deepcopy(SCENES[stage]).items():
        merge = isinstance(content, dict) and "kind" not in content
        raw[table] = {**raw.get(table, {}), **content} if merge else content
    if key is not None:
        section, _, name = key.partition(".")
        raw.setdefault(section, {})[name] = value
    return raw


def _run(raw, outdir):
    return engine.run(scenes.from_dict(raw), outdir, report=engine.Reporter(None))["base"]


#: (option, value) -> (global attribute, text it holds) for the options a stage states in its own words
SAYS = {
    ("friction.correction", "none"): ("area_factor", "S = 1"),
    ("friction.correction", "yang_persson"): ("area_factor", "P^2"),
    ("friction.shear", "none"): ("contact_shear", "none"),
    ("friction.shear", "gaussian"): ("contact_shear", "exp("),
    ("friction.shear", "table"): ("contact_shear", "table"),
    ("friction.background", "none"): ("background_heating", "none"),
    ("friction.background", "semi_infinite"): ("background_heating", "semi-infinite"),
}

_DEFAULTS: dict[str, str] = {}


def _default_key(stage, tmp_path_factory) -> str:
    if stage not in _DEFAULTS:
        _DEFAULTS[stage] = _run(_scene(stage), tmp_path_factory.mktemp(f"default-{stage}"))[stage].attrs["stage_key"]
    return _DEFAULTS[stage]


@pytest.mark.parametrize("stage, key, value", CASES, ids=[f"{s}-{k}={v}" for s, k, v in CASES])
def test_stage_follows_the_option(stage, key, value, tmp_path_factory):
    if stage in NEEDS_TAMAAS:
        pytest.importorskip("tamaas")
    default_key = _default_key(stage, tmp_path_factory)  # the small scene itself runs
    try:
        res = _run(_scene(stage, key, value), tmp_path_factory.mktemp(f"{stage}-{value}"))
    except UserError as exc:  # refused in the preflight with a one-line message naming a key: allowed
        assert exc.key and "\n" not in str(exc), exc
        return
    ds = res[stage]
    default = [p for p in sections()[key.partition(".")[0]].params if p.name == key.partition(".")[2]][0].default
    if value != default:
        assert ds.attrs["stage_key"] != default_key
    # the result says which theory it used, where the stage computes with the option itself (bands:
    # the draws it takes the quantiles of, in the stage that computes with the option)
    if stage == "bands":
        ds = res["friction" if key.startswith("friction.") else "separation"]
    attr = key.replace(".", "_")
    if (key, value) in SAYS:
        attr, text = SAYS[key, value]
        assert text in str(ds.attrs.get(attr, "none")), (attr, ds.attrs.get(attr))
    if key in {"validation.lattice", "bem.surfaces"}:  # the stage's attribute names the choice (auto: the one taken)
        assert ds.attrs[attr] in ((value,) if value != "auto" else ("synthesized", "measured")), (attr, ds.attrs[attr])
    if key in {"contact.correction", "separation.refinement"} and stage not in {"contact", *VARIANTS_SIDE_BY_SIDE}:
        said = f"{ds.attrs.get(attr, '')} {ds.attrs.get(attr + '_source', '')}"
        assert str(value) in said or (key == "separation.refinement" and value == "contact"
                                       and "contact.correction" in said), (attr, said)


@pytest.mark.parametrize("correction", ["yang_persson", "wang_mueser"])
def test_contact_correction_moves_the_sealing_pressure_and_the_leak_rate(correction, tmp_path):
    """A corrected theory has more contact at a given load (G_eff <= G), so it seals at a lower load,
    by the same factor for both theories (the percolation G is p^2 Phi(v_c)/2)."""
    raw = _scene("leakage")
    base = _run(raw, tmp_path / "a")["leakage"]
    raw["contact"]["correction"] = correction
    other = _run(raw, tmp_path / "b")["leakage"]
    for method in ("critical_junction", "effective_medium"):
        ratio = float((other[f"sealing_pressure_{method}"] / base[f"sealing_pressure_{method}"]).squeeze())
        assert 0.5 < ratio < 1.0, ratio
        assert not (other[f"leak_rate_{method}"] == base[f"leak_rate_{method}"]).all()
    assert other.attrs["contact_correction"] == correction


# -- choices read inside whole sections: the modulus kinds and shifts friction depends on, and the
# -- measured-surface options of the psd stage (on the built-in example data)

_BOX = {"kind": "box", "E0": "5 MPa", "E_inf": "3 GPa", "tau1": "1e-6 s", "tau2": "1e4 s"}
MODULI = {
    "box-wlf": None,  # the friction scene's own
    "box-none": dict(_BOX, shift="none"),
    "box-table": dict(_BOX, T_ref="-40 degC", T="20 degC", shift="table", shift_T=["-40 degC", "60 degC"],
                      shift_log10_aT=[0.0, -8.0]),
    "box-entropic": dict(_BOX, T_ref="-40 degC", T="20 degC", shift="wlf", vertical_shift="entropic"),
    "prony": {"kind": "prony", "E0": "5 MPa", "prony_E": ["100 MPa", "1 GPa"], "prony_tau": ["1e-3 s", "1e-6 s"]},
    "elastic": {"kind": "elastic", "E": "7 MPa"},
    "dma-wlf": {"kind": "dma", "sweeps": str(DATA / "dma_example.txt"), "T_ref": "-20 degC", "T": "25 degC",
                "fit": "wlf"},
    "dma-free": {"kind": "dma", "sweeps": str(DATA / "dma_example.txt"), "T_ref": "-20 degC", "T": "25 degC",
                 "fit": "free"},
}


@pytest.mark.parametrize("name", MODULI)
def test_friction_follows_the_modulus_kind_and_shift(name, tmp_path_factory):
    raw = _scene("friction")
    if MODULI[name] is not None:
        raw["modulus"] = copy.deepcopy(MODULI[name])
    try:
        res = _run(raw, tmp_path_factory.mktemp(f"modulus-{name}"))
    except UserError as exc:
        assert exc.key and "\n" not in str(exc), exc
        return
    mod, fric = res["modulus"], res["friction"]
    assert (fric.attrs["stage_key"] == _default_key("friction", tmp_path_factory)) == (MODULI[name] is None)
    assert mod.attrs["model"] == name.partition("-")[0]  # the modulus result says its kind and its shifts
    shift = {"box-none": "none", "box-table": "table", "elastic": "none", "prony": "none"}.get(name, "wlf")
    assert mod.attrs["horizontal_shift"] == shift
    assert mod.attrs["vertical_shift"] == ("entropic" if name == "box-entropic" else "none")


#: the choices of a measured surface, per kind (topography: the built-in topography scene's map; container: the
#: built-in container), for the substrate and for the solid (the same keys, read by the same stages)
SURFACE_CHOICES = {(kind, name): tuple(p.choices) for kind, params in sections()["substrate"].variants.items()
                   if kind in {"topography", "container"} for p in params if p.kind == "choice" for name in [p.name]}
SURFACE_CASES = [(surface, kind, name, value) for surface in ("substrate", "solid")
                 for (kind, name), values in SURFACE_CHOICES.items() for value in values]
_MEASURED = {"topography": {"kind": "topography", "files": [str(DATA / "substrate_map.npy")], "height_unit": "nm",
                            "size_x": "20 um", "periodic": False},
             "container": {"kind": "container", "container": str(DATA / "substrate.zip")}}


def _measured(surface="substrate", kind="topography", name=None, value=None) -> dict:
    """A measured ``surface`` (the other one smooth) of ``kind``, with option ``name`` set to ``value``."""
    other = "solid" if surface == "substrate" else "substrate"
    raw = make_scene(**{surface: dict(_MEASURED[kind]), other: {"kind": "smooth"}},
                     interface={"eta": 0.0}, material={"E": "10 MPa", "nu": 0.5},
                     load={"p": ["10 kPa", "1 MPa"]}, contact={"zeta": [1.0, 10.0]},
                     outputs={"variables": ["contact_area_ratio"]}, numerics={"points_per_decade": 20})
    if name is not None:
        raw[surface][name] = value
    return raw


def test_the_surface_cases_cover_both_kinds_and_both_surfaces():
    names = {(s, k, n) for s, k, n, _ in SURFACE_CASES}
    options = ("fill_undefined", "analysis", "detrend", "window", "extend")
    for surface in ("substrate", "solid"):
        assert {(surface, kind, n) for kind in ("topography", "container") for n in options} <= names


def _surface_param(surface, kind, name, value):
    """The solid's copies run in CI for the last value of each option (the same stages read the same keys of
    either surface), the others with the slow tests."""
    last = SURFACE_CHOICES[kind, name][-1]
    marks = [pytest.mark.slow] if surface == "solid" and value != last else []
    return pytest.param(surface, kind, name, value, marks=marks, id=f"{surface}-{kind}-{name}={value}")


@pytest.mark.parametrize("surface, kind, name, value", [_surface_param(*case) for case in SURFACE_CASES])
def test_a_measured_surface_follows_its_options(surface, kind, name, value, tmp_path_factory):
    """Every value of a measured surface's choice, substrate or solid, map or container, runs (or is
    refused in one line naming a key) through to the contact stage; a value other than the default
    changes the contact key; the measured PSD records the detrending, window and analysis it used
    (fill_undefined and extend are in the result's ``parameters``: the maps have no undefined points
    and the grid asks for no extension)."""
    try:
        res = _run(_measured(surface, kind, name, value), tmp_path_factory.mktemp(f"{surface}-{kind}-{value}"))
    except UserError as exc:
        assert exc.key and "\n" not in str(exc), exc
        return
    if (surface, kind) not in _DEFAULTS:
        _DEFAULTS[surface, kind] = _run(_measured(surface, kind),
                                        tmp_path_factory.mktemp(f"{surface}-{kind}-default"))["contact"].attrs["stage_key"]
    default = [p for p in sections()[surface].variants[kind] if p.name == name][0].default
    if value != default:
        assert res["contact"].attrs["stage_key"] != _DEFAULTS[surface, kind]
    if name in {"detrend", "window", "analysis"}:
        assert f'"{name}": "{value}"' in res["topography"][f"psd_{surface}_measured"].attrs["files"]


CONVENTIONS = sections()["substrate"].variants["psd_file"]
CONVENTION_CASES = [(surface, value) for surface in ("substrate", "solid")
                    for value in [p for p in CONVENTIONS if p.name == "convention"][0].choices]


@pytest.mark.parametrize("surface, convention", CONVENTION_CASES, ids=[f"{s}={c}" for s, c in CONVENTION_CASES])
def test_a_psd_file_follows_its_convention(surface, convention, tmp_path_factory):
    """Every convention of a PSD file (substrate or solid) runs to the contact stage, changes its key,
    and the psd stage's PSD of that surface says which convention it read."""
    import numpy as np

    folder = tmp_path_factory.mktemp(f"psd-{surface}-{convention}")
    q = np.geomspace(1e4, 1e8, 41)
    C = 1e-30 * (q / 1e4) ** -3.6 * (1.0 if convention in {"persson", "contact.engineering"} else q / 1e4 * 1e-4)
    np.savetxt(folder / "psd.txt", np.column_stack([q, C]),
               header=f"q [1/m]  C [{'m^3' if convention.startswith('1d') else 'm^4'}]")
    other = "solid" if surface == "substrate" else "substrate"
    raw = make_scene(**{surface: {"kind": "psd_file", "path": str(folder / "psd.txt"), "convention": convention,
                                  "hurst": 0.8},
                        other: {"kind": "smooth"}},
                     interface={"eta": 0.0}, material={"E": "10 MPa", "nu": 0.5}, load={"p": ["10 kPa", "1 MPa"]},
                     contact={"zeta": [1.0, 10.0]}, grid={"q_min": "1e4 1/m", "q_max": "1e8 1/m"},
                     outputs={"variables": ["contact_area_ratio"]}, numerics={"points_per_decade": 10})
    res = _run(raw, folder / "out")
    key = ("psd_file", surface)
    if key not in _DEFAULTS:
        raw[surface]["convention"] = "persson"
        _DEFAULTS[key] = _run(raw, folder / "default")["contact"].attrs["stage_key"]
    assert (res["contact"].attrs["stage_key"] != _DEFAULTS[key]) == (convention != "persson")
    assert convention in res["psd"][f"psd_{surface}"].attrs["psd_convention"]
