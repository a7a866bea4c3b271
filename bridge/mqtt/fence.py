"""Keeping a stop's place in line when it takes the fast lane (lane.py). Pure: the clock is
passed in.

A stop (or a lock) published after a target must win over it. On one connection the broker
keeps that order; with stop and lock on a lane of their own, a stop can overtake a target
still queued on the main connection, and the target would then turn the rotor after the
stop (the cold review's first finding: the rotor halted at 10, then went on to 128 by itself).

So stop and lock are subscribed on both connections, and each halt (a stop, a lock ON) is
carried out by the copy that comes first:
1. The first copy of a halt is carried out; the other copy, when it comes, is matched to it
   and dropped (one each way, oldest first; a copy older than MATCH_S is no longer waited
   for: that connection lost it).
2. While a halt carried out from the lane waits for its main-connection copy, every command
   that would move the rotor arriving on the main connection was published before that halt:
   it is dropped and reported, never carried out after the halt.
3. Lock OFF is never taken from the lane: it comes in order with the targets on the main
   connection (a target sent right after an unlock is obeyed, not refused as locked).
"""

from __future__ import annotations

from collections import deque

MATCH_S = 10.0


class Fence:
    def __init__(self, match_s: float = MATCH_S) -> None:
        self._match_s = match_s
        self._from_lane: dict[tuple[str, str], deque[float]] = {}  # carried out, main copy owed
        self._from_main: dict[tuple[str, str], deque[float]] = {}  # carried out, lane copy owed

    def halt(self, rotator_id: str, kind: str, lane: bool, now: float) -> bool:
        """Rule 1: whether this copy of a halt (``kind``: "stop" or "lock") is carried out."""
        key = (rotator_id, kind)
        other = self._from_main if lane else self._from_lane
        owed = self._fresh(other, key, now)
        if owed:
            owed.popleft()  # the other copy was carried out: this one is its echo
            return False
        mine = self._from_lane if lane else self._from_main
        mine.setdefault(key, deque()).append(now)
        return True

    def holds(self, rotator_id: str, now: float) -> bool:
        """Rule 2: a command that moves the rotor, from the main connection, must be dropped."""
        return any(
            self._fresh(self._from_lane, (rotator_id, kind), now) for kind in ("stop", "lock")
        )

    def _fresh(
        self, table: dict[tuple[str, str], deque[float]], key: tuple[str, str], now: float
    ) -> deque[float] | None:
        times = table.get(key)
        while times and now - times[0] > self._match_s:
            times.popleft()  # rule 1: that copy is not coming any more
        return times or None
