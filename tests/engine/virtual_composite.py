"""A composite rotator in virtual time: two boxes (two VirtualRotators, each a session, its
emulated controller and its line) run on one fake clock, with the composite's own parts in
front of them as the real worker has them (runtime/composite.py): one mailbox, the judge's
terms, ``split`` of every batch, and the ``Composition`` that merges the two statuses and ends
tracking in one box when the other ended it.

Rules:
1. Both boxes move on one clock: each step goes to the earliest thing either box has due
   (virtual.py rule 1), and both are stepped to it.
2. Every status a box publishes is seen by the composition, in the order it came; what the
   composition hands back (rule 4 of composite.py) goes to that box's session at once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from bridge.app import axis_configs, worker_config
from bridge.core.model import RotatorStatus, Stop, Target
from bridge.protocols.axes import Axis
from bridge.runtime.composite import (
    Composition,
    Siblings,
    joined,
    judged_whole,
    rotators_turn,
    share_quiet,
    split,
)
from bridge.session.mailbox import Batch, Mailbox
from bridge.session.session import OwnTurn
from bridge.session.tracking import Track
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from tests.engine.virtual import WALL_EPOCH_S, VirtualRotator


class VirtualComposite:
    def __init__(
        self,
        az_model: str,
        el_model: str,
        *,
        settings: dict[str, Any] | None = None,
        emulators: dict[Axis, dict[str, Any]] | None = None,
        sky: Sky | None = None,
        wall_epoch_s: float = WALL_EPOCH_S,
    ) -> None:
        rotator = RotatorSettings.model_validate(
            {
                "id": "v",
                "azimuth": {"model": az_model, "port": "/dev/ttyAZ"},
                "elevation": {"model": el_model, "port": "/dev/ttyEL"},
                **(settings or {}),
            }
        )
        self.cfg = worker_config(rotator, sky)
        boxes = axis_configs(rotator, sky)
        assert boxes is not None
        self.composition = Composition("v")
        self._siblings = Siblings()  # composite.py rules 6 and 8, as CompositeWorker
        self.mailbox = Mailbox()
        self.statuses: list[tuple[float, RotatorStatus]] = []
        self.boxes: dict[Axis, VirtualRotator] = {}
        self._seen: dict[Axis, int] = {}
        for axis, cfg, model in zip(Axis, boxes, (az_model, el_model), strict=True):
            self.boxes[axis] = VirtualRotator(
                model,
                cfg=cfg,
                sky=sky,
                wall_epoch_s=wall_epoch_s,
                emulator=(emulators or {}).get(axis),
                place=self._place,  # (composite.py rule 10: the rotator's places)
            )
            self._seen[axis] = 0
        sessions = {axis: box.session for axis, box in self.boxes.items()}
        joined(self.composition, sessions)
        judged_whole(self.cfg, sessions)  # (as CompositeWorker: composite.py rule 7)
        self._absorb()

    def _place(self, turn: OwnTurn) -> int:
        """As CompositeWorker's (composite.py rule 10)."""
        sessions = [box.session for box in self.boxes.values()]
        return self.mailbox.own_place(rotators_turn(turn, sessions))

    @property
    def az(self) -> VirtualRotator:
        return self.boxes[Axis.AZIMUTH]

    @property
    def el(self) -> VirtualRotator:
        return self.boxes[Axis.ELEVATION]

    @property
    def now(self) -> float:
        return self.az.now

    @property
    def status(self) -> RotatorStatus:
        return self.composition.status

    def wall(self) -> float:
        return self.az.wall()

    def close(self) -> None:
        self.mailbox.close()
        for box in self.boxes.values():
            box.close()

    def __enter__(self) -> VirtualComposite:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- commands: judged on the composite's terms, one mailbox, split (composite.py) -----------
    def aim(self, target: Target) -> None:
        self.mailbox.put(self.cfg.aim.judge(target, self.status.raw_bearing_deg))
        self._take()

    def stop(self) -> None:
        self.mailbox.put(Stop())
        self._take()

    def track(self, body: Body | None) -> None:
        self.mailbox.put_track(Track(body))
        self._take()

    def _take(self) -> None:
        batch = self.mailbox.take()
        if batch:
            batches = self.composition.offline(split(batch))  # (rules 1 and 8)
            if batch.target is not None:
                self.composition.aimed(batch, batches, self._holds)
            self._siblings.newer(batches)
            self._hand(batches)

    def _holds(self, axis: Axis, half: Target) -> bool:
        return self.boxes[axis].session.holds(half)  # (as CompositeWorker)

    def _hand(self, batches: dict[Axis, Batch]) -> None:
        for axis, batch in batches.items():
            box = self.boxes[axis]
            box._do(box.session.commands(batch, box.now))
        self._absorb()

    def _absorb(self) -> None:
        """Rule 2."""
        for axis, box in self.boxes.items():
            for t, status in box.statuses[self._seen[axis] :]:
                merged = self.composition.seen(axis, status)
                if merged is not None:
                    self.statuses.append((t, merged))
            self._seen[axis] = len(box.statuses)
        ends = self.composition.ends()
        if ends:
            self._hand(ends)
        sessions = {axis: box.session for axis, box in self.boxes.items()}
        for axis, step in self._siblings.follow(sessions, self.composition, self.now):
            box = self.boxes[axis]
            box._do(step(box.now))
            self._absorb()

    # -- time (rule 1) ----------------------------------------------------------------------------
    def run_for(self, seconds: float) -> None:
        end = self.now + seconds
        while self.now < end:
            self._step(end)

    def run_until(
        self, predicate: Callable[[VirtualComposite], object], timeout_s: float, what: str = ""
    ) -> float:
        start, end = self.now, self.now + timeout_s
        while not predicate(self):
            if self.now >= end:
                raise AssertionError(
                    f"not within {timeout_s:g} s: {what}\n  status={self.status}\n"
                    f"  az truth={self.az.truth()}\n  el truth={self.el.truth()}"
                )
            self._step(end)
        return self.now - start

    def _step(self, until: float) -> None:
        t = min(box.next_time(until) for box in self.boxes.values())
        for box in self.boxes.values():
            share_quiet([b.session for b in self.boxes.values()], t)  # composite.py rule 7
            box._step(t)
        self._absorb()
