"""Write the example contact.engineering containers of the built-in `container` scene (seeded).

    python -m roughcontact.scenes.data.make_container

A contact.engineering container is a ZIP file with the raw data file of every measurement of a
surface and the metadata (`meta.yml`, and `index.json` in newer exports): name, data file,
physical size, height unit, height scale, detrending, periodicity and the instrument with its
reliability parameters. This script writes two such containers, `substrate.zip` and
`solid.zip`, into pipeline/scenes/data/, each a surface measured at two scales:

* "profilometer 80 um": 128 x 128 points over 80 um x 80 um, an x3p file (heights in um; the
  file carries its unit and size), an optical instrument of lateral resolution 1.5 um;
* "AFM 10 um": 128 x 128 points over 10 um x 10 um, a bare .npy array of raw heights in
  instrument counts: unit (nm), size and height scale (0.05 nm per count) come from the
  metadata only; a scanning probe with a 40 nm tip.

Both are crops of larger random surfaces (not periodic: the pipeline detrends and windows
them) with one self-affine spectrum (H = 0.8, roll-off at 2 pi / 20 um, rms 0.4 um for the
substrate, 0.25 um for the solid). The solid's measurements are taken at the same places as
the substrate's, h_solid = a h_substrate + b n (n independent), so that the two containers pair
up and their coherence is 0.6 at every q (`interface.eta = "measured"`).

`write_container` is also what the tests use to build containers with known spectra.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import yaml

from roughcontact.scenes.data.synthetic import self_affine, synthesize, wavevectors

OUT = Path(__file__).resolve().parent  # next to this maker
H, Q0, N, ETA = 0.8, 2 * np.pi / 20e-6, 128, 0.6
SCALES = (  # name, side (m), crop factor, unit, height scale, instrument, file format
    ("profilometer 80 um", 80e-6, 4, "um", None,
     {"name": "optical profilometer", "type": "microscope-based",
      "parameters": {"resolution": {"value": 1.5, "unit": "um"}}},
     "x3p"),
    ("AFM 10 um", 10e-6, 4, "nm", 0.05,
     {"name": "AFM", "type": "contact-based", "parameters": {"tip_radius": {"value": 40, "unit": "nm"}}}, "npy"),
)


_METRES = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}


def _npy(a) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, np.asarray(a))
    return buffer.getvalue()


def _x3p(heights, size, unit) -> bytes:
    """An ISO 25178-72 (x3p) file, the format of many optical instruments: it carries its unit and sizes."""
    from SurfaceTopography import Topography

    buffer = io.BytesIO()
    Topography(np.asarray(heights, dtype=float), tuple(size), unit=unit).to_x3p(buffer, dtype="F")
    return buffer.getvalue()


def write_container(path, surface: str, measurements: list[dict], index_json: bool = True) -> None:
    """Write a contact.engineering container.

    Each measurement is a dict with ``name``, ``heights`` (array, in ``unit`` / ``height_scale``),
    ``format`` (``"npy"``, default: bare numbers, units and sizes from the metadata only; or
    ``"x3p"``: the file carries ``unit`` and ``size`` itself), ``datafile`` (its name in the
    archive; default ``<name>.<format>``) and optional metadata keys ``size`` (list, in
    ``unit``), ``unit``, ``height_scale``, ``detrend_mode``, ``is_periodic``, ``instrument``; a
    ``raw`` entry (bytes) replaces the data file's contents. ``index_json``: also write the
    schema-validated ``index.json`` (else only ``meta.yml``, as older exports).
    """
    topographies, files = [], {}
    for m in measurements:
        fmt = m.get("format", "npy")
        datafile = m.get("datafile", f"{m['name'].replace(' ', '_')}.{fmt}")
        if "raw" in m:
            files[datafile] = m["raw"]
        else:
            files[datafile] = _x3p(m["heights"], m["size"], m["unit"]) if fmt == "x3p" else _npy(m["heights"])
        meta = {"name": m["name"], "datafile": {"original": datafile}}
        meta.update({k: m[k] for k in ("size", "unit", "height_scale", "detrend_mode", "is_periodic", "instrument")
                     if m.get(k) is not None})
        if fmt == "x3p" and "raw" not in m:  # x3p stores metres: the metadata says what the file says
            meta.update(unit="m", size=[float(v) * _METRES[m["unit"]] for v in m["size"]])
        topographies.append(meta)
    tree = {"versions": {"roughcontact example": "1"}, "surfaces": [{"name": surface, "topographies": topographies}]}
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("meta.yml", yaml.safe_dump(tree, sort_keys=False))
        if index_json:
            z.writestr("index.json", json.dumps(tree, indent=1))
        for name, data in files.items():
            z.writestr(name, data)


def example_measurements(rng, hrms: float, partner=None, eta: float = ETA) -> list[dict]:
    """The example's measurements of one surface (the larger periodic surface each is cropped
    from, in m, under ``"h_big"``); with ``partner`` (the other surface's list) taken at the
    same places, with coherence ``eta`` at every q. The spectrum is scaled so that its expected
    (not its realised) rms is ``hrms``: a realised rms depends on the few longest waves and would
    tilt the coherence."""
    out = []
    for i, (name, side, crop, unit, scale, instrument, fmt) in enumerate(SCALES):
        big, n = crop * side, crop * N
        q = wavevectors(n, n, big, big)
        norm = hrms**2 / np.sum(self_affine(q, H, Q0, 1.0) * (2 * np.pi / big) ** 2)

        def psd(q, norm=norm):
            return self_affine(q, H, Q0, norm)

        h = synthesize(psd, n, n, big, big, rng)
        if partner is not None:
            ratio = hrms / partner[i]["hrms"]
            h = ratio * eta * partner[i]["h_big"] + np.sqrt(1 - eta**2) * h
        factor = {"um": 1e-6, "nm": 1e-9}[unit] * (scale or 1.0)
        out.append({"name": name, "heights": (h[:N, :N] / factor).astype(np.float32),
                    "size": [side / {"um": 1e-6, "nm": 1e-9}[unit]] * 2, "unit": unit, "height_scale": scale,
                    "detrend_mode": "height", "is_periodic": False, "instrument": instrument, "format": fmt,
                    "h_big": h, "hrms": hrms})
    return out


def main() -> None:
    rng = np.random.default_rng(20261219)
    substrate = example_measurements(rng, 0.4e-6)
    solid = example_measurements(rng, 0.25e-6, partner=substrate)
    OUT.mkdir(parents=True, exist_ok=True)
    write_container(OUT / "substrate.zip", "steel substrate", substrate)
    write_container(OUT / "solid.zip", "elastomer", solid)
    print(f"wrote {OUT}/substrate.zip and solid.zip (2 measurements each, {N} x {N} points)")


if __name__ == "__main__":
    main()
