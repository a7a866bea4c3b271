"""paho's client as every broker connection of the bridge builds it (connection.py uses it for
the main connection, the stop lane and the remote's link): protocol, session, credentials and
TLS (connection.py rule 1), the kernel's quick acknowledgement after every read (connection.py
rule 9, where it is explained), and a tick on paho's own thread.

Rules:
1. ``new_client`` builds paho's client for the settings: MQTT 5 or 3.1.1, credentials, TLS.
2. ``tick``, when set, is called on paho's thread after each round of its loop (at least once a
   second while connected: its select waits 1 s at most), for what a connection does on a clock
   without a thread of its own (the station's heartbeat, client.py rule 2). It must be cheap;
   one that raises is logged and paho's thread goes on.
3. ``use_mqtt311`` turns a client built for MQTT 5 into one that speaks MQTT 3.1.1 with a clean
   session from its next connection on (``mqtt.protocol = "auto"``, connection.py rule 1), as
   paho itself steps down from 3.1.1 to 3.1 on a refusal: its CONNECT is built from these two
   attributes on every connect (tests/mqtt/test_protocol_fallback.py holds paho to that).
4. ``accepts_mqtt311`` asks a broker once whether it accepts an MQTT 3.1.1 connection with these
   settings (credentials, TLS, client id; no will, nothing subscribed or published): a trial
   connection, closed as soon as the broker answered, within ``timeout_s``. It blocks: never on
   paho's thread.
5. A broker that never answers the CONNECT is given CONNACK_TIMEOUT_S, then the connection is
   ended as if the broker had closed it (the socket shut down: paho sees the end as always and
   reconnects; connection.py says it, rule 6). amqtt 0.12 waits for ever on an MQTT 5 CONNECT
   that carries a will; paho alone would wait the keepalive (a minute) each time.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import ssl
import time
from collections.abc import Callable

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

TCP_QUICKACK: int | None = getattr(socket, "TCP_QUICKACK", None)  # rule 9; Linux only
CONNACK_TIMEOUT_S = 10.0  # rule 5


def acknowledge_now(sock: object) -> None:
    """Rule 9: have the kernel acknowledge what was read so far now, not after its delayed-ACK
    timer (and leave its interactive mode until we next send)."""
    setsockopt = getattr(sock, "setsockopt", None)  # None before the first connect
    if TCP_QUICKACK is None or setsockopt is None:
        return
    try:
        setsockopt(socket.IPPROTO_TCP, TCP_QUICKACK, 1)
    except OSError:  # closed meanwhile: paho notices that on its own
        pass


class Client(paho.Client):
    """paho's client with rule 9 (``_loop``, loop_start's thread, reads through loop_read) and
    rule 2 (``tick``)."""

    tick: Callable[[], None] | None = None
    _connect_t: float | None = None  # rule 5: when the CONNECT now unanswered went out

    def reconnect(self) -> MQTTErrorCode:
        self._connect_t = time.monotonic()
        return super().reconnect()

    def _unanswered(self) -> None:
        """Rule 5: a CONNECT unanswered for too long ends its connection."""
        t = self._connect_t
        if t is None:
            return
        if self.is_connected():
            self._connect_t = None
        elif time.monotonic() - t >= CONNACK_TIMEOUT_S:
            self._connect_t = None
            shutdown = getattr(self.socket(), "shutdown", None)  # None: no socket (yet)
            if shutdown is not None:
                log.debug("no CONNACK in %g s: ending the connection", CONNACK_TIMEOUT_S)
                with contextlib.suppress(OSError):
                    shutdown(socket.SHUT_RDWR)

    def use_mqtt311(self) -> None:
        """Rule 3: MQTT 3.1.1 and a clean session from the next connection on."""
        self._protocol = paho.MQTTv311
        self._clean_session = True

    def loop_read(self, max_packets: int = 1) -> MQTTErrorCode:
        rc = super().loop_read(max_packets)
        acknowledge_now(self.socket())
        return rc

    def loop_misc(self) -> MQTTErrorCode:
        self._unanswered()
        rc = super().loop_misc()
        tick = self.tick
        if tick is not None and rc == MQTTErrorCode.MQTT_ERR_SUCCESS:
            try:
                tick()
            except Exception:  # connection.py rule 5: paho's network thread goes on
                log.exception("error in the MQTT connection's tick")
        return rc


def new_client(settings: MqttSettings, client_id: str) -> Client:
    """paho's client as both connections use it: rule 1's protocol and session, credentials
    and TLS."""
    v5 = settings.protocol != "3.1.1"  # "auto" tries MQTT 5 first (connection.py rule 1)
    c = Client(
        callback_api_version=CallbackAPIVersion.VERSION2,
        client_id=client_id,
        protocol=paho.MQTTv5 if v5 else paho.MQTTv311,
        clean_session=None if v5 else True,  # None: MQTT 5 has clean_start instead
    )
    if settings.username is not None:
        password = settings.password.get_secret_value() if settings.password else None
        c.username_pw_set(settings.username, password)
    if settings.tls.enabled:
        c.tls_set(
            ca_certs=str(settings.tls.ca_file) if settings.tls.ca_file else None,
            certfile=str(settings.tls.cert_file) if settings.tls.cert_file else None,
            keyfile=str(settings.tls.key_file) if settings.tls.key_file else None,
            cert_reqs=ssl.CERT_REQUIRED,
        )
        c.tls_insecure_set(settings.tls.insecure)
    return c


def accepts_mqtt311(settings: MqttSettings, client_id: str, timeout_s: float = 5.0) -> bool:
    """Rule 4: whether the broker accepts an MQTT 3.1.1 connection from this client now."""
    c = new_client(settings, client_id)
    c.use_mqtt311()
    c.connect_timeout = timeout_s
    answers: list[bool] = []

    def on_connect(*args: object) -> None:
        reason = args[3]
        answers.append(not getattr(reason, "is_failure", True))

    c.on_connect = on_connect
    try:
        c.connect(settings.host, settings.port, keepalive=max(5, settings.keepalive_s))
    except (OSError, ValueError, ssl.SSLError):
        return False
    try:
        deadline = time.monotonic() + timeout_s
        while not answers and time.monotonic() < deadline:
            if c.loop(timeout=0.1) != MQTTErrorCode.MQTT_ERR_SUCCESS:
                break
    finally:
        with contextlib.suppress(Exception):
            c.disconnect()
        with contextlib.suppress(Exception):
            c.loop(timeout=0.1)  # hands the DISCONNECT to the socket
    return answers == [True]
