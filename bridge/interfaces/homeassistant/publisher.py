"""Home Assistant MQTT discovery, the publisher: keeps the entity table's messages
(entities.py) current on the broker, as the rotators' versions and the TLE file change, and
sends the state again when Home Assistant comes back. The only part of homeassistant/ with a
thread (a timer) and a lock.

Rules (numbered for all of homeassistant/; 1 to 3, 7 and 8 are entities.py's, whose 6 is
another):
4. Configs are published only when they changed. Configs under our node ids that we no longer
   generate (a rotator removed from the configuration), and that follow our bridge's state (a
   node id alone may be another bridge's), are cleared with an empty retained payload when the
   broker shows them to us; the client says what it did (or, for a config another client
   publishes while the bridge runs, that it left it alone), a flood of them in a few lines
   (interfaces/mqtt/client.py rule 15). Another bridge's config on one of our own topics (base
   topics that differ only in characters a node id cannot hold) is said once.
5. On Home Assistant's birth message every config is published again at once (``publish_again``,
   whether changed or not: a broker that replays retained messages only to exact-topic
   subscriptions, RabbitMQ, gives Home Assistant's ``homeassistant/#`` none of them), then the
   retained state after a delay, so Home Assistant, which ignores state that arrives before it
   has processed discovery, gets it. Births that come while a round's delay runs, or within
   ROUND_MIN_S of its start (a ``birth_delay_s`` of 0), do not push its state back and start
   nothing at once; once its state is out they get one round of their own (one of them may be
   a Home Assistant that restarted meanwhile), ROUND_MIN_S after the last one's start at the
   earliest: a flood of births costs one round of configs and state, and one log line
   (counting them), per delay and at most one per ROUND_MIN_S.
6. Discovery turned off (``homeassistant.enabled = false``, ``retired``): nothing is published
   and Home Assistant's birth is not answered, but rule 4's clearing still runs with nothing
   generated: every config under our node ids that follows our bridge's state, left by a run
   with discovery on, is cleared when the broker shows it to us (they kept the bridge's devices
   in Home Assistant for good, every entity unavailable). Configs that follow another bridge's
   state are left alone, as in rule 4. A broker that will not let the bridge read them (an ACL
   that keeps it out of the prefix: why its owner turned discovery off) costs only that, said
   once in the log (``optional``, interfaces/mqtt/client.py rule 17).
9. A rotator's configs go out for a new version of its controller at most once every
   ROUND_MIN_S; a version that comes within that is held, and the latest goes out when the
   time is up (a timer). A controller may say a version in every line (an Easycomm III's
   ``VE...`` is taken whenever it comes, a Rotor-EZ's banner after every stop at rest): an
   attack pass sent 200 ``VE`` lines in a second and Home Assistant was sent 4105 configs,
   each one rebuilt on the serial-lines thread.

Lock: ``_lock`` makes a snapshot of the configs and its publishing one step: the lines thread
(a controller's version arrived), paho's thread (Home Assistant came back) and the catalog's
watcher (the TLE file changed) all publish, and an older snapshot published last would stay
retained. ``on_status`` looks at a reading's version before taking it (see there).
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import replace

from bridge.core.model import RotatorStatus
from bridge.interfaces.homeassistant.entities import all_configs, rotator_messages, unshared
from bridge.interfaces.homeassistant.info import GroupInfo, Identity, RotatorInfo
from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics

log = logging.getLogger(__name__)

ROUND_MIN_S = 2.0  # rule 5: a round of configs and state at most this often


class DiscoveryPublisher:
    """Keeps the discovery messages current on the broker (see the module rules)."""

    def __init__(
        self,
        *,
        prefix: str,
        status_topic: str,
        topics: Topics,
        rotators: list[RotatorInfo],
        groups: tuple[GroupInfo, ...] = (),
        publish_retained: Callable[[str, str], None],
        clear_retained: Callable[[str], None],
        republish_state: Callable[[], None],
        birth_delay_s: float = 10.0,
        publish_again: Callable[[str, str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
        retired: bool = False,
    ) -> None:
        self.prefix = prefix
        self._retired = retired  # rule 6: publish nothing, clear what an earlier run left
        self._disc = DiscoveryTopics(prefix)
        self.status_topic = status_topic
        self._topics = topics
        self._ident = Identity(topics.base)
        if not retired:
            rotators = unshared(self._ident, rotators)  # rule 8, said once
            for r in rotators:
                for object_id in sorted(r.shared_ids):
                    log.warning(
                        "rotator %r: its Home Assistant entity %r would have the unique id of "
                        "another rotator's (%s_%s), which Home Assistant drops; it is given "
                        "%s:%s (rename the rotator to keep the usual form)",
                        r.rotator_id,
                        object_id,
                        self._ident.rotator_node(r.rotator_id),
                        object_id,
                        self._ident.rotator_node(r.rotator_id),
                        object_id,
                    )
        # (retired, rule 6: none generated, so every config of ours is cleared)
        self._rotators = {} if retired else {r.rotator_id: r for r in rotators}
        self._groups = () if retired else groups  # interfaces/mqtt/groups.py: a device each
        self._publish = publish_retained
        self._clear = clear_retained
        self._republish_state = republish_state
        self._publish_again = publish_again  # rule 5: a config, sent even if unchanged
        self._birth_delay_s = birth_delay_s
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._clock = clock
        self._round_t = -1e18  # rule 5: when the last round of configs and state began
        self._births_since = 0  # rule 5: births that began no round since it
        self._stopped = False
        self._current: dict[str, str] = {}
        self._said_twin = False  # rule 4: another bridge on our node ids, said once
        # rule 9: when each rotator's configs last went out for a version, those held since
        self._version_t: dict[str, float] = {}
        self._held: set[str] = set()
        self._version_timer: threading.Timer | None = None

    @property
    def subscriptions(self) -> list[str]:
        if self._retired:  # rule 6: Home Assistant's birth is none of ours
            return [self._disc.config_filter]
        return [self.status_topic, self._disc.config_filter]

    @property
    def optional(self) -> dict[str, str]:
        """Rule 6: the subscriptions whose denial is no problem, each with what it costs."""
        if not self._retired:
            return {}
        return {
            self._disc.config_filter: "with Home Assistant discovery off that only means "
            "configs an earlier run with it on left there, if any, are not cleared (delete "
            "the bridge's devices in Home Assistant by hand)"
        }

    def publish_all(self) -> None:
        if self._retired:  # rule 6
            return
        # under the lock (see Lock): an older snapshot published last would stay retained
        with self._lock:
            rotators = list(self._rotators.values())
            configs = all_configs(self.prefix, self._ident, self._topics, rotators, self._groups)
            self._current = configs
            for topic, payload in configs.items():
                self._publish(topic, payload)  # the client skips what did not change

    def set_satellites(self, satellites: tuple[str, ...]) -> None:
        """The TLE file changed: the track select offers what it holds now."""
        with self._lock:
            before = dict(self._rotators)
            self._rotators = {k: r.with_satellites(satellites) for k, r in before.items()}
            changed = self._rotators != before
        if changed:
            log.info("Home Assistant's track select now lists %d satellite(s)", len(satellites))
            self.publish_all()

    def set_spot_calls(self, calls: tuple[str, ...]) -> None:
        """The newest DX cluster spots changed (interfaces/dxcluster/client.py, at most once a
        minute): the spot select offers their calls."""
        with self._lock:
            before = dict(self._rotators)
            self._rotators = {k: r.with_spot_calls(calls) for k, r in before.items()}
            changed = self._rotators != before
        if changed:
            self.publish_all()

    def on_status(self, rotator_id: str, status: RotatorStatus) -> None:
        """A controller's version came: its rotator's configs say it (only they change; all of
        them for 16 rotators took a tenth of the start-up's CPU, once per rotator). A version
        already said is seen without the lock (every reading comes here): only this method
        changes one, on the thread of the rotator's statuses, and the dict read is whole. The
        configs at the start say the version kept from the last run (runtime/kept.py rule 11):
        a restart with the same firmware publishes nothing here."""
        version = status.version
        if not version:
            return
        known = self._rotators.get(rotator_id)
        if known is None or version == known.version:
            return
        with self._lock:
            r = self._rotators.get(rotator_id)
            if r is None or version == r.version:
                return
            r = self._rotators[rotator_id] = replace(r, version=version)
            if self._current:  # (else every config goes out below, as at the start)
                now = self._clock()
                wait = self._version_t.get(rotator_id, -math.inf) + ROUND_MIN_S - now
                if wait > 0 or rotator_id in self._held:  # rule 9: its latest, when it ends
                    self._held.add(rotator_id)
                    self._hold(max(wait, 0.0))
                    return
                self._version_t[rotator_id] = now
                self._send_rotator(r)
                return
        self.publish_all()

    def _send_rotator(self, r: RotatorInfo) -> None:
        """One rotator's configs as they are now (under the lock: see Lock)."""
        configs = rotator_messages(self.prefix, self._ident, self._topics, r)
        self._current.update(configs)
        for topic, payload in configs.items():
            self._publish(topic, payload)

    def _hold(self, wait: float) -> None:
        """Rule 9: the held rotators' configs go out ``wait`` from now (under the lock)."""
        if self._stopped or (self._version_timer is not None and self._version_timer.is_alive()):
            return  # (the one that runs sends them, or arms itself again for the rest)
        self._version_timer = threading.Timer(wait, self._release)
        self._version_timer.daemon = True
        self._version_timer.start()

    def _release(self) -> None:
        """Rule 9: each held rotator whose hold has ended gets its configs, its latest version."""
        with self._lock:
            self._version_timer = None  # (this thread: a hold may arm another)
            if self._stopped:
                return
            now = self._clock()
            later = []
            for rid in sorted(self._held):
                wait = self._version_t.get(rid, -math.inf) + ROUND_MIN_S - now
                if wait > 0:
                    later.append(wait)
                    continue
                self._held.discard(rid)
                self._version_t[rid] = now
                self._send_rotator(self._rotators[rid])
            if later:
                self._hold(min(later))

    def on_message(self, topic: str, payload: bytes, retain: bool) -> bool:
        """Handle Home Assistant's birth and our own retained configs; True if it was ours."""
        if topic == self.status_topic and not self._retired:
            if payload.strip().lower() == b"online":
                self._schedule_republish()
            return True
        parsed = self._disc.parse_config(topic)
        if parsed is None:
            return False
        _, node, _ = parsed
        if not self._ident.owns(node) or not payload:
            return True
        with self._lock:
            ours = self._current.get(topic)
        if ours is None:
            if self._names_our_bridge(payload):
                self._clear(topic)  # said by the client, a flood in a few lines (rule 4)
        elif (
            payload != ours.encode() and not self._said_twin and not self._names_our_bridge(payload)
        ):
            self._said_twin = True  # rule 4: once, however often the two overwrite each other
            log.warning(
                "another bridge publishes Home Assistant's config %s, one of ours: its base "
                "topic differs from ours (%r) only in characters a node id cannot hold "
                "(shack/rotor and shack_rotor are one node, rotorbridge_shack_rotor), so the two "
                "overwrite each other's entities; give one of them another base topic",
                topic,
                self._topics.base,
            )
        return True

    def _names_our_bridge(self, payload: bytes) -> bool:
        """Rule 4: a config is ours if it follows our bridge's state (every config this bridge
        ever published does: its availability, or the bridge's connection state). Node ids alone
        do not say it: another bridge's base topic can make ours a prefix of its node ids
        (``rotor/r/x`` beside ``rotor``: rotorbridge_rotor_r_x...), and clearing its configs
        took its entities out of Home Assistant, again each time it published them."""
        try:
            config = json.loads(payload)
        except (ValueError, RecursionError):  # (junk, or nested past the parser's depth)
            return False
        if not isinstance(config, dict):
            return False
        ours = self._topics.bridge_state
        availability = config.get("availability")
        topics = (
            [a.get("topic") for a in availability if isinstance(a, dict)]
            if isinstance(availability, list)
            else []
        )
        return config.get("state_topic") == ours or ours in topics

    def _schedule_republish(self) -> None:
        """Rule 5: a round of configs now and state after the delay, unless one runs."""
        now = self._clock()
        with self._lock:
            running = self._timer is not None and self._timer.is_alive()
            if running or now - self._round_t < ROUND_MIN_S:
                self._births_since += 1
                return
            self._round_t, more, self._births_since = now, self._births_since, 0
            self._timer = threading.Timer(self._birth_delay_s, self._round_done)
            self._timer.daemon = True
            self._timer.start()
        if self._publish_again is not None:  # rule 5, not on paho's thread
            threading.Thread(target=self._configs_again, daemon=True).start()
        log.info(
            "Home Assistant came online; state follows in %g s%s",
            self._birth_delay_s,
            f" ({more} more birth messages came during the last round)" if more else "",
        )

    def _round_done(self) -> None:
        """Rule 5: the round's state; births that came during the round get a round of their
        own (one may be a Home Assistant that restarted meanwhile), ROUND_MIN_S after this
        one's start at the earliest."""
        self._republish_state()
        with self._lock:
            if self._stopped or self._births_since == 0:
                return
            wait = max(0.0, self._round_t + ROUND_MIN_S - self._clock())
            self._timer = threading.Timer(wait, self._trailing)
            self._timer.daemon = True
            self._timer.start()

    def _trailing(self) -> None:
        with self._lock:
            self._timer = None  # (this thread: not a round that runs)
        self._schedule_republish()

    def _configs_again(self) -> None:
        """Rule 5: every config, as published last (under the lock: see Lock)."""
        with self._lock:
            if self._publish_again is not None:
                for topic, payload in self._current.items():
                    self._publish_again(topic, payload)

    def stop(self) -> None:
        with self._lock:
            self._stopped = True
            if self._timer is not None:
                self._timer.cancel()
            if self._version_timer is not None:
                self._version_timer.cancel()
