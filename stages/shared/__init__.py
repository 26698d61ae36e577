"""What several stages share, split by meaning; not stages (the registry imports only the
modules directly in ``stages/``).

* :mod:`.coordinates`: the coordinates several stages write (q, p, eta, zeta, v, T, ...);
* :mod:`.material`: the elastic solid, its load and E*;
* :mod:`.surfaces`: the two surfaces and their coherence;
* :mod:`.grid`: the wavenumber grid and its reference qL;
* :mod:`.magnification`: the magnifications asked for and the contact-area correction;
* :mod:`.draws`: the spectrum draws of the uncertainty bands;
* :mod:`.maps`, :mod:`.measured`: measured height maps and their statistical errors;
* :mod:`.mastercurve`: DMA frequency sweeps shifted onto a master curve (the modulus stage's
  ``dma`` source);
* :mod:`.flash`: the flash-temperature option of the friction stage;
* :mod:`.variants`, :mod:`.validation_table`: the theory variants set against exact numerics,
  and the validation stage's reductions;
* :mod:`.bem_solve`, :mod:`.bem_theory`, :mod:`.bem_hardness`, :mod:`.bem_fields`: the BEM's
  surface pairs solved (``bem`` and ``interface_bem`` stages), the theory at its magnification,
  its elastoplastic outputs, its pressure and gap maps.

Each module declares its scene sections and coordinates once, at import.
"""
