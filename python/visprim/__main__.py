"""``python -m visprim``: the same command line as ``visprim``."""

import sys

from visprim.cli.main import main

sys.exit(main())
