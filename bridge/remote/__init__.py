"""``rotor-bridge remote``: the station's rotators on the operator's own computer, through the
station's MQTT broker, as local ports that programs already speak (rotctld, GS-232B and
Easycomm II on TCP or a pty, PstRotator UDP).

The parts: settings/ (the remote's file), rotator.py (a station rotator in the shape rotctld's,
GS-232's and the loggers' commands use, from the station's retained topics), run.py (start-up
and the servers), and the broker connection in interfaces/mqtt/remote.py (paho stays in mqtt/).

Rules:
1. Never late: a command goes out only while connected, with an MQTT 5 expiry, and is never
   queued for a later connection (interfaces/mqtt/remote.py rules 2 and 3).
2. Never stale: a reading is shown only while the station says it is current
   (rotator.py rule 1); otherwise the client gets an error code.
3. The station decides: limits, models and capabilities come from its ``R/info``, and its
   judge has the last word on every command (rotator.py rule 2).
4. Loopback by default: an endpoint listens on 127.0.0.1 unless its bind says otherwise; any
   other address is warned about in the log (the TCP ports by interfaces/tcplines.py, the PstRotator
   UDP port by run.py).
"""
