import sys

from visprim.cli.main import main

sys.exit(main())
