"""`python -m bridge.emulators MODEL [options]`: the same as `rotor-bridge emulate`."""

import sys

from bridge.emulators.cli import main

sys.exit(main())
