"""``python -m attitude`` is the ``attitude`` command."""

import sys

from .cli import main

sys.exit(main())
