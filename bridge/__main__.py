"""`python -m bridge` and the installed `rotor-bridge` (pyproject's [project.scripts]): the
command line (cli.py). A Ctrl-C while it loads is one line and exit code 2 (cli.main says the
same of one before a command has the signals), not a traceback."""

import sys


def main() -> int:
    try:
        from bridge.cli import main as cli_main
    except KeyboardInterrupt:
        print("rotor-bridge: stopped before it started", file=sys.stderr)
        return 2
    return cli_main()


if __name__ == "__main__":
    sys.exit(main())
