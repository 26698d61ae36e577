"""Write the example height maps of the built-in `topography` scene (seeded: reproducible).

    python -m roughcontact.scenes.data.make_topographies

Two periodic 256 x 256 maps of 20 um x 20 um, heights in nm (float32 .npy), with self-affine
spectra (H = 0.8, roll-off at 2 pi / 4 um) of rms 60 nm (substrate) and 40 nm (solid); the solid is
h2 = a h1 + b n with n an independent map of the same spectrum, so that its coherence with the
substrate is a / sqrt(a^2 + b^2) = 0.6 at every q.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roughcontact.scenes.data.synthetic import self_affine, synthesize

OUT = Path(__file__).resolve().parent  # next to this maker
N, SIZE, H, Q0 = 256, 20e-6, 0.8, 2 * np.pi / 4e-6
ETA = 0.6


def main() -> None:
    rng = np.random.default_rng(20261121)
    psd = lambda q: self_affine(q, H, Q0, 1.0)  # noqa: E731
    h1 = synthesize(psd, N, N, SIZE, SIZE, rng)
    n = synthesize(psd, N, N, SIZE, SIZE, rng)
    h1 *= 60e-9 / h1.std()
    n *= 60e-9 / n.std()
    h2 = ETA * h1 + np.sqrt(1 - ETA**2) * n
    h2 *= 40e-9 / h2.std()
    OUT.mkdir(parents=True, exist_ok=True)
    np.save(OUT / "substrate_map.npy", (h1 * 1e9).astype(np.float32))
    np.save(OUT / "solid_map.npy", (h2 * 1e9).astype(np.float32))
    print(f"wrote {OUT}/substrate_map.npy and solid_map.npy ({N} x {N}, {SIZE * 1e6:g} um, nm)")


if __name__ == "__main__":
    main()
