"""``python -m crmgrasp.cli``: the ``crmgrasp`` command."""

import sys

from crmgrasp.cli.main import main

sys.exit(main())
