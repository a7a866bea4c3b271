"""UDP endpoints for contest and logging programs, beside MQTT and rotctld: PstRotator's
``<PST>`` interface (N1MM, Log4OM, DXLog, QLog, KST4Contest, Minos, horus-gui, Hamlib 4.6's
``rotctl -m 3``) and N1MM Logger+'s rotor messages. Written from
../shared/protocols/logger-udp.md; datagrams.py parses, commands.py turns a datagram into a
command or a reply, server.py owns the sockets and the thread."""

from bridge.interfaces.loggers.server import LoggerEndpoints

__all__ = ["LoggerEndpoints"]
