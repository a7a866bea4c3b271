"""The last word on stop and lock, across the two MQTT connections. Pure: the clock is passed in;
the service (service.py rule 5) calls it under one lock, together with the mailbox put it
decides, so a decision and the command it lets through are one step.

Stop and lock come on two connections: the main one, in order with the targets behind any
flood, and the stop lane (lane.py), behind nothing. The broker keeps each connection's order,
but not the order between them. So:

1. The main connection is the order. Every stop and lock word it brings (ON and OFF) is carried
   out where it stands among the targets: a target before a stop is dropped by that stop, one
   after it is obeyed, and the lock ends on the last word published. Nothing is matched away
   or dropped as a duplicate on that side: a stop carried out twice stops twice (the session
   merges it on the wire), a lock ON twice is still ON.
2. The lane is the speed. A stop or a lock ON it brings is carried out at once, in full (the
   rotor stops, its target and tracking are dropped, the lock is set), and puts the rotator on
   **hold**: no target goes to the controller until the main connection has caught up with
   that word. To know when, the bridge publishes a **marker** of its own on the main connection
   (``B/bridge/fence``, this process's token and a number). The broker had the stop before the
   marker, so every message the main connection brings before the marker was published at or
   before the lane's word: a target among them waits (held, not sent), and the main
   connection's own copy of the stop or lock, which comes among them too, drops every target
   older than it, as rule 1 says. When the marker comes back, the hold ends and what is still
   pending (published after the word) goes out. Nothing is decided by matching copies, and
   nothing waits on a timer.
3. A lock OFF from the lane is not carried out (it comes in order on the main connection,
   rule 1), except while the main connection is down: then the lane's word is the only one.
4. The main connection may read a halt before the lane does (both are idle and race). The lane's
   copy, carried out late, would stop a target published after it and already on its way. So
   when the main connection carries out a halt the lane had no copy of waiting, the bridge
   publishes a **lane marker** (``B/bridge/fence/lane``, read by the lane only): the broker
   had the halt before it, so the lane's copy, if the lane has one, comes before the lane
   marker; a copy of that kind for that rotator read on the lane before then is the echo and
   is dropped, and the note ends when the lane marker comes back (within the lane's own round
   trip). A note is also forgotten when the lane reconnects (an older copy cannot come on the
   new connection). No clock decides it.
5. A hold ends with clearing when the main connection drops (nothing older can come any more;
   a target or tracking that waited is dropped and reported: its place in line is lost) and
   when it connects again. A marker still out after RESEND_S (a broker that drops messages for
   a reader that fell behind) is sent again with a new number; a later marker ends every hold
   before it. One that has not come back after GIVE_UP markers (an ACL that denies the marker
   topic: a broker may grant the subscription and drop the publish without a word) ends the
   holds with clearing and is reported as a problem (rule 7).
6. A retained stop or lock ON (a dashboard button set to retain by mistake) is carried out when
   it is published, like any, and reported; and once at most when the broker replays it: on a
   subscription, to either connection, at every reconnect. Under MQTT 5 the stop and lock
   topics are subscribed so that the broker replays nothing (retain handling 2) and a retained
   one is always live; under MQTT 3.1.1 a live one arrives without the flag, and one with it
   is a replay, known by its payload (a new payload on the topic is a new message; an empty
   retained message deletes it and is forgotten).
7. While the main connection cannot read the markers (rule 5, or a subscription the broker
   denies), the lane's halts hold nothing: they are still carried out at once, and again in
   order on the main connection, as before there were markers.
8. A lock OFF the main connection reads while a lane lock ON for that rotator still waits for
   its main copy was published before that ON: it is not carried out (the ON is the last word,
   even if the main connection then drops before its copy comes).
"""

from __future__ import annotations

import secrets
from collections import deque
from dataclasses import dataclass, field

RESEND_S = 2.0  # rule 5
GIVE_UP = 3


@dataclass
class LastWord:
    token: str = field(default_factory=lambda: secrets.token_hex(4))
    _next: int = 0
    _holds: dict[str, int] = field(default_factory=dict)  # rotator -> marker it waits for
    _marker_sent_at: dict[int, float] = field(default_factory=dict)  # markers still out
    _resends: int = 0
    _lane_waiting: dict[tuple[str, str], deque[int]] = field(default_factory=dict)
    _echoes: dict[tuple[str, str], deque[int]] = field(default_factory=dict)  # rule 4
    _lane_next: int = 0
    echoes: bool = True  # False: the lane cannot read its markers (rule 4 then notes nothing)
    _retained: dict[str, bytes] = field(default_factory=dict)  # rule 6

    # -- the lane (rule 2) -------------------------------------------------------------------
    def lane_halt(self, rotator_id: str, kind: str, now: float, hold: bool = True) -> int | None:
        """A stop or lock ON read on the lane: the marker to hold the rotator until (0: carry
        it out without a hold, rule 7), or None when it is the echo of one the main connection
        carried out (rule 4)."""
        key = (rotator_id, kind)
        echoes = self._echoes.get(key)
        if echoes:
            echoes.popleft()
            return None
        if not hold:
            return 0
        self._next += 1
        n = self._next
        self._holds[rotator_id] = n
        self._marker_sent_at[n] = now
        self._lane_waiting.setdefault(key, deque()).append(n)
        return n

    def marker(self, n: int) -> str:
        """The payload of marker ``n`` (either connection's)."""
        return f"{self.token} {n}"

    def lane_connected(self) -> None:
        """Rule 4: no copy of an older halt comes on the new connection."""
        self._echoes.clear()

    def lane_marker_back(self, payload: bytes) -> None:
        """Rule 4: the lane has read every copy it will get of the halts noted up to it."""
        n = self._number(payload)
        for echoes in self._echoes.values():
            while echoes and echoes[0] <= n:
                echoes.popleft()

    # -- the main connection (rule 1) ----------------------------------------------------------
    def main_halt(self, rotator_id: str, kind: str) -> int | None:
        """A stop or lock ON read on the main connection (it is carried out whatever this says):
        the lane's copy, if it came first, is accounted for; if not, the number of the lane
        marker to publish (rule 4)."""
        key = (rotator_id, kind)
        waiting = self._lane_waiting.get(key)
        if waiting:
            waiting.popleft()
            return None
        if not self.echoes:
            return None
        self._lane_next += 1
        self._echoes.setdefault(key, deque()).append(self._lane_next)
        return self._lane_next

    def lane_came_first(self, rotator_id: str, kind: str) -> bool:
        """Whether a halt the main connection reads now is one the lane has carried out already
        (rule 2: carried out again all the same; the audit trail counts it once)."""
        return bool(self._lane_waiting.get((rotator_id, kind)))

    def main_lock_off(self, rotator_id: str) -> bool:
        """Rule 8: whether a lock OFF read on the main connection is carried out."""
        return not self._lane_waiting.get((rotator_id, "lock"))

    def marker_back(self, payload: bytes) -> tuple[int, list[str]]:
        """A marker read on the main connection: its number (0 if it is not this process's)
        and the rotators whose hold ends with it."""
        n = self._number(payload)
        if not n:
            return 0, []
        self._resends = 0
        for sent in [m for m in self._marker_sent_at if m <= n]:
            del self._marker_sent_at[sent]
        for waiting in self._lane_waiting.values():
            while waiting and waiting[0] <= n:  # its main copy came before the marker, or
                waiting.popleft()  # was lost: either way none is to come (rule 1)
        released = [rid for rid, m in self._holds.items() if m <= n]
        for rid in released:
            del self._holds[rid]
        return n, released

    def main_gone(self) -> list[str]:
        """Rule 5 (the main connection dropped or is new): the rotators whose hold ends with
        clearing; every marker out is void."""
        released = list(self._holds)
        self._holds.clear()
        self._marker_sent_at.clear()
        self._lane_waiting.clear()
        self._resends = 0
        return released

    def resend_due(self, now: float) -> int | None:
        """Rule 5: a new marker to publish when one has been out RESEND_S, else None; -1 when
        GIVE_UP markers went unanswered (the caller ends the holds and reports it)."""
        if not self._marker_sent_at or now - min(self._marker_sent_at.values()) < RESEND_S:
            return None
        if self._resends >= GIVE_UP:
            return -1
        self._resends += 1
        self._next += 1
        n = self._next
        self._marker_sent_at = {n: now}  # (a later marker ends every hold before it)
        return n

    @property
    def holding(self) -> bool:
        return bool(self._holds)

    def _number(self, payload: bytes) -> int:
        token, _, number = payload.decode("ascii", "replace").partition(" ")
        return int(number) if token == self.token and number.isdigit() else 0

    # -- rule 6 ----------------------------------------------------------------------------------
    def retained_halt(self, topic: str, payload: bytes, replayed: bool) -> bool:
        """Whether a retained stop or lock ON is carried out: a live one always, a replay once."""
        if not payload:
            self._retained.pop(topic, None)  # deleted: a new one is a new message
            return False
        if not replayed:
            return True
        if self._retained.get(topic) == payload:
            return False
        self._retained[topic] = payload
        return True
