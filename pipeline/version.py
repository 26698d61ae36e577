"""The version of roughcontact, a leaf module: setuptools-scm writes it, with the commit, into
``_version.py`` when the package is built (pip install). Modules import ``__version__`` from here,
not from the package (``from . import __version__`` would import ``roughcontact/__init__.py``,
which imports the API, which imports them: a cycle)."""

try:  # written by setuptools-scm when the package is built, from git
    from ._version import __version__
except ImportError:  # pragma: no cover - a source tree that was never built
    __version__ = "0+unbuilt"

__all__ = ["__version__"]
