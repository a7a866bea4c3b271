"""The control lease: one operator holds a rotator for a while, and motion from anyone else is
refused. Pure: no clock, no thread, no I/O; the time (unix seconds, the station's clock, the
wall clock never set back while the bridge runs: runtime/operators.py rule 5; the lease is
shown in UTC and kept across a restart) comes in with every call. Rotator (runtime/rotator.py)
keeps one per rotator, judges with it and carries out what it returns.

Rules:
1. A claim names an operator and a number of minutes, MIN_MINUTES to MAX_MINUTES; anything else
   is refused with a message saying what was wrong, and changes nothing. An interface's name
   (``mqtt``, ``rotctld 127.0.0.1``) is no operator's: it stands for everyone who sends
   without a name there, Home Assistant among them, and the lease would be theirs.
2. A claim while another operator holds the lease is refused naming the holder and the time it
   ends; the holder's own claim renews it (from now, for the minutes asked). A name is the
   same operator's whatever its case (``same_operator``: DL1ABC and dl1abc are one call).
3. The lease ends by itself at ``until``: from then on ``holder`` is None, with no call needed
   (``expired`` tells the caller once, so it can say so). It has ended too when more than
   MAX_MINUTES are left: the wall clock was set back between two runs of the bridge (a kept
   lease), and must not stretch it (rule 1).
4. Anyone may release it: the lease is coordination between operators who can all publish
   commands, not security (the broker's ACLs are); the station owner's release button must work
   whoever holds it. The audit log says who released it.
5. ``refusal`` is the judge's question: a motion command from ``who`` while another holds the
   lease gets the message to refuse it with; the holder's and anyone's while free get None.
   Stop, lock ON and tracking OFF never ask (docs/architecture.md rule 11). A target another
   operator sent before a claim, still waiting in the session when the lease changes hands,
   is dropped there by the same test of who sent it (session/session.py rule 23); one judged
   before the claim and put in the mailbox after it is refused at its put by that test too
   (session/mailbox.py rule 14), and so are a track or follow start and a feature's own
   command (a setting too, as the judge takes it) judged so. A satellite tracked by name is
   looked up on the sky worker: its answer is judged by the same test against the lease when
   it comes (session.py rule 23), so a look-up asked before a claim and answered after it
   starts nothing for another operator; nor does a start put before a claim and taken in
   the claim's own batch (session.py rule 23 judges it there, as it judges a target).
6. A lease kept across a restart (the state file) is taken only if a claim could have made it:
   an operator's name (not an interface's, rule 1), and at most MAX_MINUTES left. One that is
   not (a hand-edited or damaged file, a date no clock can show, the wall clock set far back)
   is ignored: ``restorable``.
"""

from __future__ import annotations

import math

from bridge.core.model import (
    OPERATOR_CHARS,
    Control,
    interface_name,
    same_operator,
    valid_operator,
)

__all__ = ["Lease", "LeaseError", "held_text", "restorable", "valid_operator"]

MIN_MINUTES = 1.0
MAX_MINUTES = 24 * 60.0


class LeaseError(ValueError):
    """A claim refused (rules 1, 2): nothing changed."""


def held_text(control: Control, now_unix: float) -> str:
    """``DL1ABC holds the rotator until 14:30 UTC (25 min left)``."""
    return control.held_text(now_unix)


def _ended(held: Control, now_unix: float) -> bool:
    """Rule 3: at its end, or the clock set back past a claim's longest."""
    return not 0.0 < held.until_unix - now_unix <= 60.0 * MAX_MINUTES


def restorable(held: Control | None, now_unix: float) -> Control | None:
    """Rule 6: the kept lease ``held`` if a claim could have made it, else None."""
    if held is None or valid_operator(held.operator) != held.operator:
        return None
    if interface_name(held.operator):  # rule 1: no claim makes it (an attack pass: restored)
        return None
    left_s = held.until_unix - now_unix
    return held if math.isfinite(left_s) and left_s <= 60.0 * MAX_MINUTES else None


class Lease:
    def __init__(self, held: Control | None = None) -> None:
        self._held = held

    def holder(self, now_unix: float) -> Control | None:
        """Rule 3: who holds it now (None once it has ended)."""
        held = self._held
        return held if held is not None and not _ended(held, now_unix) else None

    def has_ended(self, now_unix: float) -> bool:
        """Rule 3: whether ``expired`` would tell of an end now (asking changes nothing)."""
        held = self._held
        return held is not None and _ended(held, now_unix)

    def expired(self, now_unix: float) -> Control | None:
        """Rule 3: the lease that has ended by itself since the last call, once."""
        held = self._held
        if held is not None and _ended(held, now_unix):
            self._held = None
            return held
        return None

    def claim(self, operator: object, minutes: object, now_unix: float) -> Control:
        """Rules 1, 2: the new lease, or LeaseError saying why not."""
        name = valid_operator(operator)
        if name is None:
            raise LeaseError(
                f"operator must be a name of 1 to {OPERATOR_CHARS} characters, none of them "
                "invisible (core/model.py valid_operator)"
            )
        if interface_name(name):  # rule 1
            raise LeaseError(
                f"{name!r} is how the bridge names an interface, not an operator: claim the "
                "lease with your call sign"
            )
        if isinstance(minutes, bool) or not isinstance(minutes, (int, float)):
            raise LeaseError("minutes must be a number")
        if not MIN_MINUTES <= minutes <= MAX_MINUTES:  # (NaN, infinities, any int: exact)
            raise LeaseError(f"minutes must be from {MIN_MINUTES:g} to {MAX_MINUTES:g}")
        held = self.holder(now_unix)
        if held is not None and not same_operator(held.operator, name):
            raise LeaseError(f"not claimed: {held_text(held, now_unix)}")
        self._held = Control(name, now_unix + 60.0 * float(minutes))
        return self._held

    def release(self, now_unix: float) -> Control | None:
        """Rule 4: the lease released (None if it was free)."""
        held, self._held = self.holder(now_unix), None
        return held

    def refusal(self, who: str, now_unix: float) -> str | None:
        """Rule 5: why a motion command from ``who`` is refused, or None."""
        held = self.holder(now_unix)
        if held is None or same_operator(held.operator, who):
            return None
        return f"{held_text(held, now_unix)}: only they may turn it (control lease)"
