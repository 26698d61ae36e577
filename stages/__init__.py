"""Stage declarations of roughcontact: for each derived quantity, which kernels of
:mod:`roughcontact.physics` it calls, which scene keys and upstream results it reads and which
variables it writes (with units and long names). No numerics and no file I/O here.

:mod:`.shared` holds what several stages share, split by meaning (the surfaces, material,
load, interface, magnification and grid sections, the shared coordinates, E*, measured maps,
...); :mod:`.figures` draws stored results. Every other module registers one stage (two for
``validation``) when it is imported.
"""

# the scene sections and coordinates several stages read or write, declared once
from .shared import coordinates, draws, grid, magnification, material, surfaces  # noqa: F401

