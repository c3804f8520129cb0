"""``python -m sewgen ...``: the same as the ``sewgen`` command."""
import sys

from .cli import main

sys.exit(main())
