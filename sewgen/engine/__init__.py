"""The engine: a compiled mechanism swept over shaft angles (and designs) in one call into C.

Reads only the leaves (units, errors, abi, roles, hermite) and, to build a mechanism not yet compiled,
:mod:`sewgen.derive`. ``description`` (the typed description of a compiled mechanism), ``build`` and
``loader`` (cffi builds and the module cache), ``mechanism`` (the prepared call), ``designs`` (many designs
at once), ``results``, ``forces``, ``loads``, ``frames`` (results as pandas / xarray tables).
"""
