"""roughcontact: Persson's contact mechanics for two rough surfaces, as a staged pipeline.

The package has three layers (docs/architecture.md):

* :mod:`roughcontact.physics`: pure numpy kernels, one function per equation;
* :mod:`roughcontact.stages`: thin declarations wiring kernels to scene keys and to labelled
  outputs (units and long names declared once);
* the engine (this package's own modules: :mod:`~roughcontact.scene`, :mod:`~roughcontact.engine`,
  :mod:`~roughcontact.store`, :mod:`~roughcontact.readers`, :mod:`~roughcontact.cli`, ...): scenes,
  planning, hashing, caching, file I/O and scheduling. It knows no physics and reaches the stages
  only through the registry of :mod:`roughcontact.stage`.
"""

__version__ = "0.1.0"
