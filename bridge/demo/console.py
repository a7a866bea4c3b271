"""The demo's console: an ordinary MQTT client beside the demo's bridge. It prints what the
bridge publishes, turns typed lines into commands on the same topics any client would use, and at
the end removes what the demo left retained (bridge.demo, rule 4).

Rules:
1. It reaches the bridge only through the broker: every typed line becomes one MQTT message on
   the demo's topics (from bridge.interfaces.mqtt.topics), nothing is called directly.
2. It subscribes with retain-as-published (MQTT 5), so it knows which of the demo's topics hold a
   retained message on the broker, and can clear exactly those. On a broker that speaks MQTT
   3.1.1 alone (nats, aedes, RabbitMQ 3: the demo's look says which, bridge/demo/mosquitto.py
   ``connack_of``) it connects in 3.1.1, where a message that arrives while subscribed never
   says it was retained: it clears every topic of the demo's that carried a message since it
   connected and is one the bridge keeps retained (its state topics, ``Topics.owned``, and its
   Home Assistant configs), but those it published itself (review 127: in MQTT 5 alone it was
   refused for the whole run and left its retained messages behind; review 134: a new
   subscription's retained messages came after the marker that was to wait for them on aedes,
   and were left; review 139: its heartbeat, audit and errors were counted and cleared too). A
   retained topic it must read before the bridge starts is asked alone (``look``).
3. A line that is not a command is answered with a hint, never published as a target.
4. What it prints goes through a Screen (bridge/demo/screen.py): on a terminal the bearing,
   elevation and state of every rotator stay on one status line, redrawn in place, and
   everything else is a log line printed above it; elsewhere (a pipe, a file, a test) every
   change is a line of its own, ``  <topic> = <value>``.
5. A demo that started a private mosquitto says so on it, retained on ``PRIVATE_BROKER_MARK``
   (its instance name); ``private_broker_of`` reads that mark, so a second demo does not lean
   on a broker that ends with the first (bridge.demo rule 5).
6. Every typed command goes at QoS 1, in the order typed, only on a connection up: one the console
   knows it has lost (or never had) sends nothing it did not send before. What the broker has not
   acknowledged when a connection goes (paho's queue, taken from it as the next one comes up:
   ``drop_out_messages``) may have reached the broker or not, and is never sent again in paho's
   way, all of it: a move sent late would turn the rotor seconds after it was typed (review 134),
   and a STOP or lock ON sent again alone would land after the bearing or the lock OFF typed behind
   it (review 144). Of each rotator's typed commands it held, those after the last one that can
   move it or lift its lock (a target, an elevation, a preset, park, a nudge, tracking begun, a
   lock OFF: ``_kind``) go again on the new connection, first, in their order: they land after
   everything typed for it before them, and nothing that moves it was typed behind them (a STOP
   typed on a dead connection reached nobody and the rotor ran on: review 139; one left behind for
   a ``jam off`` or another rotator's turn typed after it: review 146; or a typo: a move the
   bridge's own parser of its topic refuses, or a preset its rotator's list lacks, counts as none,
   ``_may_move``, reviews 147, 149 and 151; one the bridge takes and the rotator then refuses, past
   its travel or on an axis it lacks, still counts, a known failure: review 151). That move and
   what was typed for the rotator before it are said unsure, to be typed again if still wanted; a
   command the broker acknowledged is forgotten then (``_on_publish``: review 147, a message id
   paho handed out again took an old lock ON's place). Typed while the console has no connection
   (or as paho finds it lost, its send refused), a STOP or lock ON is held for the next connection
   and goes there after those, said so; a move is refused, said so, and never sent (review 134: a
   bearing typed into a console that showed nothing turned the rotor when the broker came back).
   One lock orders the typed commands against the connection coming up (review 146: a STOP typed
   while it came up was said held and never sent). The console's own messages (its sync marker, the
   end's clean-up, rule 5's mark) go again as paho would; the clean-up and the mark are waited for
   by a sync round trip behind them, one deadline for all (review 146: each waited its whole
   timeout for the message it published first).
"""

from __future__ import annotations

import contextlib
import json
import secrets
import threading
from collections.abc import Callable
from functools import partial
from typing import Any

import paho.mqtt.client as paho
from paho.mqtt.client import topic_matches_sub
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.demo.screen import Screen
from bridge.features import tracking
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.payloads import PayloadError, parse_switch
from bridge.interfaces.mqtt.topics import Topics

OPTIONS = ("endpoint", "jam", "overshoot", "unstick")
SHOWN_LEAVES = (
    "bearing", "elevation", "state", "availability", "version", "error", "presets", "tracking"
)  # fmt: skip
STATUS_LEAVES = ("bearing", "elevation", "state")  # on a terminal: the status line (rule 4)
# retained by a demo on the private mosquitto it started: the demo's instance (rule 5)
PRIVATE_BROKER_MARK = "rotor-demo/private-broker"


class Console:
    """Shows what arrives on the broker, turns typed lines into MQTT commands, and at the end can
    remove what the demo left retained (rule 4)."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        client_id: str,
        topics: Topics,
        rotator_ids: list[str],
        discovery_filters: list[str],
        screen: Screen | None = None,
        mqtt5: bool = True,
    ) -> None:
        self.screen = screen or Screen()
        self._v5 = mqtt5
        self._seen: set[str] = set()  # rule 2, MQTT 3.1.1: the topics that carried a message
        self._sent: set[str] = set()  # rule 2: ... but those it published
        self._kept = [*topics.owned(), *discovery_filters]  # rule 2: those kept retained
        self._topics = topics
        self._ids = rotator_ids
        self._roots = {topics.rotator(rid).root for rid in rotator_ids}
        self._filters = [f"{topics.base}/#", *discovery_filters]
        self._sync_topic = f"{topics.base}/console/sync"
        self._retained: dict[str, bytes] = {}
        self._last: dict[str, str] = {}
        self._lock = threading.RLock()  # (rule 6: held across a connection's coming up)
        self._ever = False  # rule 6: a connection was up once
        self._synced = threading.Event()
        self._sync_word = b""  # the newest sync marker's (an older one back late ends no wait)
        self._subscribed = threading.Event()
        self.connected = threading.Event()
        self._typed: dict[int, tuple[str, str, bool]] = {}  # rule 6: by message id (went?)
        self._held: list[tuple[str, str]] = []  # rule 6: last words for the next connection
        self._kinds: dict[str, tuple[str, str]] = {}  # rule 6: topic -> (rotator, what it is)
        self._parsers: dict[str, Callable[[bytes], object]] = {}  # rule 6: a move's, by topic
        self._presets: dict[str, str] = {}  # rule 6: a preset topic -> its rotator's list
        for rid in rotator_ids:
            t = topics.rotator(rid)
            moves = (t.target, t.target_elevation, t.preset, t.park, t.nudge)
            self._kinds.update({topic: (rid, "move") for topic in moves})
            self._kinds.update({t.stop: (rid, "stop"), t.lock: (rid, "lock")})
            self._kinds[t.feature(tracking.COMMAND)] = (rid, "track")
            self._parsers[t.target] = pl.parse_aim  # (rule 6: the bridge's own, service.py's)
            self._parsers[t.target_elevation] = partial(pl.parse_number, what="elevation")
            self._parsers[t.preset] = partial(pl.parse_name, what="preset")
            self._presets[t.preset] = t.presets  # (rule 6: the names it may take)
            self._parsers[t.park] = partial(pl.parse_press, what="park", word="PARK")
            self._parsers[t.nudge] = pl.parse_nudge
        if mqtt5:
            c = paho.Client(CallbackAPIVersion.VERSION2, client_id=client_id, protocol=paho.MQTTv5)
        else:  # (rule 2: a clean session, as MQTT 5's clean start)
            c = paho.Client(
                CallbackAPIVersion.VERSION2, client_id=client_id, protocol=paho.MQTTv311
            )
        c.on_connect = self._on_connect
        c.on_disconnect = self._on_disconnect
        c.on_publish = self._on_publish
        c.on_message = self._on_message
        c.on_subscribe = self._on_subscribe
        c.reconnect_delay_set(1, 5)
        if mqtt5:
            c.connect_async(host, port, clean_start=True)
        else:
            c.connect_async(host, port)
        c.loop_start()
        self._client = c

    def _on_connect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.ConnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        if reason_code.is_failure:
            return
        self._subscribe(client)
        with self._lock:  # (rule 6: nothing typed meanwhile is held for a connection up)
            self._again(client)
            self._ever = True
            self.connected.set()

    def _on_disconnect(self, client: paho.Client, *_: Any) -> None:
        self.connected.clear()  # (rule 6: from now on a move typed is refused)

    def _kind(self, topic: str, payload: str) -> tuple[str, str]:
        """Rule 6: whose a typed command is (its rotator; the topic, for none) and what:
        "last" (a STOP, a lock ON: sent late, it moves nothing), "move" (it can move the rotor
        or lift its lock) or "other" (an option, tracking ended, a payload the bridge refuses)."""
        rid, what = self._kinds.get(topic, (topic, "other"))
        if what == "lock":
            try:
                what = "last" if parse_switch(payload.encode()) else "move"
            except PayloadError:
                what = "other"
        elif what == "track":  # (the bridge's own reading: review 151)
            try:
                name, tle = pl.parse_track(payload.encode())
            except (PayloadError, ValueError):
                what = "other"
            else:
                what = "other" if tle is None and name.strip().casefold() == "off" else "move"
        elif what == "stop":
            what = "last"
        elif what == "move" and not self._may_move(topic, payload):
            what = "other"
        return rid, what

    def _may_move(self, topic: str, payload: str) -> bool:
        """Rule 6: a move the bridge could take, as far as the console can tell: read by the
        bridge's own parser of its topic (review 149: the console's guesses took ``120 , 30``
        for none and ``+10`` for one), and not a preset its rotator's retained list lacks
        (review 147: a STOP typed before such a typo was left unsent)."""
        parse = self._parsers.get(topic)
        if parse is None:
            return True
        try:
            read = parse(payload.encode())
        except (PayloadError, ValueError):
            return False
        if topic in self._presets:  # (the name as the bridge reads it: review 151)
            with contextlib.suppress(ValueError, TypeError):
                names = json.loads(self._last.get(self._presets[topic], ""))
                return not isinstance(names, dict) or read in names
        return True

    def _again(self, client: paho.Client) -> None:
        """Rule 6, as a connection comes up (paho's thread, under the lock, before paho sends
        its queue again): what the last one left unacknowledged, and the last words held."""
        out = client.drop_out_messages()
        typed = [(m, self._typed.pop(m.mid, None)) for m in out]
        self._typed.clear()
        cut: dict[str, int] = {}  # rotator -> the place after its last move that went
        for i, (_m, t) in enumerate(typed):
            if t is not None and t[2]:
                rid, what = self._kind(t[0], t[1])
                if what == "move":
                    cut[rid] = i + 1
        held, self._held = self._held, []
        for i, (m, t) in enumerate(typed):
            if t is None:  # the console's own: as paho would have
                client.publish(m.topic, m.payload, qos=m.qos, retain=m.retain)
            elif i >= cut.get(self._kind(t[0], t[1])[0], 0):
                if t[2] or self._kind(t[0], t[1])[1] == "last":  # (a move refused: said then)
                    self._send(client, t[0], t[1])
            elif t[2]:  # (one refused as it was typed was said so then)
                self.screen.log(
                    f"  not sure it was sent ({t[0]} {t[1]}): the console lost the broker "
                    "before it said so; not sent again: type it again if you still want it"
                )
        for topic, payload in held:
            self._send(client, topic, payload)

    def _subscribe(self, client: paho.Client) -> None:
        if self._v5:
            # retain-as-published: what is retained on the broker arrives marked so even while
            # we are subscribed, which is how the console knows what to remove at the end
            opts = SubscribeOptions(qos=1, retainAsPublished=True)
            client.subscribe([(f, opts) for f in self._filters])
        else:  # (rule 2: what is retained is what arrives)
            client.subscribe([(f, 1) for f in self._filters])

    def _on_subscribe(self, client: paho.Client, *_: Any) -> None:
        self._subscribed.set()

    def _on_message(self, client: paho.Client, userdata: Any, msg: paho.MQTTMessage) -> None:
        topic = msg.topic
        if topic == self._sync_topic:
            if msg.payload == self._sync_word:
                self._synced.set()
            return
        if not self._v5:  # rule 2: no flag says which are retained
            with self._lock:
                if msg.payload:
                    self._seen.add(topic)
                else:
                    self._seen.discard(topic)
        if msg.retain:
            with self._lock:
                if msg.payload:
                    self._retained[topic] = bytes(msg.payload)
                else:
                    self._retained.pop(topic, None)
        if not topic.startswith(self._topics.base + "/") or not msg.payload:
            return  # a Home Assistant config (kept track of) or a removal: not shown
        leaf = topic.rsplit("/", 1)[-1]
        text = msg.payload.decode("utf-8", "replace")
        if leaf == "status":
            self._show_target_info(topic, text)
            self._show_tracking(topic, text)
            return
        if leaf not in SHOWN_LEAVES or (self._last.get(topic) == text and leaf != "error"):
            return
        self._last[topic] = text
        root = topic.rsplit("/", 1)[0]
        on_status = leaf in STATUS_LEAVES and root in self._roots
        if on_status:
            self.screen.status(root, leaf, text)
        self.screen.log(f"  {topic} = {text}", quiet=on_status and leaf != "state")

    def _show_target_info(self, topic: str, text: str) -> None:
        """A locator target's distance and paths, once each time it changes."""
        with contextlib.suppress(ValueError, AttributeError, KeyError, TypeError):
            info = json.loads(text).get("target_info")
            key = f"{topic}:target_info"
            if info and json.dumps(info) != self._last.get(key):
                self._last[key] = json.dumps(info)
                where = info.get("locator") or f"{info['latitude']:.2f}, {info['longitude']:.2f}"
                root = topic.rsplit("/", 1)[0]
                self.screen.log(
                    f"  {root}: {where} is {info['distance_km']:,.0f} km away by the "
                    f"{info['path']} path (short {info['short_path_deg']:g}°, "
                    f"long {info['long_path_deg']:g}°)"
                )

    def _show_tracking(self, topic: str, text: str) -> None:
        """What tracking does, once each time its phase or pass changes."""
        with contextlib.suppress(ValueError, AttributeError, KeyError, TypeError):
            doc = json.loads(text)
            info, ended = doc.get("tracking"), doc.get("tracking_ended")
            key = f"{topic}:tracking"
            root = topic.rsplit("/", 1)[0]
            if info is None:
                if ended and self._last.get(key) != f"ended {ended}":
                    self._last[key] = f"ended {ended}"
                    self.screen.log(f"  {root}: tracking ended ({ended})")
                return
            shown = f"{info['body']} {info['phase']} {info.get('aos')}"
            if shown == self._last.get(key):
                return
            self._last[key] = shown
            now = f"now az {info['azimuth']:g} el {info['elevation']:g}"
            if info["phase"] == "waiting":
                self.screen.log(
                    f"  {root}: {info['body']} is below the horizon ({now}); waiting at "
                    f"az {info['aos_azimuth']:g} for its rise at {info['aos'][11:19]} UTC"
                )
            elif info["phase"] == "tracking":
                until = f" until {info['los'][11:19]} UTC" if "los" in info else ""
                flip = ", flipped (elevation past 90)" if info.get("flip") else ""
                self.screen.log(f"  {root}: tracking {info['body']} ({now}){until}{flip}")
            else:
                self.screen.log(f"  {root}: {info['body']}: no pass in the next two days")

    def _presets_text(self) -> str:
        """The first rotator's preset names, as its retained R/presets lists them."""
        topic = self._topics.rotator(self._ids[0]).presets
        with contextlib.suppress(ValueError, AttributeError):
            return ", ".join(json.loads(self._last.get(topic, "{}"))) or "none"
        return "see " + topic

    def publish(self, topic: str, payload: str) -> None:
        """Rule 6: a typed command, sent now, held (a last word) or refused."""
        with self._lock:
            self._sent.add(topic)
            if self.connected.is_set() and self._send(self._client, topic, payload):
                return
            last = self._kind(topic, payload)[1] == "last"
            if last and not self.connected.is_set():  # (one paho refused is in its queue)
                self._held.append((topic, payload))
            said = "held: it goes first when the broker is back" if last else "not sent"
            why = "has lost the broker" if self._ever else "has not reached the broker yet"
            self.screen.log(f"  {said} ({topic} {payload}): the console {why}")

    def _send(self, client: paho.Client, topic: str, payload: str) -> bool:
        """Under the lock: handed to paho; False if paho refused it for a connection lost (it
        keeps it: the next connection's ``_again`` decides, rule 6)."""
        info = client.publish(topic, payload, qos=1)
        went = info.rc == paho.MQTT_ERR_SUCCESS
        self._typed[info.mid] = (topic, payload, went)
        if went and info.is_published():  # (acknowledged before it was kept: past
            # ``_on_publish``; one paho refused raises there)
            self._typed.pop(info.mid, None)
        return went

    def _on_publish(self, client: paho.Client, userdata: Any, mid: int, *_: Any) -> None:
        """Rule 6: acknowledged, so not kept (paho's thread, holding paho's lock of its queue:
        the console's lock is not taken here; a message id paho hands out again later is then
        no old command's: review 147)."""
        self._typed.pop(mid, None)

    def command(self, line: str) -> bool:
        """Handle one typed line; False to quit."""
        words = line.split()
        if not words:
            return True
        head = words[0].lower()
        if head in ("q", "quit", "exit"):
            return False
        if head in ("help", "h", "?"):
            self.screen.log(self.help_text())
            return True
        rid = self._ids[0]
        if len(self._ids) > 1 and words[0] in self._ids:
            rid, words = words[0], words[1:]
            if not words:
                self.screen.log(f"  {rid} what? type 'help'")
                return True
        t = self._topics.rotator(rid)
        head, rest = words[0].lower(), words[1:]
        if head in ("s", "stop") and not rest:
            self.publish(t.stop, "STOP")
        elif head == "lock" and len(rest) == 1:
            self.publish(t.lock, rest[0].upper())
        elif head in OPTIONS and len(rest) == 1:
            self.publish(t.option(head), rest[0].upper())
        elif head == "el" and len(rest) == 1:
            self.publish(t.target_elevation, rest[0])
        elif head == "preset" and len(rest) == 1:
            self.publish(t.preset, rest[0])
        elif head == "park" and not rest:
            self.publish(t.park, "PARK")
        elif head == "locator" and len(rest) in (1, 2) and rest[1:] in ([], ["long"], ["short"]):
            path = rest[1] if len(rest) == 2 else "short"
            self.publish(t.target, json.dumps({"locator": rest[0], "path": path}))
        elif head == "track" and rest:
            self.publish(t.feature(tracking.COMMAND), " ".join(rest))
        elif head in ("long", "short") and not rest:
            self.publish(t.target, json.dumps({"path": head}))
        elif head == "nudge" and len(rest) in (1, 2) and all(map(_is_number, rest)):
            if len(rest) == 1:
                self.publish(t.nudge, rest[0])
            else:
                axes = dict(zip(("azimuth", "elevation"), map(float, rest), strict=True))
                self.publish(t.nudge, json.dumps(axes))
        elif _is_number(head) or head.startswith("{"):
            self.publish(t.target, " ".join(words))
        else:
            self.screen.log(f"  unknown command {line.strip()!r}; type 'help'")
        return True

    def help_text(self) -> str:
        first = self._topics.rotator(self._ids[0]).root
        lines = [
            "  Type (each line becomes an MQTT message, as from any other client):",
            f"    120            turn to 120 deg              -> {first}/target",
            "    120 30         azimuth and elevation (SPID, SatEL)",
            f"    el 30          elevation alone              -> {first}/target/elevation",
            f"    preset JA      a configured preset ({self._presets_text()})  -> {first}/preset",
            f"    park           the park position            -> {first}/park",
            f"    locator PM95   great-circle bearing from the station; add 'long' for the long "
            f"path -> {first}/target",
            "    long, short    the other path to that locator",
            f"    nudge -10      turn by a few degrees (az/el: nudge 5 -2) -> {first}/nudge",
            f"    track sun      follow the sun, moon, a satellite; 'track off' -> {first}/track",
            f"    s, stop        stop now                     -> {first}/stop",
            f"    lock on|off    safety lock                  -> {first}/lock",
            f"    jam on|off     Rotor-EZ options ({', '.join(OPTIONS)})",
        ]
        if len(self._ids) > 1:
            lines.append(
                f"    <id> ...       the same for one rotator (default {self._ids[0]}); ids: "
                + ", ".join(self._ids)
            )
        lines += ["    help           this list", "    q              quit (also ^D, ^C)"]
        return "\n".join(lines)

    def sync(self, timeout_s: float = 5.0) -> bool:
        """Wait until everything the broker had for us so far has arrived (a round trip through
        it: what was published before our marker reaches us before the marker)."""
        if not self.connected.wait(timeout_s):
            return False
        self._sync_word = f"sync {secrets.token_hex(4)}".encode()  # (then cleared: an
        self._synced.clear()  # older marker back meanwhile ends no wait, review 147)
        self._client.publish(self._sync_topic, self._sync_word, qos=1)
        return self._synced.wait(timeout_s)

    def mark_private_broker(self, instance: str, timeout_s: float = 5.0) -> None:
        """Rule 5: say on the broker that it is this demo's private one, and ends with it."""
        self._client.publish(PRIVATE_BROKER_MARK, instance.encode(), qos=1, retain=True)
        self.sync(timeout_s)  # (rule 6: a round trip behind it)

    def retained(self, topic: str) -> bytes | None:
        with self._lock:
            return self._retained.get(topic)

    def look(self, topic: str, timeout_s: float = 5.0) -> bytes | None:
        """Rule 2: what ``topic`` holds retained, asked alone (its own subscription, then a
        round trip): on MQTT 3.1.1 a broker may hand a new subscription's many retained
        messages after a later marker (review 134: aedes, a bridge's 150 configs), where one
        alone comes ahead of it. None: nothing, or no answer in time."""
        if not self.connected.wait(timeout_s):
            return None
        if self._v5 or self.retained(topic) is not None:
            self.sync(timeout_s)
            return self.retained(topic)
        self._subscribed.clear()
        self._client.subscribe(topic, 1)
        if self._subscribed.wait(timeout_s):
            self.sync(timeout_s)
        self._client.unsubscribe(topic)
        return self.retained(topic)

    def remove_retained(self, timeout_s: float = 3.0) -> int | None:
        """Clear every retained message seen on the demo's topics; how many there were (None:
        the broker no longer answers, as a private one a Ctrl-C ended with the demo)."""
        if not self.sync(timeout_s):  # the bridge's last "offline" included
            return None
        with self._lock:
            seen = self._seen - self._sent  # (rule 2: those kept retained alone)
            kept = {t for t in seen if any(topic_matches_sub(f, t) for f in self._kept)}
            topics = sorted(self._retained if self._v5 else kept)
        for topic in topics:
            self._client.publish(topic, b"", qos=1, retain=True)
        if not self.sync(timeout_s):  # rule 6: behind them all, on whichever connection
            return None  # (review 147: said removed, though the broker took none of them)
        return len(topics)

    def close(self, *, remove_retained: bool = False) -> None:
        try:
            if remove_retained:
                n = self.remove_retained()
                self.screen.log(
                    f"rotor-bridge demo: removed its {n} retained messages"
                    if n is not None
                    else "rotor-bridge demo: the broker no longer answers, so its retained "
                    "messages were not removed (a private broker, ended with the demo, keeps none)"
                )
        finally:
            self._client.disconnect()
            self._client.loop_stop()


def private_broker_of(host: str, port: int, timeout_s: float = 5.0) -> str | None:
    """Rule 5: the instance of the demo whose private mosquitto answers at host:port; None for
    any other broker, and when that cannot be told in time (a broker that wants a login)."""
    probe = f"rotor-demo/probe/{secrets.token_hex(4)}"
    owner: list[str] = []
    done = threading.Event()

    def on_connect(client: paho.Client, u: Any, f: Any, rc: ReasonCode, p: Any) -> None:
        if rc.is_failure:
            done.set()
        else:
            client.subscribe([(PRIVATE_BROKER_MARK, 1), (probe, 1)])

    def on_subscribe(client: paho.Client, u: Any, mid: int, rcs: Any, p: Any) -> None:
        # a retained mark comes right behind the subscription, so before this round trip
        client.publish(probe, b"probe", qos=1)

    def on_message(client: paho.Client, u: Any, msg: paho.MQTTMessage) -> None:
        if msg.topic == probe:
            done.set()
        elif msg.payload:
            owner.append(msg.payload.decode("utf-8", "replace"))

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="", protocol=paho.MQTTv5)
    c.on_connect, c.on_subscribe, c.on_message = on_connect, on_subscribe, on_message
    try:
        c.connect(host, port, clean_start=True)
    except OSError:
        return None
    c.loop_start()
    try:
        done.wait(timeout_s)
    finally:
        c.disconnect()
        c.loop_stop()
    return owner[-1] if owner else None


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True
