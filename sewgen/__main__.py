"""``python -m sewgen ...``: the same as the ``sewgen`` command."""
import sys

from sewgen.cli.main import main

sys.exit(main())
