"""`python -m fdi_host.tuning.cli` = `fdi-tune`."""

import sys

from fdi_host.tuning.cli import main

sys.exit(main())
