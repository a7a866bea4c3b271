"""Rotor health's memory to the state file: what the health part (health.py) learned, kept
across restarts without ever writing beside a stop.

Rules:
1. ``seen`` is given every status on the lines thread and only looks: a report new since the
   last one (a move ended) is noted; the first one is the memory just read back, not news.
2. A noted report goes to the state file on its writer thread (state_store.py rule 5), at most
   every SAVE_S: a rotor tracking in small steps ends a move every few seconds, and an SD card
   would be written that often. ``flush`` (the rotator stopping) hands the last one over, and
   the report after a reset is written at once (``reset``): a repair's new baseline must not
   be lost to a power cut in the next minute.
3. A write that fails is logged by the state store; health is no safety matter and the next
   move tries again.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from bridge.core.model import RotatorHealth
from bridge.runtime.state_store import StateStore

SAVE_S = 60.0  # rule 2


class HealthMemory:
    def __init__(
        self, store: StateStore, rotator_id: str, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self._store = store
        self._id = rotator_id
        self._clock = clock
        self._kept: RotatorHealth | None = None
        self._unsaved: RotatorHealth | None = None
        self._saved_s = -math.inf

    def seen(self, health: RotatorHealth | None) -> None:
        """Rules 1 and 2."""
        if health is None or health is self._kept:
            return
        first, self._kept = self._kept is None, health
        if health.measured and not first:
            self._unsaved = health
            if self._clock() >= self._saved_s + SAVE_S:
                self.flush()

    def reset(self) -> None:
        """Rule 2: the next report (the reset's) is written at once."""
        self._saved_s = -math.inf

    def flush(self) -> None:
        """Rule 2: the newest unsaved report to the writer thread."""
        health, self._unsaved = self._unsaved, None
        if health is not None:
            self._saved_s = self._clock()
            memory = health.memory

            def save() -> None:
                self._store.set_health(self._id, memory)  # rule 3: its failure is logged there

            self._store.later(save)
