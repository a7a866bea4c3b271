"""Attack 8 on session.py rule 13 (c222c9df, 559c7859): a feature's command that moves, stamped
and taken under a hold, is the start judged when the hold ends; past its expiry the target its
part proposed is dropped (``_waited``: ``waiting.part``). A later command under the same hold
takes its place in ``_wait`` before its part has run, on the ground that it ended what the one
before began: ``_end`` ends tracking, following and the parts' own motion, but not the target
the late command's part proposed, which only a new target of the later command's would replace.
When the later command ends in no target (its part refuses it, saying so; or the session's own
check refuses the target it proposed: outside the limits), the late command's target stays
pending, nothing judges it at the hold's end, and the rotor turns to it after the STOP.

Sequence: a STOP holds the rotator for its marker; a remote's ``aim 200`` (stamped, 5 s
expiry) is taken under the hold, its part proposing 200; then another ``aim`` (unstamped, or
stamped with a long expiry) that ends in no target; the marker comes back 8 s later. The rotor
must not turn to the 200 sent 8 s earlier with a 5 s expiry (it does with no second command:
test_session_last_word.py)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

import bridge.feature
from bridge.core.errors import Refused
from bridge.core.model import ErrorKind, FeatureCommand, Origin, Source, Stop, Target
from bridge.feature import CommandTopic, Feature
from bridge.features import FEATURES
from bridge.session.actions import Report
from bridge.session.parts import Part, Proposal, Wake
from bridge.session.session import RotatorSession
from tests.engine.test_feature_commands import TOY
from tests.engine.test_session_last_word import bearings, ready
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def _dish_command(s: RotatorSession, cmd: FeatureCommand, now: float) -> Proposal | None:
    """A well-behaved part: ``aim <az>`` judged by the rotator's aim; one it may not turn to is
    refused, said, and no target proposed."""
    assert isinstance(cmd.value, float)
    target = Target(cmd.value, None, cmd.source, origin=cmd.origin)
    try:
        return Proposal(target=s.cfg.aim.judge(target, s.status.raw_bearing_deg))
    except Refused as exc:
        return Proposal(error=Report(ErrorKind.REFUSED, exc.message, f"dish aim {cmd.value:g}"))


def _parse(payload: bytes, by: Origin) -> FeatureCommand:
    """``aim <az>`` (unused here: the commands are put as the judge puts them)."""
    return FeatureCommand(feature="dish", name="aim", value=float(payload.split()[-1]), origin=by)


DISH = Part[RotatorSession](
    "dish",
    Wake.STEP,
    True,
    lambda s: False,
    lambda s, scene: None,
    lambda s, now: None,
    command=_dish_command,
)
DISH_FEATURE = Feature(
    "dish",
    "docs/architecture.md",
    "turns the rotor on its own command",
    commands=(CommandTopic("dish", "dish", _parse),),
    part=DISH,
)


@pytest.mark.parametrize("second_s", [None, 60.0])
@pytest.mark.parametrize("feature", ["dish", "beam"])
def test_a_later_command_ending_in_no_target_does_not_let_a_late_commands_target_go(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, feature: str, second_s: float | None
) -> None:
    """``dish``: the part refuses ``aim 999`` itself (an error, no target); ``beam``: the toy's
    ``raw 999`` proposes it unjudged and the session's check refuses it (outside the limits)."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY, DISH_FEATURE))
    v = ready(rig)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    late = FeatureCommand(feature=feature, name="aim", value=200.0, not_after_s=t + 5.0)
    v.mailbox.put_feature(late)  # stamped, taken under the hold: its part proposes 200
    v._take()
    name = "aim" if feature == "dish" else "raw"
    expiry = None if second_s is None else t + second_s
    v.mailbox.put_feature(
        FeatureCommand(feature=feature, name=name, value=999.0, not_after_s=expiry)
    )
    v._take()
    v.run_for(8.0)
    assert bearings(v, since=t) == []  # (held)
    v.mailbox.put_release(1)  # the marker back, past the first command's expiry
    v._take()
    v.run_for(30)
    said = [e.message for e in v.errors(since=t)]
    assert any("outside" in m for m in said), said  # (the second command refused, said)
    assert bearings(v, since=t) == [] and not v.truth().is_moving, (
        "the rotor turned after the STOP to the 200 of a command whose expiry passed while it "
        f"waited: {said}"
    )
