"""Thin-film (Reynolds) flow through the gap between two contacting rough surfaces: the exact
leak rate of a periodic gap map, against which the leakage theories are checked.

A Newtonian liquid of viscosity mu in a gap g(x) much thinner than its lateral variations
flows as q = -(g^3 / 12 mu) grad P (per unit width), and mass conservation gives

    div(g^3 grad P) = 0,

with no flow through the contact (g = 0). On a periodic N x M map (pixel dx, square) the
pressure is P = -G x + phi with phi periodic: periodic sideways and along the flow, the mean
gradient G imposed along the flow. Finite volumes on the pixels, the face conductance the
harmonic mean of the two pixels' g^3 (zero next to a contact pixel), the sparse system solved
directly (scipy.sparse, SuperLU); one pressure per fluid cluster is pinned (an isolated pool
carries no net flow, and its level is arbitrary). The result is the effective flow factor

    sigma = 12 mu <flux per unit width> / G   (m^3),

so that a seal of width W and length L leaks Q = (W/L) sigma dp / (12 mu). sigma = g^3 for a
uniform gap; 1/<g^-3> for a gap varying along the flow only, <g^3> across it (exact on the
lattice: the sums are the periodic trapezoid rule). See docs/theory.md, section "Interface:
stiffness, conductance, leakage"; Dapp, Luecke, Persson & Mueser, Phys. Rev. Lett. 108,
244301 (2012).
"""

from __future__ import annotations

import numpy as np


def face_conductances(c, axis):
    """Harmonic means 2 c_i c_j / (c_i + c_j) of neighbouring cells along ``axis`` (periodic):
    entry i is the face between cell i and cell i + 1. Zero where either cell is closed."""
    nb = np.roll(c, -1, axis)
    total = c + nb
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(total > 0, 2.0 * c * nb / np.where(total > 0, total, 1.0), 0.0)


def _graph(faces, shape):
    """Sparse adjacency (weights = face conductances) of the periodic grid from the two face arrays."""
    import scipy.sparse as sp  # on first use: the stage declarations load this module at every run
    idx = np.arange(np.prod(shape)).reshape(shape)
    rows, cols, vals = [], [], []
    for axis, f in enumerate(faces):
        nb = np.roll(idx, -1, axis)
        keep = f.ravel() > 0
        rows += [idx.ravel()[keep], nb.ravel()[keep]]
        cols += [nb.ravel()[keep], idx.ravel()[keep]]
        vals += [f.ravel()[keep]] * 2
    n = idx.size
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def percolates(open_cells, axis):
    """Whether the open cells (bool map, periodic) hold a path that wraps around along ``axis``.

    Cut the torus along ``axis`` (drop the faces from the last row to the first), label the
    clusters of the cut map, then follow the cut faces between clusters, each a step of +1 in
    the winding number: the open region percolates along ``axis`` exactly when a cluster is
    reached twice with different windings.
    """
    return bool(_winding_clusters(open_cells, axis, first=True)[1])


def percolating_cells(open_cells, axis):
    """The open cells of the clusters that wrap around the periodic map along ``axis``: the
    channels through which a fluid can cross the map (the rest of the open area is pools).

    Parameters
    ----------
    open_cells : bool array (nx, ny)
        Open (non-contact) cells of a periodic map.
    axis : int
        0: paths along the first index, 1: along the second.

    Returns
    -------
    bool array (nx, ny)
        True on every cell of a cluster that percolates along ``axis`` (:func:`percolates` is
        whether any cell is True); a cluster is the set of open cells joined through open
        neighbours (4-connected, periodic).

    References
    ----------
    Dapp, Luecke, Persson & Mueser, Phys. Rev. Lett. 108, 244301 (2012); docs/interface.md.
    """
    label, found = _winding_clusters(open_cells, axis)
    return np.isin(label, list(found)) & np.asarray(open_cells, dtype=bool)


def _winding_clusters(open_cells, axis, first=False):
    """(labels of the clusters of the map cut along ``axis``, the labels of those that belong to
    a cluster of the whole torus that wraps around along ``axis``); with ``first``, stop at the
    first such cluster found."""
    from scipy.sparse.csgraph import connected_components

    open_cells = np.asarray(open_cells, dtype=bool)
    shape = open_cells.shape
    faces = [(open_cells & np.roll(open_cells, -1, a)).astype(float) for a in (0, 1)]
    wrap = np.take(faces[axis], [shape[axis] - 1], axis=axis).ravel() > 0
    cut = [f.copy() for f in faces]
    index = [slice(None)] * 2
    index[axis] = shape[axis] - 1
    cut[axis][tuple(index)] = 0.0
    _, label = connected_components(_graph(cut, shape), directed=False)
    label = label.reshape(shape)
    top = np.take(label, [shape[axis] - 1], axis=axis).ravel()[wrap]
    bottom = np.take(label, [0], axis=axis).ravel()[wrap]
    winding: dict[int, int] = {}
    links: dict[int, list[tuple[int, int]]] = {}
    for a, b in zip(top.tolist(), bottom.tolist(), strict=True):
        links.setdefault(a, []).append((b, 1))
        links.setdefault(b, []).append((a, -1))
    found: set[int] = set()
    for start in links:
        if start in winding:
            continue
        winding[start] = 0
        todo, members, wraps = [start], [start], False
        while todo:
            a = todo.pop()
            for b, step in links[a]:
                if b not in winding:
                    winding[b] = winding[a] + step
                    todo.append(b)
                    members.append(b)
                elif winding[b] != winding[a] + step:
                    wraps = True
                    if first:
                        return label, {start}
        if wraps:
            found.update(members)
    return label, found


def flow_factors(gap, axes=(0, 1)):
    """Effective flow factor sigma (m^3) of a periodic gap map for flow along each of ``axes``.

    Parameters
    ----------
    gap : array (nx, ny)
        Local gap g >= 0 (m); 0 marks contact (closed to flow). Square pixels (the pixel size
        drops out of sigma).
    axes : tuple of int
        Flow directions (0: along the first index, 1: along the second).

    Returns
    -------
    array (len(axes),)
        sigma per direction (m^3), exactly 0 where the open gap does not percolate along it.

    References
    ----------
    Reynolds, Phil. Trans. R. Soc. 177, 157 (1886); Dapp et al., Phys. Rev. Lett. 108, 244301
    (2012); docs/theory.md, section "Interface: stiffness, conductance, leakage".
    """
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    from scipy.sparse.linalg import splu

    g = np.maximum(np.asarray(gap, dtype=float), 0.0)
    shape = g.shape
    scale = float(g.max()) if g.size and g.max() > 0 else 1.0
    c = (g / scale) ** 3
    faces = [face_conductances(c, a) for a in (0, 1)]
    out = np.zeros(len(axes))
    wanted = [k for k, a in enumerate(axes) if percolates(g > 0, a)]
    if not wanted:
        return out
    adjacency = _graph(faces, shape)
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    ncomp, label = connected_components(adjacency, directed=False)
    pin = np.zeros(degree.size)
    pin[np.unique(label, return_index=True)[1]] = max(float(degree.max()), 1.0)  # phi = 0, one cell per cluster
    lu = splu((sp.diags(degree + pin) - adjacency).tocsc(), permc_spec="MMD_AT_PLUS_A")
    for k in wanted:
        f = faces[axes[k]]
        # unit drop per pixel along the axis: sum over faces of f (phi_i - phi_nb + 1) = 0 per cell
        rhs = np.roll(f, 1, axes[k]) - f
        phi = lu.solve(rhs.ravel()).reshape(shape)
        flux = f * (phi - np.roll(phi, -1, axes[k]) + 1.0)
        out[k] = float(flux.mean()) * scale**3
    return out
