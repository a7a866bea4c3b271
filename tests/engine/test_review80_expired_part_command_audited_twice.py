"""Review 80: a feature's command whose expiry passed under a STOP's hold is two refusals of
its sender in the audit trail, one of them a target the sender never sent.

A feature's command that moves (``dish aim 200``), stamped, taken under a hold: its part
proposes the target, which goes by the command's expiry (session.py ``_feature_command``, rule
13). When the hold ends past that expiry, ``commands`` first drops the pending target as
expired (``_drop_pending(EXPIRED)``), then ``_waited`` ends the command -- whose comment says the
target its part proposed is "said once: below", but the target is gone already, so both say
it. dbb4a840 (rule 24) gives both reports the sender's origin, so the judge
(runtime/rotator.py ``_session_event``) audits two refusals: ``target az 200`` -- a command
G4XYZ never sent -- and ``dish aim 200``.

In virtual time (test_attack8_late_command_target's ``dish`` feature, on its Rotor-EZ)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

import bridge.feature
from bridge.core.model import FeatureCommand, Origin, Source, Stop
from bridge.features import FEATURES
from tests.engine.test_attack8_late_command_target import DISH_FEATURE
from tests.engine.test_feature_commands import TOY
from tests.engine.test_session_last_word import bearings, ready
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
G4XYZ = Origin(Source.MQTT, "G4XYZ")
EXPIRY_S = 5.0  # virtual: the command's stamp
HELD_S = 8.0  # virtual: the STOP's marker comes back past it
AFTER_S = 30.0  # virtual


def test_an_expired_feature_command_is_one_refusal_of_its_sender(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY, DISH_FEATURE))
    v = ready(rig)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    aim = FeatureCommand(
        feature="dish", name="aim", value=200.0, not_after_s=t + EXPIRY_S, origin=G4XYZ
    )
    v.mailbox.put_feature(aim)  # taken under the hold: its part proposes 200
    v._take()
    v.run_for(HELD_S)
    v.mailbox.put_release(1)  # the marker back, past the command's expiry
    v._take()
    v.run_for(AFTER_S)
    assert bearings(v, since=t) == []  # nothing went out
    audited = [(e.command, e.message) for e in v.errors(since=t) if e.origin == G4XYZ]
    assert len(audited) == 1, f"G4XYZ sent one command; the judge audits {audited}"


def test_a_feature_command_a_clearing_hold_ends_is_one_refusal_of_its_sender(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same command, unstamped, ended by the hold clearing (the main MQTT connection lost
    before the STOP's marker came back): its part's target and the command are one refusal,
    the command G4XYZ sent."""
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY, DISH_FEATURE))
    v = ready(rig)
    t = v.now
    v.mailbox.put(Stop(Source.MQTT), hold=1)
    aim = FeatureCommand(feature="dish", name="aim", value=200.0, origin=G4XYZ)
    v.mailbox.put_feature(aim)  # taken under the hold: its part proposes 200
    v._take()
    v.run_for(HELD_S)
    v.mailbox.put_release(1, clear=True)  # the hold clears: what waited goes no more
    v._take()
    v.run_for(AFTER_S)
    assert bearings(v, since=t) == []  # nothing went out
    audited = [(e.command, e.message) for e in v.errors(since=t) if e.origin == G4XYZ]
    assert [command for command, _ in audited] == ["dish aim 200"], audited
