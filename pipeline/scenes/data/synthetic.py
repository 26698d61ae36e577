"""Synthetic random surfaces (Fourier synthesis): what the example-data makers of this folder use, and
the topography tests and benchmark."""

from __future__ import annotations

import numpy as np


def wavevectors(nx, ny, sx, sy):
    qx = 2 * np.pi * np.fft.fftfreq(nx, d=sx / nx)
    qy = 2 * np.pi * np.fft.fftfreq(ny, d=sy / ny)
    return np.sqrt(qx[:, None] ** 2 + qy[None, :] ** 2)


def self_affine(q, H, q0, C0):
    """Persson-convention PSD: C0 for 0 < q < q0, C0 (q/q0)^(-2(1+H)) above, 0 at q = 0."""
    q = np.asarray(q, float)
    with np.errstate(divide="ignore"):
        C = np.where(q < q0, C0, C0 * (np.maximum(q, q0) / q0) ** (-2 * (1 + H)))
    return np.where(q > 0, C, 0.0)


def synthesize(psd, nx, ny, sx, sy, rng):
    """A periodic Gaussian random map (m) whose expected PSD (Persson convention) is psd(q):
    E|DFT h|^2 = N^2 C(q) (2 pi)^2 / (Lx Ly)."""
    q = wavevectors(nx, ny, sx, sy)
    amp = nx * ny * np.sqrt(2.0 * psd(q) * (2 * np.pi) ** 2 / (sx * sy))
    z = (rng.standard_normal((nx, ny)) + 1j * rng.standard_normal((nx, ny))) / np.sqrt(2.0)
    return np.fft.ifft2(amp * z).real
