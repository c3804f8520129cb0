"""``python -m derive`` in a checkout: the same as ``python -m sewgen.derive`` (regenerate or --check generated/).

The derivation lives in the installed package as :mod:`sewgen.derive`; this folder is not installed and only
keeps the short command working from the repository root.
"""
import sys

from sewgen.derive.__main__ import main

sys.exit(main())
