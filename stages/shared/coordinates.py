"""The coordinates several stages write, declared once (units and long names): q, p, eta,
zeta, the hrms sweeps, v, T, omega and the spectrum draw."""

from __future__ import annotations

from roughcontact.stage import Var, register_coords

register_coords(
    q=Var("1/m", "wavenumber"),
    p=Var("Pa", "nominal pressure"),
    eta=Var("1", "coherence of the two surfaces' roughness"),
    zeta=Var("1", "magnification zeta = q/qL"),
    hrms_substrate=Var("m", "rms roughness of the substrate"),
    hrms_solid=Var("m", "rms roughness of the solid"),
    v=Var("m/s", "sliding velocity"),
    # CF has no standard name for the temperature of a solid (its temperature names are of the air, sea,
    # soil, ...); CF-1.11's units_metadata says it is a temperature on its scale, not a difference
    T=Var("K", "temperature", attrs={"units_metadata": "temperature: on_scale"}),
    omega=Var("rad/s", "angular frequency"),
    draw=Var("1", "spectrum draw", standard_name="realization", attrs={
        "comment": "0 is the measured spectrum; 1..N are spectra drawn within its statistical band"}),
)
