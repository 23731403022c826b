"""``python -m crmgrasp``: the ``crmgrasp`` command."""

import sys

from .cli import main

sys.exit(main())
