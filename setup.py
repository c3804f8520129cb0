"""Builds the compiled catalog (cffi out-of-line API mode) at install time, one module per SIMD level
(sewgen/engine/build.py catalog_modules); metadata is in pyproject.toml."""
import runpy

from setuptools import setup

setup(cffi_modules=runpy.run_path("sewgen/engine/build.py")["catalog_modules"]())
