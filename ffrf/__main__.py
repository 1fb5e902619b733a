"""``python -m ffrf``: see :mod:`ffrf.cli`."""

import sys

from .cli import main

sys.exit(main())
