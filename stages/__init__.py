"""Physics of roughcontact: one module per quantity, each a pure numpy kernel plus a thin
xarray stage wrapper registered with :mod:`pipeline.stage`. No file I/O here.

Modules whose names start with ``_`` are helpers, not stages.
"""
