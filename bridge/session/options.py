"""A controller's settings (Rotor-EZ letters such as the jog or the ramp, a GS-232's speed), as
their declarations say (protocols/base.py ``Setting``), and the automatic-motion switch a SatEL
report may ask for: what is owed to the controller, and when. Pure.

Rules:
1. A setting declared AT_REST (and one the model does not declare) is sent only while the rotor
   is idle (and settled: a rotor without a brake is idle while ``motion.settling``, and may
   still be turning), no target waits and the line is free; one declared ANYTIME whenever the
   line is free (the controller checks that no silent slew is under way and no stop is due).
   A setting declared ``resend`` (the controller forgets it at power-off) is sent again after
   every (re)connect, after a power-on byte and every OPTIONS_REFRESH_S while idle; the others
   (the controller keeps them) when they are set (set while the port is closed or the
   controller silent: once it answers), and once after the bridge starts (whether the
   controller has the kept value is not known). A controller may restart without saying so (a
   GS-232 back at its fastest speed): a stall that names a restart owes the ``resend`` ones
   again (controller.py rule 12), and so does a reply that never came (``unanswered``: was
   the box off?), at the first reading after it (``answered``); until then a target waits
   for that reading (session.py ``_try_target``), and a setting that may go while a target
   waits is written ahead of it (an attack pass: a GS-232 set to X1, power-cycled, turned at
   X4 until the refresh, up to a minute later).
2. A report that says automatic motion is off owes an enable, sent once the line is free and
   no slew or stop is under way.
3. What the controller was last sent is ``in_effect``; its speed factor (the product of the
   declarations' ``speed_factor``) scales the rotor's speeds the engine expects. A (re)connect
   or a power-on forgets the values it will send again: the controller runs at its own
   default until then.
4. A setting goes to the controller at most once per SETTING_GAP_S: a value set meanwhile
   waits, and only the last one set goes. Anyone who may publish
   ``R/option/<name>`` can send hundreds a second, and each went out as its own frame (a
   GS-232's line full of X commands, its polls crowded out, a target left unturned).
5. A value written is told in the log once (``news``): the same value written again (rule 1's
   refresh, a reconnect's) is not news (review 46: ``setting jam sent`` at INFO every minute
   for a letter typed once, 1,440 journal lines a day for each).
"""

from __future__ import annotations

import math

from bridge.core.model import SettingValue
from bridge.protocols.base import SendWhen, Setting

OPTIONS_REFRESH_S = 60.0
SETTING_GAP_S = 0.5  # rule 4


class Options:
    def __init__(
        self, values: dict[str, SettingValue] | None, settings: tuple[Setting, ...] = ()
    ) -> None:
        self.values: dict[str, SettingValue] = dict(values or {})
        self.declared = {s.name: s for s in settings}
        self.in_effect: dict[str, SettingValue] = {}  # rule 3
        self._unsent = set(self.values)  # rule 1: each is sent once after the start
        self.enable_due = False  # rule 2
        self._due: set[str] = set()
        self._sent_t = 0.0
        self._written_t: dict[str, float] = {}  # rule 4: when each was last written
        self.revision = 0  # one more for every value set: the status shows them (session.py)
        self._factor: float | None = None  # rule 3: speed_factor's, until in_effect changes
        self.unanswered = False  # rule 1: a reply never came; owed again at the next reading
        self._told: dict[str, SettingValue] = {}  # rule 5: the value last told in the log

    def _resent(self) -> set[str]:
        """The values the controller forgets, and those not sent since the start (rule 1)."""
        forgets = {n for n in self.values if n not in self.declared or self.declared[n].resend}
        return forgets | self._unsent

    def _forgotten(self) -> None:
        """Rule 3: what will be sent again is not in effect until it is."""
        for name in self._resent():
            self.in_effect.pop(name, None)
        self._factor = None

    def connected(self, answering: bool) -> None:
        """A (re)connect: all are owed once the controller answers."""
        self.enable_due, self._sent_t = False, 0.0
        self._forgotten()
        self._due = self._resent() if answering else set()

    def all_due(self) -> None:
        """The controller answers again, or said it was powered on (rule 1)."""
        self._forgotten()
        self._due = self._resent()

    def answered(self) -> None:
        """Rule 1: the first reading after a reply that never came (``unanswered``): the
        settings the controller forgets are owed again, still taken as in effect."""
        self.unanswered = False
        self._due |= self._resent()

    def set(self, name: str, value: SettingValue, connected: bool) -> None:
        self.values[name] = value
        self.revision += 1
        self._unsent.add(name)  # rule 1: owed until sent, whenever the controller answers
        if connected:
            self._due.add(name)

    def _anytime(self, name: str) -> bool:
        setting = self.declared.get(name)
        return setting is not None and setting.when is SendWhen.ANYTIME

    def take(
        self, idle: bool, free: bool, now: float, *, line_free: bool | None = None
    ) -> list[tuple[str, SettingValue]]:
        """The settings to write now (rule 1), by name: AT_REST ones when ``idle`` and ``free``
        (no target waits and the line is free), ANYTIME ones when ``line_free``."""
        if idle and self.values and now - self._sent_t >= OPTIONS_REFRESH_S:
            self._due |= self._resent()
        if not self._due:
            return []  # (the step of almost every reading)
        line_free = free if line_free is None else line_free
        due = sorted(
            n
            for n in self._due
            if ((idle and free) or (line_free and self._anytime(n)))
            and now - self._written_t.get(n, -math.inf) >= SETTING_GAP_S  # rule 4
        )
        if not due:
            return []
        self._due -= set(due)
        self._unsent -= set(due)
        self._sent_t = now
        self._written_t.update((n, now) for n in due)
        taken = [(name, self.values[name]) for name in due]
        self.in_effect.update(taken)
        self._factor = None
        return taken

    def news(self, name: str, value: SettingValue) -> bool:
        """Rule 5: whether writing ``value`` to ``name`` is news for the log (not the value
        told last)."""
        if name in self._told and self._told[name] == value:
            return False
        self._told[name] = value
        return True

    def speed_factor(self) -> float:
        """Rule 3: 1.0 when nothing in effect changes the rotor's speed (made again only once
        ``in_effect`` changed: rotor health asks at every reading)."""
        factor = self._factor
        if factor is None:
            factor = self._factor = math.prod(
                self.declared[n].speed_factor(v)
                for n, v in self.in_effect.items()
                if n in self.declared
            )
        return factor

    def owed_from(self, idle: bool) -> float:
        """From when ``owes(idle, t)`` holds while nothing else changes: -inf (now), inf
        (never), or the refresh's time (rule 1)."""
        if self._due:
            return -math.inf
        return self._sent_t + OPTIONS_REFRESH_S if idle and self.values else math.inf

    def owes(self, idle: bool, now: float) -> bool:
        """Whether ``take`` may give anything now (the question it asks first: the step asks
        it before it looks at the line)."""
        return bool(self._due) or (
            idle and bool(self.values) and now - self._sent_t >= OPTIONS_REFRESH_S
        )
