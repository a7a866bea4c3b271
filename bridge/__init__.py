"""rotor-bridge: antenna rotator controllers on MQTT. The map of the package is
docs/architecture.md; the command line is cli.py."""

__version__ = "0.1.0"
