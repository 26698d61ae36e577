"""Pure numpy kernels of roughcontact: every equation the project implements.

No registry, no xarray, no file I/O: each function takes arrays in SI units and returns
arrays in SI units, with its equation, units and references in its docstring. The stages
(:mod:`roughcontact.stages`) declare how scene keys and upstream results feed these
functions; the theory they implement is stated in ``docs/theory.md``.

Modules
-------
quadrature   the one quadrature of the project (piecewise power-law integrals on log grids)
roots        the one bracketing root finder
spectra      self-affine PSDs, the combined PSD of two surfaces, PSD conventions
contact      G(zeta), A/A0, P(sigma) (non-adhesive contact)
corrections  contact-area corrections (Yang-Persson, Wang-Mueser): the variance ODE solved exactly; theory variants
separation   mean interfacial separation u(p)
adhesion     full-contact adhesion (effective surface energy)
volterra     partial-contact adhesion (the marching Volterra solver)
viscoelastic complex modulus models and temperature shifts
friction     viscoelastic (hysteretic) rubber friction
flash        flash temperature of rubber friction (marched in q) and background heating
mastercurve  master curves from DMA sweeps: shifts, WLF fit, relaxation spectrum, Kramers-Kronig check
estimators   spectral estimators on measured maps and profiles (PSD, coherence)
modes        independent Fourier modes of windowed scans (how a window correlates modes)
uncertainty  errors of measured spectra on the grid, spectra drawn within them, quantiles
preprocessing  detrending, windows and the tip-radius cutoff of measured scans
synthesis    random periodic surface pairs with given spectra and coherence; band limit of a map
bem          the exact FFT boundary-element contact solve (tamaas, optional)
validation   the validation's BEM tasks, Richardson extrapolation of the area, lattice moments, deviations
"""
