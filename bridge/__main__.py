"""`python -m bridge`: the command line (cli.py). A Ctrl-C while it loads is one line and exit
code 2 (cli.main says the same of one before a command has the signals), not a traceback."""

import sys

try:
    from bridge.cli import main
except KeyboardInterrupt:
    print("rotor-bridge: stopped before it started", file=sys.stderr)
    sys.exit(2)

sys.exit(main())
