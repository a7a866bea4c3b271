"""UDP endpoints for contest and logging programs, beside MQTT and rotctld: PstRotator's
``<PST>`` interface (N1MM, Log4OM, DXLog, QLog, KST4Contest, Minos, horus-gui, Hamlib 4.6's
``rotctl -m 3``) and N1MM Logger+'s rotor messages. Written from
../shared/protocols/logger-udp.md; datagrams.py parses, server.py serves."""

from bridge.loggers.server import LoggerEndpoints

__all__ = ["LoggerEndpoints"]
