"""A controller's options (Rotor-EZ letters such as the jog or the ramp) and the automatic-motion
switch a SatEL report may ask for: what is owed to the controller, and when. Pure.

Rules:
1. Options are sent only while the rotor is idle (and settled: a rotor without a brake is idle
   while ``motion.settling``, and may still be turning), no target waits and the line is free,
   and re-sent after every (re)connect, after a power-on byte and every OPTIONS_REFRESH_S while
   idle: the controller forgets them at power-off, and the letters are idempotent.
2. A report that says automatic motion is off owes an enable, sent once the line is free and
   no slew or stop is under way.
"""

from __future__ import annotations

OPTIONS_REFRESH_S = 60.0


class Options:
    def __init__(self, values: dict[str, bool] | None) -> None:
        self.values: dict[str, bool] = dict(values or {})
        self.enable_due = False  # rule 2
        self._due: set[str] = set()
        self._sent_t = 0.0

    def connected(self, answering: bool) -> None:
        """A (re)connect: all are owed once the controller answers."""
        self.enable_due, self._sent_t = False, 0.0
        self._due = set(self.values) if answering else set()

    def all_due(self) -> None:
        """The controller answers again, or said it was powered on (rule 1)."""
        self._due = set(self.values)

    def set(self, name: str, enabled: bool, connected: bool) -> None:
        self.values[name] = enabled
        if connected:
            self._due.add(name)

    def take(self, idle: bool, free: bool, now: float) -> list[tuple[str, bool]]:
        """The options to write now (rule 1), by name."""
        if idle and self.values and now - self._sent_t >= OPTIONS_REFRESH_S:
            self._due = set(self.values)
        if not (self._due and idle and free):
            return []
        due, self._due, self._sent_t = sorted(self._due), set(), now
        return [(name, self.values[name]) for name in due]
