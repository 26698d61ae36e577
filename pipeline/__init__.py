"""roughcontact: Persson's contact mechanics for two rough surfaces, as a staged pipeline.

The Python API (:mod:`roughcontact.api`, documented in docs/api.md) is available at the top
level and imported on first use, so that ``import roughcontact`` stays cheap::

    import roughcontact as rc
    scene = rc.load_scene("default")          # a file, a built-in name or a dict
    results = rc.run(scene, outdir="outputs/default", progress=False)
    results["base"]["contact"]                # an xarray Dataset per variant and stage
    rc.compute(scene)["base"]["contact"]      # the same, computed in memory (no file)

The package has three layers (docs/architecture.md):

* :mod:`roughcontact.physics`: pure numpy kernels, one function per equation (docs/theory.md);
* :mod:`roughcontact.stages`: thin declarations wiring kernels to scene keys and to labelled
  outputs (units and long names declared once);
* the engine (this package's own modules: :mod:`~roughcontact.scene`, :mod:`~roughcontact.engine`,
  :mod:`~roughcontact.store`, :mod:`~roughcontact.readers`, :mod:`~roughcontact.cli`, ...): scenes,
  planning, hashing, caching, file I/O and scheduling. It knows no physics and reaches the stages
  only through the registry of :mod:`roughcontact.stage`.
"""

from .version import __version__  # the modules import it from there too (no cycle through this file)

#: the Python API, re-exported from roughcontact.api on first use
API = ("load_scene", "plan", "run", "compute", "open_result", "builtin_scenes", "Results")

__all__ = ["__version__", *API]


def __getattr__(name: str):
    if name in API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'roughcontact' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(API))
