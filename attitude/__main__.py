"""``python -m attitude`` is the ``attitude`` command."""

import sys

from .app.cli import main

sys.exit(main())
