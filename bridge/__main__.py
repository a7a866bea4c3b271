"""`python -m bridge`: the command line (cli.py)."""

import sys

from bridge.cli import main

sys.exit(main())
