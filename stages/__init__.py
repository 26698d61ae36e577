"""Stage declarations of roughcontact: for each derived quantity, which kernels of
:mod:`roughcontact.physics` it calls, which scene keys and upstream results it reads and which
variables it writes (with units and long names). No numerics and no file I/O here.

:mod:`.shared` declares what several stages read (the surfaces, material, load, interface
and grid sections, the shared coordinates, E*); :mod:`.figures` draws stored results.
Every other module registers one stage when it is imported.
"""
