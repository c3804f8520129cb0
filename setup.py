"""Builds the compiled catalog (cffi out-of-line API mode) at install time; metadata is in pyproject.toml."""
from setuptools import setup

setup(cffi_modules=["sewgen/build.py:catalog_ffi"])
