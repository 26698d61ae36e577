"""The command line's xarray: no dask.array and pint imported to build an in-memory numpy result.

Every ``xarray.Variable`` built from numpy data asks whether the data is a dask array
(``as_compatible_data``), and every index asks whether it is a pint quantity (``to_numpy``).
xarray answers with ``isinstance(data, array_type(name))``, and ``array_type`` imports the
module behind ``name`` whenever it is installed, used or not; its ``is_dask_collection`` imports
dask to ask about a plain numpy array. Together 0.25 s of dask, dask.array (with scipy.sparse and
scipy.fft) and pint on every small run: more than half the time of importing numpy and xarray
themselves (docs/scale-out.md, "Cold start"). xarray's own comment on the class doing this says
it exists "to only import pint when required".

No object can be an instance of a class that has not been imported yet, and a numpy array or
scalar has no ``__dask_graph__``. So until ``dask.array`` (or ``pint``) is in ``sys.modules`` the
exact answer to "is this a dask array?" is "no", found without importing anything. :func:`install`
puts an entry in xarray's cache of duck-array modules that gives that answer while the module is
absent and hands over to xarray's own entry (which then imports nothing new) as soon as anything
has imported it: a chunked sweep, ``xarray.open_dataset(..., chunks=...)``, a user's own ``import
dask.array``; any other question (the module, its version, whether it is available) goes to
xarray's own entry at once. It also answers ``is_dask_collection`` for a numpy array or scalar
while dask is not imported, and hands everything else to xarray's function.

This changes another library's private state, so only roughcontact's own program does it: the
command line (:mod:`roughcontact.cli`) calls :func:`install` for the commands that compute or
read results. ``import roughcontact`` (the Python API, in a user's process) leaves xarray as it is.
:func:`install` does nothing, and says so, with an xarray laid out otherwise than the one this was
written against (the cache, its class, ``array_type`` and ``is_dask_collection`` present): xarray
then imports what it always imported (``tests/test_duckarrays.py``).
"""

from __future__ import annotations

import sys

import numpy as np

try:
    from xarray.namedarray import pycompat as _pycompat, utils as _utils
except ImportError:  # an xarray without namedarray: leave it as it is
    _pycompat = _utils = None

#: xarray's name of a duck-array library -> the module whose import makes its array type exist
WATCHED = {"dask": "dask.array", "pint": "pint"}


def _imported(module: str) -> bool:
    """Whether ``module`` has been imported (and is not still running its own import)."""
    loaded = sys.modules.get(module)
    return loaded is not None and not getattr(getattr(loaded, "__spec__", None), "_initializing", False)


def supported() -> bool:
    """Whether this xarray is laid out as :func:`install` expects."""
    return (
        _pycompat is not None
        and isinstance(getattr(_pycompat, "_cached_duck_array_modules", None), dict)
        and isinstance(getattr(_pycompat, "DuckArrayModule", None), type)
        and callable(getattr(_pycompat, "array_type", None))
        and callable(getattr(_utils, "is_dask_collection", None))
    )


if supported():

    class _UntilImported(_pycompat.DuckArrayModule):
        """xarray's cache entry for a duck-array library not imported yet (see the module doc)."""

        def __init__(self, name: str) -> None:  # noqa: D107 - deliberately not the parent's (it imports)
            self._name = name

        def _xarrays_own(self):
            own = _pycompat.DuckArrayModule(self._name)
            _pycompat._cached_duck_array_modules[self._name] = own
            return own

        @property
        def type(self):
            if _imported(WATCHED[self._name]):
                return self._xarrays_own().type
            return ()

        @property
        def module(self):
            return self._xarrays_own().module

        @property
        def version(self):
            return self._xarrays_own().version

        @property
        def available(self):
            return self._xarrays_own().available


    def _is_dask_collection(x, _xarrays_own=_utils.is_dask_collection) -> bool:
        """xarray's ``is_dask_collection``, answered without importing dask for a plain numpy array.

        A numpy array or scalar has no ``__dask_graph__``, so it is never a dask collection;
        anything else, and everything once dask is imported, goes to xarray's own function (which
        imports dask)."""
        if (type(x) is np.ndarray or isinstance(x, np.generic)) and not _imported("dask"):
            return False
        return _xarrays_own(x)


def install() -> bool:
    """Put the not-yet-imported entries in xarray's cache and the numpy shortcut in front of
    xarray's ``is_dask_collection``; True if they are (or already were) there.

    Libraries already imported, or already asked about, are left with xarray's own entry.
    """
    if not supported():
        return False
    cache = _pycompat._cached_duck_array_modules
    for name, module in WATCHED.items():
        if name not in cache and not _imported(module):
            cache[name] = _UntilImported(name)
    if _utils.is_dask_collection.__name__ != "_is_dask_collection":
        _utils.is_dask_collection = _is_dask_collection
    return True


def installed(name: str) -> bool:
    """Whether xarray's cache holds the not-yet-imported entry for ``name`` (for tests)."""
    return supported() and type(_pycompat._cached_duck_array_modules.get(name)).__name__ == "_UntilImported"

