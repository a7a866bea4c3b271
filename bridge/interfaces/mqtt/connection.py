"""One connection to the broker, as both of the bridge's use it: the main one (client.py) and
the stop lane (lane.py). It builds paho's client (protocol, session, credentials, TLS), connects
it, subscribes the command topics on every connect, notes which subscriptions the broker denies,
hands every message on, and slows down a fight over the client id. What a connection means
beyond that (the bridge's presence, its retained state; or a lane for stops) is the subclass's.

Rules (numbered as the bridge's MQTT rules; client.py keeps the index of all of them):
1. paho 2.x, CallbackAPIVersion.VERSION2. MQTT 5 with a clean start and no session expiry, so
   commands sent while the bridge was away are not replayed to it; subscriptions ask for
   retain-as-published, so a command published with the retain flag is recognised as such even
   while the bridge is connected (MQTT 3.1.1 clears the flag then; so under MQTT 5 the flag
   does not tell the broker's replay from a live message there: client.py rule 14); not the
   state topics read (``replayed``: the wind) nor the bridge's own (owned.py rule 10), whose
   flag then says "replayed" or "held", as under MQTT 3.1.1. ``protocol =
   "3.1.1"`` is for brokers without MQTT 5 (clean session, same rules otherwise). ``"auto"``, the
   default, tries MQTT 5 and steps down to 3.1.1 for good (paho_client.py rule 3) when the broker
   answers "Unsupported protocol version" (NATS, aedes), as long as no MQTT 5 connection was
   ever accepted: said once, with what 3.1.1 loses (``_fell_back``), and on ``B/bridge/info``
   while it lasts (app.py). RabbitMQ 3 and amqtt close an MQTT 5 connection before any CONNACK
   instead; but so does a broker restarting, one not ready yet behind a proxy, a connection
   limit, or anyone on the path who wants the bridge on 3.1.1 and its weaker rules (a retained
   command carried out, a remote's stale command without its stamps). So a close alone never
   steps down: after one, ``auto`` asks the broker once in MQTT 3.1.1 (a trial connection on a
   thread of its own, closed at once: paho_client.py rule 4), and steps down only if that
   trial was accepted and the next MQTT 5 attempt is closed before its CONNACK again (a
   broker that came back speaks MQTT 5 to that attempt; a connection limit refuses the trial
   too). Over TLS a close never steps down (``_trusts_closes``): nobody on the path can answer
   for the broker there, but anyone can still close connections, the first and the third, and
   let the trial between them through. Until then, and for ``"5"``, the close is said with the
   fix (rule 6).
   ``"5"`` and ``"3.1.1"`` never change.
4. Command topics are subscribed at QoS 0 (COMMAND_QOS). The session is clean, so QoS 1 would
   buy no redelivery; what it does cost: a broker holds at most ~1000 QoS 1 messages for a
   subscriber that falls behind and then drops the NEWEST (mosquitto: "Outgoing messages are
   being dropped"), which in a flood of targets loses the final target, or a STOP. At QoS 0 a
   connected subscriber gets everything, in order. (Measured: tests/faults, 10,000-target burst.)
5. Callbacks run on paho's thread and stay short: they hand messages to the handler, which must
   not block (it drops commands into mailboxes); a handler that raises is logged, and paho's
   thread goes on.
6. paho's reconnect loop (connect_async + loop_start, exponential back-off; the loop runs on a
   thread of ours, paho_client.py rule 6); a refused
   connection (bad credentials) or a failed one (TLS, unreachable) is logged once with the
   reason (the main connection's words; the lane has its own, lane.py rule 3) and retried,
   never a crash; a login refused names the keys to check (``login_hint``: it said "Not
   authorized" and no key, an attack pass): with a client certificate and no user name, the
   certificate (a broker that takes it as the login), not a password to set. Rule 7 only
   slows that loop down. The back-off is 1 s doubling to 30 s (``RECONNECT_MAX_S``) for the main
   connection, whose tries a broker refusing the login sees; a connection that carries stops
   and locks (the stop lane, the stop express: their ``RECONNECT_MAX_S``) doubles to
   STOP_RECONNECT_MAX_S (2 s) only. A broker back from an outage is not announced: its
   persisted retained ``R/availability`` says ``online`` at once (a broker's own shutdown
   sends no last will), so a dashboard offers STOP while the bridge is still waiting out its
   back-off, and a clean session keeps nothing for a connection not yet back (rule 1). With
   30 s, after a 33 s outage every connection came back 28 s after the broker, and a STOP
   sent then reached nobody: the rotor turned on to its target (attack 23). The cost of 2 s
   is small: a try at a broker that is away is a TCP connection refused (or one that times
   out, which spaces the tries by itself), and the stop lane and the express start only once
   the main connection was accepted, so a wrong password is tried on the main connection's
   back-off alone; a lane the broker keeps refusing or closing (rule 3 of lane.py: said once)
   tries under 30 times a minute, below what a broker's flapping detection bans (EMQX: 30
   disconnects a minute when it is turned on). Less would pass that ban, and close the window
   no better: a STOP sent before the lane is back, however soon it tries, reaches the main
   connection only, if that one is back; only the broker keeping the STOP for the lane would
   close it, which a clean session does not ask (docs/reliability.md, Limits, says why the
   lane's stays clean). A connection the broker closes before it answers the CONNECT (an
   ACL on the client id, a connection limit, a broker without MQTT 5) is said too, once, with
   the likely fixes (``_closed_early``): it is never silent. One the bridge itself ends for want
   of an answer (``unanswered``: paho's keep-alive, or paho_client.py rule 5's CONNACK_TIMEOUT_S,
   ran out before any byte of the broker's) is said as that (``_unanswered``): the broker took
   the connection and said nothing, a broker stalled or overloaded, or its host or the network
   holding its packets, never its access rules nor a connection limit, which answer or close
   (attack 23: a broker frozen past the keep-alive was said at ERROR as one that "closed the
   connection before accepting it (Keep alive timeout)", its ACL to check, and the stop lane
   said the same of its own). The stop lane and the express leave it to the main connection,
   which speaks to the same broker (as they do a broker that cannot be reached). An attempt's
   end by paho's keep-alive is judged once (paho_client.py ``attempts``): paho says it twice,
   the second as if the connection had never been accepted, and that second word was said at
   ERROR as a broker that never answered, to check that it runs (review 152: the main
   connection given up on a dead path, the broker healthy throughout).
   A connection of the bridge's that carries stops (the stop and lock lanes, the stop express:
   their ``KEEPALIVE_MAX_S``), once accepted, pings after STOP_KEEPALIVE_S (2 s) of quiet and
   gives the connection up when a ping is not answered as long after it (paho_client.py
   ``ping_within``), so that a path that dies without a word under it (a router's reboot that
   lost its NAT table, a VPN or Wi-Fi link made again under another address: no FIN, no RST,
   the broker still up and taking connections) is found within STOP_DEAD_PATH_S (7 s) and the
   connection made again on a live one. With the setting's 30 s the three came back 30 to 60 s
   after the path died, while a dashboard showed the rotator online and a STOP pressed then
   reached nobody: the rotor turned on to its target (attack 32). Its CONNECT still says
   ``keepalive_s``: a broker slow to accept has rule 5's CONNACK_TIMEOUT_S, and one that hears
   nothing of it for a few seconds (a stalled uplink, the bridge's process held) does not drop
   it (review 145: at 2 s in the CONNECT, a broker 2.5 s slow to accept kept the three off for
   good, and 3 s stalls under MQTT 3.1.1 were said as a fight over the client id). The main
   connection keeps the setting: its keep-alive is the bridge's presence (its will after 1.5 of
   them), and it rides out a broker that stalls for longer while its lanes come and go. The
   cost is a PINGREQ and its answer every 2 s on each such connection while nothing else
   passes; a broker or a path that holds back an answer for 2 s more has such a connection
   made again (paho's own keep-alive end, no evidence of a fight: rule 7), and its stops take
   the main connection until it is back, behind whatever that one is reading (review 148: a
   few seconds' stall of the uplink, its downlink fine, ended the stop lane, and a STOP then
   waited behind a backlog of targets: a known failure, the price of finding a dead path;
   a new connection made before the old one is given up would avoid it). A connection still
   waiting for its CONNACK when the path dies is given up at rule 5's CONNACK_TIMEOUT_S (10
   s), not within STOP_DEAD_PATH_S (review 148, a known failure: a shorter wait would again
   keep a broker slow to accept from ever having it). The remote's link keeps the setting: it
   watches its own path (remote.py rule 10), and what a stalled link held, stamped, is refused
   late at the station. A STOP pressed in the first seconds after a path died still reaches
   nobody on these paths (docs/reliability.md, Limits).
7. One client id, one connection. A broker that gets a second connection with a client id closes
   the first ("session taken over": MQTT 5 reason 0x8E; MQTT 3.1.1 just closes the socket), so
   two processes with one id (two hosts sharing a configuration, a stale container beside a new
   one) would take each other over in a loop, each reconnect kicking the other. The main
   connection logs that ONCE, naming the client id and the likely cause, and both back off
   instead of fighting: TAKEOVER_FIRST_S, doubling per reconnect up to TAKEOVER_MAX_S (so at
   most one reconnect a minute), until a connection lasts STABLE_S. Brokers that say nothing
   (MQTT 3.1.1; mosquitto 2.0.11 even with MQTT 5) just drop the connection, so FLAP_COUNT drops
   in a row, each less than STABLE_S after the connection was accepted and each followed by a
   connection accepted at the first try (the broker never went away), count as a takeover too;
   the side that holds the connection longer sees exactly that. A drop right after which the
   broker's address (the connection's own) refuses a TCP connection (``listening``, within
   PROBE_S: a broker killed or crashed closes its port with its connections, and systemd starts
   it again 100 ms later at the earliest) is the broker going away ("gone"), no evidence: a
   broker that crashed and was restarted at once three times in a row was taken for a fight, and
   the bridge stayed away up to a minute after it was back (an attack pass). (A port kept open
   in front of a dead broker, Docker's proxy, says nothing: evidence.) A drop after a keepalive
   timeout or with another reason from the broker is no evidence. (A link that keeps breaking
   the same way earns the same back-off; the error says "most likely".) A connection that
   carries stops (the stop lane, the stop express: ``FIGHT_BACKOFF_MAX_S``) says a fight the
   same way and backs off TAKEOVER_FIRST_S at most (and the remote's link, which carries its
   stops), paho's delay after a failed connect too: a broker that crashes and is restarted at
   once (systemd's 100 ms) three times in a row looked exactly like one, before the look at its
   port (and still does behind a port kept open, or to a bridge too busy to look within 100 ms),
   and the back-off kept every STOP out for up to a minute after the broker was back (an attack
   pass); two bridges' lanes fighting take turns every few seconds, fewer connections a minute
   than a broker's flapping detection bans (EMQX: 30), as the main connections' would at first.
   The default client id is unique per installation (MqttSettings.effective_client_id): only an
   explicit one, or a copied state file on a host of the same name, can collide.
9. Whatever the broker sends is acknowledged at once, in TCP: after every read paho makes, the
   socket gets TCP_QUICKACK (Linux; elsewhere nothing changes). A broker with Nagle on
   (mosquitto's default, set_tcp_nodelay false) holds a second small packet until the first is
   acknowledged, and Linux delays the acknowledgement of a packet we do not answer (a PUBACK for
   our error event, a command that changes nothing) by 40 ms once we answer others quickly: a
   stop 0-3 ms behind a refused target reached the controller 44 ms late (p50;
   benchmarks/latency.py), and behind any target while state went out at QoS 1. The kernel
   leaves quick-ack mode again as soon as we send, so it is set after every read, not once (a
   system call per read; paho_client.py). Command topics stay QoS 0 (rule 4): our PUBACK would
   acknowledge a command too, but brings back what rule 4 avoids.
17. A filter subscribed as optional (``optional``: Home Assistant's config topics read with
   discovery off, homeassistant/publisher.py rule 6; a rotator's other command topics under
   a group's root, read only to refuse them, service.py rule 10) that the broker denies is
   said once in the log, with what its denial costs, and is no problem: not on
   ``B/bridge/info`` nor a rotator's last error, and the command topics count as subscribed
   all the same (an ACL that keeps a bridge out of Home Assistant's prefix is why its owner
   turned discovery off).
18. Under MQTT 5 every connection (the main one, the stop lane, the stop express) tells the
   broker in its CONNECT the largest packet it takes (MAX_PACKET_BYTES: far above any payload
   the bridge reads, its own retained ones included); the broker drops a larger message for it
   rather than send it. An attack pass on a broker anyone may publish to: each 200 MB
   ``R/stop`` (mosquitto takes up to 256 MB) was read whole by all three connections, and the
   bridge and its express each kept some 160 MB of memory afterwards; a few of them at once
   would leave a Raspberry Pi to its out-of-memory killer. MQTT 3.1.1 has no such word: there
   the broker's own ``message_size_limit`` is the bound (docs/brokers.md). The bound lies well
   above the payloads the bridge refuses with a word (a 1 MiB target is refused on ``R/error``
   as too large: tests/faults/test_input.py), so only a message no client means gets none; such
   a "stop" is not carried out either (a 1 MiB bound dropped the 1 MiB stop and target of the
   fault tests without a word: CI).
"""

from __future__ import annotations

import errno
import logging
import math
import socket
import ssl
import sys
import threading
import time
from collections.abc import Callable
from typing import Any, Literal, TypedDict, Unpack

import paho.mqtt.client as paho
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.paho_client import CONNACK_TIMEOUT_S, accepts_mqtt311, new_client
from bridge.settings.mqtt import MqttSettings

log = logging.getLogger(__name__)

# topic, payload, retain flag, the MQTT 5 user property ``operator`` as sent (None without it),
# the send time the message carries (heartbeat.py rule 4; None without one)
MessageHandler = Callable[[str, bytes, bool, str | None, Stamp | None], None]
COMMAND_QOS = 0  # rule 4


def operator_of(msg: paho.MQTTMessage) -> str | None:
    """The user property ``operator`` of an MQTT 5 message, as sent (the service judges it);
    None without one (and always under MQTT 3.1.1, which has no properties). Two that differ
    name nobody: the text of both, which no operator's name is (model.valid_operator refuses
    a line break), so the service ignores it as any name it cannot take (an attack pass: the
    first of two was taken, where the last of two ``sent`` was)."""
    props = getattr(msg, "properties", None)
    pairs = getattr(props, "UserProperty", None) or []
    names = list(dict.fromkeys(str(value) for key, value in pairs if key == "operator"))
    if not names:
        return None
    return "\n".join(names)


def stamp_of(msg: paho.MQTTMessage) -> Stamp | None:
    """The user properties ``sent`` and ``expiry`` of an MQTT 5 message (heartbeat.py rule 4),
    as sent (the service judges them); None without either."""
    props = getattr(msg, "properties", None)
    return Stamp.of_properties(getattr(props, "UserProperty", None) or [])


MAX_PACKET_BYTES = 4 << 20  # rule 18: the largest packet the broker may send a connection
UNSUPPORTED_PROTOCOL = 0x84  # rule 1: CONNACK for a version the broker does not speak
MQTT311_LOSES = (  # rule 1: said when the bridge speaks MQTT 3.1.1 (docs/brokers.md)
    "a retained command published while the bridge is connected arrives without its retain "
    "flag and is carried out like any other (a retained target moves the rotor once), and "
    "rotor-bridge remote's commands lose their send time, expiry and operator (a command held "
    "up on the remote's link is carried out late): remote operation needs MQTT 5 on both sides"
)
# rule 7
SESSION_TAKEN_OVER = 0x8E
CONNECTION_LOST = 0x80  # paho's "Unspecified error" for a socket that closed without a word
KEEPALIVE_TIMEOUT = 0x8D  # rule 6: paho's "Keep alive timeout" (its own, not the broker's)
TAKEOVER_FIRST_S = 5
TAKEOVER_MAX_S = 60
STABLE_S = 2 * TAKEOVER_MAX_S  # longer than the other side's back-off: a fight never looks stable
FLAP_COUNT = 3
Ending = Literal["taken over", "dropped", "gone", "other"]
STOP_RECONNECT_MAX_S = 2  # rule 6: the back-off's most for a connection that carries stops
STOP_KEEPALIVE_S = 2  # rule 6: a ping after this much quiet on a connection that carries stops
#: rule 6: a dead path under such a connection is found, and the connection made again on a live
#: one, this long after the path died at most: the PINGREQ after the keep-alive of quiet, its
#: answer given up as long after it (each seen by a round of paho's loop, a second apart at
#: most: paho_client.py rule 2), then the reconnect's first wait (a second)
STOP_DEAD_PATH_S = 2 * (STOP_KEEPALIVE_S + 1) + 1
PROBE_S = 1.0  # rule 7: how long the look at the broker's port after a drop may take
_GONE_ERRNOS = (errno.ECONNREFUSED, errno.EHOSTUNREACH, errno.ENETUNREACH)  # rule 7: "gone"


class TakeoverGuard:
    """Rule 7's bookkeeping, without paho or a clock: times in, a back-off out."""

    def __init__(self) -> None:
        self.connected_at: float | None = None
        self._drops = 0  # dropped connections in a row, the broker reachable throughout
        self.backoff_s = 0  # 0: no takeover episode, paho's own reconnect delays apply
        self.reported = False

    def connected(self, now: float) -> None:
        self.connected_at = now

    def connect_failed(self) -> None:
        """The broker was unreachable or refused us: the drops before were not a fight."""
        self._drops = 0

    def disconnected(self, now: float, ending: Ending) -> bool:
        """Whether this disconnect is part of a takeover episode (``backoff_s`` is then set)."""
        lasted = now - self.connected_at if self.connected_at is not None else 0.0
        self.connected_at = None
        if lasted >= STABLE_S:
            self._drops, self.backoff_s, self.reported = 0, 0, False
        self._drops = self._drops + 1 if ending == "dropped" else 0
        if ending == "gone":  # the broker went away: no evidence, however the episode stands
            return False
        if not (ending == "taken over" or self._drops >= FLAP_COUNT or self.backoff_s):
            return False
        self.backoff_s = min(TAKEOVER_MAX_S, self.backoff_s * 2 or TAKEOVER_FIRST_S)
        return True


def listening(host: str, port: int, timeout_s: float = PROBE_S) -> bool:
    """Rule 7: whether the broker's address (the one the connection had: no name to resolve)
    takes a TCP connection now (closed at once, nothing sent): False only when it is refused
    or the host unreachable within ``timeout_s``; a look that cannot tell by then (a lost SYN)
    leaves the drop as it looked."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError as exc:
        return exc.errno not in _GONE_ERRNOS
    except ValueError:
        return True


def peer_of(client: paho.Client) -> tuple[str, int] | None:
    """Rule 7: the broker's address and port of the connection just accepted, or None (a
    socket that cannot say: a unix socket, a websocket paho wraps)."""
    try:
        peer = client.socket().getpeername()  # type: ignore[union-attr]
    except (AttributeError, OSError):
        return None
    return (peer[0], peer[1]) if isinstance(peer, tuple) and len(peer) >= 2 else None


def takeover_message(client_id: str, ending: Ending, most_s: int = TAKEOVER_MAX_S) -> str:
    """Rule 7: what a connection says, once an episode; ``most_s``: the longest it backs off
    (``FIGHT_BACKOFF_MAX_S``: shorter for a connection that carries stops)."""
    if ending == "taken over":
        what = f"MQTT session taken over: another client connected with client id {client_id!r}"
    else:
        what = (
            f"the MQTT broker dropped the connection {FLAP_COUNT} times in a row without a "
            f"reason, taking new ones at once: most likely another client connects with "
            f"client id {client_id!r}"
        )
    return (
        f"{what}. Two processes with one client id (two hosts sharing one configuration, a "
        f"stale container still running) keep kicking each other off: stop the other one or "
        f"give each its own mqtt.client_id. "
        + (
            f"Backing off: {TAKEOVER_FIRST_S} s, doubling up to {most_s} s between "
            f"reconnects, until a connection lasts {STABLE_S} s"
            if most_s > TAKEOVER_FIRST_S
            else f"Backing off {most_s} s between reconnects at most: it carries stops (a "
            "broker restarted again and again can look the same)"
        )
    )


def command_filters(
    filters: list[str], no_replay: frozenset[str], v5: bool, replayed: frozenset[str] = frozenset()
) -> list[tuple[str, Any]]:
    """Rules 1 and 4: command topics at COMMAND_QOS, MQTT 5 with retain-as-published; the
    filters in ``no_replay`` (stop: lastword.py rule 6) also ask the broker not to replay their
    retained message on subscribing (retain handling 2); those in ``replayed`` go without it."""
    if not v5:
        return [(topic, COMMAND_QOS) for topic in filters]
    live = SubscribeOptions(qos=COMMAND_QOS, retainAsPublished=True)
    keep = SubscribeOptions.RETAIN_DO_NOT_SEND
    fresh = SubscribeOptions(qos=COMMAND_QOS, retainAsPublished=True, retainHandling=keep)
    state = SubscribeOptions(qos=COMMAND_QOS)  # rule 1: the retain flag says "replayed"
    return [(t, fresh if t in no_replay else state if t in replayed else live) for t in filters]


def ending_of(flags: paho.DisconnectFlags, reason_code: ReasonCode) -> Ending:
    """Rule 7: how a connection ended, as evidence of a takeover."""
    code = getattr(reason_code, "value", None)
    from_server = bool(getattr(flags, "is_disconnect_packet_from_server", False))
    if from_server and code == SESSION_TAKEN_OVER:
        return "taken over"
    if not from_server and code == CONNECTION_LOST:
        return "dropped"
    return "other"


def unanswered(
    flags: paho.DisconnectFlags, reason_code: ReasonCode, client: Any, keepalive_s: int
) -> str | None:
    """Rule 6: for an attempt the broker never answered, how long it was given ("within the
    keep-alive (60 s)"), if the bridge's own client ended it for that; None if the broker
    closed it (or any other end)."""
    if getattr(client, "connack_timed_out", False):
        return f"within {CONNACK_TIMEOUT_S:g} s"
    from_server = bool(getattr(flags, "is_disconnect_packet_from_server", False))
    if not from_server and getattr(reason_code, "value", None) == KEEPALIVE_TIMEOUT:
        return f"within the keep-alive ({keepalive_s} s)"
    return None


# the broker's words for a login it refused: MQTT 5's reasons 0x86 and 0x87, MQTT 3.1.1's 4 and 5
LOGIN_REFUSED = ("Bad user name or password", "Not authorized")


def login_hint(reason: str, settings: MqttSettings) -> str:
    """Rule 6: what to check when the broker refused the login (``reason``), else ""."""
    if reason not in LOGIN_REFUSED:
        return ""
    if settings.username is None and settings.tls.cert_file is not None:  # (a review: a
        return (  # broker that takes the certificate as the login was told of a password)
            ": check the client certificate (mqtt.tls.cert_file) and the broker's access rules"
        )
    if settings.username is None:
        return ": the broker asks for a login: set mqtt.username and mqtt.password_file"
    return (
        ": check mqtt.username and mqtt.password (or password_file), and the broker's access rules"
    )


class Options(TypedDict, total=False):
    """What both connections take alike, as keywords of their constructors."""

    on_new_connection: Callable[[], None] | None  # before any message of a new connection
    on_subscribed: Callable[[], None] | None  # the command topics' SUBACK, before their messages
    # what to publish (topic, payload; QoS 0) right behind the command topics' SUBSCRIBE, on
    # the same connection (a lane's marker: lastword.py rule 17)
    behind_subscribe: Callable[[], list[tuple[str, str]]] | None
    no_replay: list[str] | None  # command filters whose retained message is not replayed
    replayed: list[str] | None  # state topics read, their retain flag saying "replayed" (rule 1)
    reconnect_min_s: int  # paho's reconnect back-off (rule 6)
    reconnect_max_s: int  # (by default the class's RECONNECT_MAX_S: rule 6)


class Connection:
    """A paho client and what both connections do with it. Subclasses say what the rest means
    through the hooks below (all called on paho's thread, holding paho's callback mutex)."""

    FIGHT_BACKOFF_MAX_S = TAKEOVER_MAX_S  # rule 7: TAKEOVER_FIRST_S for one that carries stops
    RECONNECT_MAX_S = 30  # rule 6: STOP_RECONNECT_MAX_S for one that carries stops
    KEEPALIVE_MAX_S: int | None = None  # rule 6: STOP_KEEPALIVE_S for one that carries stops

    def __init__(
        self,
        settings: MqttSettings,
        client_id: str,
        *,
        subscriptions: list[str],
        on_message: MessageHandler,
        clock: Callable[[], float] = time.monotonic,
        **options: Unpack[Options],
    ) -> None:
        self._settings = settings
        self._client_id = client_id  # what a takeover names (rule 7): the remote has its own
        self._v5 = settings.protocol != "3.1.1"  # rule 1: "auto" tries MQTT 5 first
        self._auto = settings.protocol == "auto"  # ... and may step down (``_fall_back``)
        self._accepted_once = False  # a connection was accepted: the protocol is settled
        self._answered = False  # the broker sent a CONNACK to this attempt (rules 1 and 6)
        self._gave_up = False  # ... or, unanswered, this client ended it (rule 6: ``unanswered``)
        self._keep_s = settings.keepalive_s  # (what rule 6 says it waited)
        self._trial_lock = threading.Lock()  # rule 1: the MQTT 3.1.1 trial after a close
        self._trial: threading.Thread | None = None
        self._trial_ok = False  # ... was accepted, since the last MQTT 5 attempt closed
        self._subscriptions = subscriptions
        self._no_replay = frozenset(options.get("no_replay") or ())
        self._replayed = frozenset(options.get("replayed") or ())
        self._handler = on_message
        self._on_new_connection = options.get("on_new_connection")
        self._on_subscribed = options.get("on_subscribed")
        self._behind_subscribe = options.get("behind_subscribe")
        self._clock = clock
        self._reconnect_s = (
            options.get("reconnect_min_s", 1),
            options.get("reconnect_max_s", self.RECONNECT_MAX_S),
        )
        self._guard = TakeoverGuard()
        self._peer: tuple[str, int] | None = None  # rule 7: the address the connection had
        self._slowed = False  # reconnect_delay_set raised for a takeover (rule 7)
        self._up = False  # a connection accepted
        # rule 6: the attempt whose end by paho's keep-alive was last said (and that reason)
        self._ended_attempt: tuple[int | None, int] | None = None
        self._subscribed = False  # ... and the SUBACK of its command topics came
        self._subscribed_since: float | None = None  # ... then (``heard_since``), while it lasts
        self._subscribing = False  # ... or at least its SUBSCRIBE is on its way (``hears``)
        self._command_mid: int | None = None
        self._stopping = False  # a shutdown under way: a broker going away is no news
        self._last_refusal: str | None = None  # rule 6: each reason said once in a row
        self._sub_filters: dict[int, list[str]] = {}  # SUBSCRIBE's message id -> its filters
        self._optional: dict[str, str] = {}  # rule 17: filter -> what its denial costs
        self._optional_said: set[str] = set()
        self.connected = threading.Event()
        self.before_message: Callable[[], None] | None = None  # lane.py rule 4
        c = new_client(settings, client_id)
        c.reconnect_delay_set(*self._reconnect_s)
        c.on_connect = self._on_connect
        c.on_connect_fail = self._on_connect_fail
        c.on_disconnect = self._on_disconnect
        c.on_message = self._on_message
        c.on_subscribe = self._on_subscribe
        c.tick = self._tick
        self._client = c

    def _connect(self) -> None:
        """Rule 6: paho's reconnect loop from now on (a clean start under MQTT 5, rule 1)."""
        s = self._settings
        fresh = True if self._v5 else paho.MQTT_CLEAN_START_FIRST_ONLY  # 3.1.1: clean session
        most = Properties(PacketTypes.CONNECT)  # type: ignore[no-untyped-call]  # rule 18
        most.MaximumPacketSize = MAX_PACKET_BYTES  # (sent under MQTT 5 only)
        self._client.connect_async(
            s.host, s.port, keepalive=s.keepalive_s, clean_start=fresh, properties=most
        )
        self._client.loop_start()

    def _disconnect(self) -> None:
        self._client.disconnect()
        self._client.loop_stop()  # joins paho's thread: never call this on it

    def optional(self, filters: dict[str, str]) -> None:
        """Rule 17: filters (among the subscriptions) whose denial is no problem, each with
        what it costs; before the connection starts."""
        self._optional.update(filters)

    def _subscribe(self, client: paho.Client, filters: list[tuple[str, Any]]) -> int | None:
        """SUBSCRIBE, its filters kept by message id to name what the SUBACK denies."""
        if not filters:
            return None
        _rc, mid = client.subscribe(filters)
        if mid is not None:
            self._sub_filters[mid] = [f for f, _opts in filters]
        return mid

    # -- hooks: by default what the main connection (client.py) says of rules 6 and 7 --------
    def _refused(self, reason: str) -> None:
        """The broker refused the connection (CONNACK failure)."""
        if reason != self._last_refusal:
            hint = login_hint(reason, self._settings)
            log.error("MQTT broker refused the connection: %s%s (retrying)", reason, hint)
            self._last_refusal = reason

    def _failed(self) -> None:
        """The connection could not be made (inside paho's ``except OSError``)."""
        if self._stopping:
            return
        exc = sys.exc_info()[1]  # paho calls back inside its `except OSError`: it says why
        if isinstance(exc, ssl.SSLError):
            text = f"TLS handshake with the MQTT broker failed: {exc} (check tls.ca_file/cert_file)"
        else:
            text = f"cannot connect to the MQTT broker: {exc or 'unknown error'}"
        if text != self._last_refusal:
            log.error("%s (retrying with back-off)", text)
            self._last_refusal = text

    def _accepted(self) -> None:
        """A connection is accepted; nothing of it has been handed on yet."""
        self._last_refusal = None
        log.info("connected to MQTT broker (%s)", self.protocol)

    def _fell_back(self, what: str) -> None:
        """Rule 1: ``auto`` steps down to MQTT 3.1.1, the broker having done ``what``."""
        s = self._settings
        log.warning(
            "the MQTT broker at %s:%d %s: using MQTT 3.1.1 from now on (set mqtt.protocol = "
            '"3.1.1" to skip the try). Under MQTT 3.1.1 %s',
            s.host,
            s.port,
            what,
            MQTT311_LOSES,
        )

    def _closed_early(self, reason: str) -> None:
        """Rule 6: the connection ended before the broker answered the CONNECT."""
        if self._stopping:
            return
        hint = ""
        if self._v5 and not self._accepted_once:  # (once accepted, the protocol is not why)
            hint = (
                "; a broker without MQTT 5 (RabbitMQ 3, amqtt) closes it this way too: set "
                'mqtt.protocol = "3.1.1" for it'
                + (
                    ' (with "auto" the bridge asks the broker in MQTT 3.1.1 to tell)'
                    if self._trusts_closes
                    else ""
                )
            )
        text = (
            f"the MQTT broker closed the connection before accepting it ({reason}): check the "
            "broker's log "
            "(its access rules for this client id and user, a connection limit)" + hint
        )
        if text != self._last_refusal:
            log.error("%s (retrying)", text)
            self._last_refusal = text

    def _unanswered(self, waited: str) -> None:
        """Rule 6: the connection was ended by this client: the broker did not answer it
        ``waited`` ("within the keep-alive (60 s)")."""
        if self._stopping:
            return
        hint = ""
        if self._v5 and not self._accepted_once:  # (amqtt: paho_client.py rule 5)
            hint = (
                "; amqtt 0.12 never answers an MQTT 5 connection that carries a will: if this "
                'is one, set mqtt.protocol = "3.1.1" for it'
                + (
                    ' (with "auto" the bridge asks the broker in MQTT 3.1.1 to tell)'
                    if self._trusts_closes
                    else ""
                )
            )
        text = (
            f"the MQTT broker did not answer the connection {waited}: it took the connection "
            "and then said nothing (the broker stalled or overloaded, or its host or the "
            "network holding its packets; check that the broker runs and answers)" + hint
        )
        if text != self._last_refusal:
            log.error("%s (retrying)", text)
            self._last_refusal = text

    def _opened(self, client: paho.Client) -> None:
        """The command topics are subscribed (the SUBACK may be on its way)."""

    def _denied(self, topic: str, reason: str) -> None:
        """The broker denied a subscription to ``topic``."""

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        """The connection is gone; whether to judge its end as takeover evidence (rule 7)."""
        return was_up

    def _ended(self, reason_code: ReasonCode, ending: Ending, fight: bool) -> None:
        """After rule 7's judgement: ``fight``, a takeover episode (the back-off is set)."""
        if not fight:
            log.warning("disconnected from MQTT broker (%s); reconnecting", reason_code)
        elif self._guard.reported:
            log.debug(
                "MQTT connection closed again (%s); next try in %d s",
                reason_code,
                self._guard.backoff_s,
            )
        else:  # once an episode
            self._guard.reported = True
            log.error("%s", takeover_message(self._client_id, ending))

    @property
    def v5(self) -> bool:
        """Whether this connection speaks MQTT 5 now (rule 1)."""
        return self._v5

    @property
    def protocol(self) -> str:
        """The MQTT version this connection speaks now (rule 1): "MQTT 5" or "MQTT 3.1.1"."""
        return "MQTT 5" if self._v5 else "MQTT 3.1.1"

    def use_mqtt311(self) -> None:
        """MQTT 3.1.1 from the next connection on (rule 1; the stop lane follows the main
        connection's choice): before ``start``, or from paho's callbacks once an attempt
        ended, never while a connection of this client is up."""
        self._v5 = False
        self._auto = False
        self._client.use_mqtt311()

    def _fall_back(self, what: str) -> bool:
        """Rule 1: whether ``auto`` steps down now (then it is said)."""
        if not (self._auto and self._v5) or self._accepted_once or self._stopping:
            return False
        self.use_mqtt311()
        self._fell_back(what)
        return True

    def _close_steps_down(self) -> bool:
        """Rule 1: an MQTT 5 attempt was closed before its CONNACK; whether ``auto`` steps down
        now (an MQTT 3.1.1 trial since the last such close was accepted), else a trial is
        started if none runs."""
        if not self._trusts_closes or self._accepted_once or self._stopping:
            return False
        with self._trial_lock:
            accepted, self._trial_ok = self._trial_ok, False
            running = self._trial is not None and self._trial.is_alive()
            if not accepted and not running:
                self._trial = threading.Thread(
                    target=self._try_mqtt311, name="mqtt-3.1.1-trial", daemon=True
                )
                self._trial.start()
        return accepted and self._fall_back(
            "closed MQTT 5 connections before answering them and accepted an MQTT 3.1.1 one "
            "between two of them"
        )

    @property
    def _trusts_closes(self) -> bool:
        """Rule 1: whether closes may step ``auto`` down (an MQTT 5 attempt, not over TLS)."""
        return self._auto and self._v5 and not self._settings.tls.enabled

    def _try_mqtt311(self) -> None:
        """Rule 1: the trial, on its own thread (it blocks for up to a few seconds)."""
        try:
            ok = accepts_mqtt311(self._settings, self._client_id)
        except Exception:  # rule 5: a failed trial is no evidence, and no crash
            log.debug("MQTT 3.1.1 trial failed", exc_info=True)
            ok = False
        with self._trial_lock:
            self._trial_ok = ok and not self._accepted_once

    def _filters(self) -> list[tuple[str, Any]]:  # the subscriptions, their options (rules 1, 4)
        return command_filters(self._subscriptions, self._no_replay, self._v5, self._replayed)

    def _intercepted(self, topic: str, payload: bytes, retained: bool = False) -> bool:
        """Whether a message is the connection's own business, not the handler's."""
        return False

    def _tick(self) -> float | None:
        """After each round of paho's loop while connected (Client.tick): must be cheap. It
        returns when (``time.monotonic``) it must run again, None within a second
        (paho_client.py rule 2); a connection with nothing on a clock, never."""
        return math.inf

    # -- paho callbacks (paho's thread) ---------------------------------------------------
    def _on_connect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.ConnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        self._answered = True
        with self._trial_lock:
            self._trial_ok = False  # rule 1: an answer, not a close: no evidence for a trial
        if reason_code.is_failure:
            self._guard.connect_failed()
            code = getattr(reason_code, "value", None)
            if code == UNSUPPORTED_PROTOCOL and self._fall_back(
                f'refused MQTT 5 ("{reason_code}")'
            ):
                return
            self._refused(str(reason_code))
            return
        self._up = True
        self._accepted_once = True
        if self.KEEPALIVE_MAX_S is not None:  # rule 6: a stop's carrier finds a dead path soon
            self._client.ping_within(self.KEEPALIVE_MAX_S)
        self._guard.connected(self._clock())
        self._peer = peer_of(client)  # rule 7: where to look after a drop
        self._subscribed = self._subscribing = False  # until the SUBACK of the command topics
        self._subscribed_since = None
        self._accepted()
        if self._on_new_connection is not None:  # before any message of the new connection
            self._on_new_connection()
        self._sub_filters.clear()  # before subscribing: the SUBACKs come after this returns
        # ``hears`` from here (after the new connection's hook), before the SUBSCRIBE is queued:
        # a stop-lane halt read as it goes holds, never not (a marker queued ahead of it is
        # lost and sent again: a hold a few seconds long, the safe direction)
        self._subscribing = True
        self._command_mid = self._subscribe(client, self._filters())
        if self._behind_subscribe is not None and self._command_mid is not None:
            for topic, payload in self._behind_subscribe():  # (paho's queue keeps the order)
                client.publish(topic, payload, qos=0, retain=False)
        self._opened(client)

    def _on_connect_fail(self, client: paho.Client, userdata: Any) -> None:
        with self._trial_lock:
            self._trial_ok = False  # rule 1: the broker was away: no evidence either way
        self._guard.connect_failed()
        self._failed()

    @property
    def subscribed_since(self) -> float | None:
        """When this connection's command topics were last subscribed, while that lasts."""
        return self._subscribed_since

    def heard_since(self, t: float) -> bool:
        """Whether this connection has had its command topics since before ``t`` (monotonic)
        without a break: a message published at ``t`` reaches it, or has (express.py rule 10).
        Any thread; a SUBACK moments after the broker took the subscription makes it False
        for a message it does deliver (the safe side there: a stop carried out twice)."""
        since = self._subscribed_since
        return since is not None and since <= t

    def _on_subscribe(
        self,
        client: paho.Client,
        userdata: Any,
        mid: int,
        reason_codes: list[ReasonCode],
        properties: Properties | None,
    ) -> None:
        filters = self._sub_filters.pop(mid, [])
        named = [*filters, *[None] * (len(reason_codes) - len(filters))]
        failed = [(t, c) for t, c in zip(named, reason_codes, strict=False) if c.is_failure]
        if mid == self._command_mid:
            self._subscribed = True  # the commands reach us from now on
            if all(t in self._optional for t, _c in failed):  # (a topic denied: perhaps a
                self._subscribed_since = self._clock()  # stop's, express.py rule 11; rule 17)
            if self._on_subscribed is not None:  # (paho reads what comes next after this)
                self._on_subscribed()
        for topic, code in failed:
            if topic is None:
                continue
            if topic in self._optional:  # rule 17: said once, no problem
                if topic not in self._optional_said:
                    self._optional_said.add(topic)
                    log.info(
                        "the MQTT broker does not let this bridge read %s (%s): %s",
                        topic,
                        code,
                        self._optional[topic],
                    )
                continue
            self._denied(topic, str(code))

    def _on_disconnect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.DisconnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        attempt = getattr(client, "attempts", None)
        code = getattr(reason_code, "value", None)
        ended = (attempt, code) if code == KEEPALIVE_TIMEOUT else None
        if ended is not None and ended == self._ended_attempt and not self._up:
            return  # rule 6: paho's second word of its keep-alive's end (review 152)
        self._ended_attempt = ended
        was, self._up, self._subscribed, self._subscribing = self._up, False, False, False
        self._subscribed_since = None
        answered, self._answered = self._answered, False
        self.connected.clear()
        # rule 6: an attempt our own client gave up on, unanswered, is no close of the broker's
        waited = None if was or answered else unanswered(flags, reason_code, client, self._keep_s)
        self._gave_up = waited is not None
        if not was and not answered and not self._close_steps_down():  # no CONNACK came
            if waited is not None:
                self._unanswered(waited)
            else:
                self._closed_early(str(reason_code))  # rule 6: never silent
        if not self._closed(was, reason_code):
            return
        ending = ending_of(flags, reason_code)
        peer, self._peer = self._peer, None
        if ending == "dropped" and peer is not None and not listening(*peer):
            ending = "gone"  # rule 7: a broker killed or restarted, not a takeover
        fight = self._guard.disconnected(self._clock(), ending)
        if fight:
            # paho forgets its back-off on every accepted connection and starts again at the
            # minimum delay: the minimum is what slows a fight down (rule 7)
            most = self.FIGHT_BACKOFF_MAX_S  # (a stop carrier's: its back-off, never doubled
            backoff = min(self._guard.backoff_s, most)  # by paho's failed connects: a review)
            client.reconnect_delay_set(
                backoff, backoff if most < TAKEOVER_MAX_S else max(backoff, self._reconnect_s[1])
            )
            self._slowed = True
        elif self._slowed:  # a connection lasted: paho's own delays again
            client.reconnect_delay_set(*self._reconnect_s)
            self._slowed = False
        self._ended(reason_code, ending, fight)

    def _on_message(self, client: paho.Client, userdata: Any, msg: paho.MQTTMessage) -> None:
        before = self.before_message
        if before is not None:
            try:
                before()  # another connection's messages go before this one's (lane.py rule 4)
            except Exception:  # rule 5: a courtesy that fails costs neither thread nor message
                log.exception("error letting the stop lane go first")
        try:
            payload = bytes(msg.payload)
            if not self._intercepted(msg.topic, payload, bool(msg.retain)):
                self._handler(msg.topic, payload, bool(msg.retain), operator_of(msg), stamp_of(msg))
        except Exception:  # rule 5: a handler bug must not kill paho's network thread
            log.exception("error handling MQTT message on %s", msg.topic)
