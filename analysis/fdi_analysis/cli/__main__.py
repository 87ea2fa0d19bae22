"""`python -m fdi_analysis.cli`: the same program as `fdi-analyze`."""

import sys

from fdi_analysis.cli import main

sys.exit(main())
