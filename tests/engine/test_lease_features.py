"""The control lease beside following WSJT-X, as the judge (runtime/rotator.py) applies it, in
virtual time (a wall clock that is a number; no port is opened, so a start the lease lets
through is refused for the link). A follow start is judged like a track start: the lock, then
the lease, then the link; following off is never refused. Each is an audit event with its
origin. Following the holder started goes on, its targets the bridge's own with the interface
``wsjtx`` (the session, in virtual time). The wind park moving the rotor under a lease is
proven end to end in tests/integration/test_wind_bridge.py (the wind comes before the lease)."""

from __future__ import annotations

from pathlib import Path

from bridge.app import worker_config
from bridge.core.model import (
    AuditEvent,
    Claim,
    Control,
    ErrorEvent,
    FollowQso,
    Lock,
    Origin,
    Source,
)
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.session.config import FollowConfig
from bridge.session.follow import Follow
from bridge.settings import RotatorSettings
from tests.engine.test_follow import bearing, spid
from tests.engine.test_operators import HOLDER, OTHER, Clock, refused
from tests.integration.test_pointing_bridge import angle_between

STATION = (52.52, 13.4)


def follower(tmp_path: Path, clock: Clock) -> tuple[Rotator, list[AuditEvent], list[ErrorEvent]]:
    audit: list[AuditEvent] = []
    events: list[ErrorEvent] = []
    settings = RotatorSettings(id="t", model="md01", port="/dev/null", park_az_deg=0)
    cfg = worker_config(settings, None, FollowConfig(STATION, wsjtx=True))
    store = StateStore(tmp_path / "state.json")
    rot = Rotator(cfg, store, lambda s: None, events.append, wall=clock, on_audit=audit.append)
    assert rot.can_follow
    return rot, audit, events


def test_a_follow_start_by_another_than_the_holder_is_refused_and_audited(
    tmp_path: Path,
) -> None:
    clock = Clock()
    rot, audit, events = follower(tmp_path, clock)
    rot.submit(Claim("DL1ABC", 30, origin=HOLDER), "claim")
    clock.now += 300
    follow = lambda who: rot.submit(FollowQso(True, origin=who), "follow 'wsjtx'")  # noqa: E731
    assert refused(lambda: follow(OTHER)) == "leased"
    assert events[-1].message == (
        "DL1ABC holds the rotator until 14:43 UTC (25 min left): only they may turn it "
        "(control lease)"
    )
    assert events[-1].command == "follow 'wsjtx'"
    # the holder's start passes the lease (refused here only for the link: offline)
    assert refused(lambda: follow(HOLDER)) == "offline"
    # following off is never refused, whoever sends it (docs/architecture.md rule 11)
    rot.submit(FollowQso(False, origin=OTHER), "follow 'off'")
    # the lock comes before the lease: the other's start is refused for the lock
    rot.submit(Lock(True, origin=OTHER))
    assert refused(lambda: follow(OTHER)) == "locked"
    rows = [(a.origin.who, a.origin.interface, a.command, a.result.split(":")[0]) for a in audit]
    assert rows == [
        ("DL1ABC", Source.MQTT, "claim", "executed"),
        ("G4XYZ", Source.MQTT, "follow 'wsjtx'", "refused"),
        ("DL1ABC", Source.MQTT, "follow 'wsjtx'", "refused"),  # offline
        ("G4XYZ", Source.MQTT, "follow 'off'", "executed"),
        ("G4XYZ", Source.MQTT, "lock ON", "executed"),
        ("G4XYZ", Source.MQTT, "follow 'wsjtx'", "refused"),  # locked
    ]
    assert audit[1].result.startswith("refused: DL1ABC holds the rotator until 14:43 UTC")


def test_without_a_lease_a_follow_start_is_judged_only_for_the_link(tmp_path: Path) -> None:
    rot, audit, _ = follower(tmp_path, Clock())
    anyone = Origin(Source.MQTT)
    assert refused(lambda: rot.submit(FollowQso(True, origin=anyone), "follow")) == "offline"
    assert [a.result.split(":")[0] for a in audit] == ["refused"]


def test_following_the_holder_started_goes_on_and_its_targets_carry_the_wsjtx_origin() -> None:
    with spid() as v:
        v.mailbox.put_control(Control("DL1ABC", v.wall() + 1800))  # the judge's lease, shown
        v.mailbox.put_follow(Follow(True, origin=HOLDER))
        v.heard("JA1ABC", "PM95")
        v.run_until(lambda h: angle_between(h.truth().az_deg, bearing("PM95")) <= 0.5, 90, "PM95")
        assert v.status.control is not None and v.status.control.operator == "DL1ABC"
        # the status names the interface (wsjtx) and who switched following on
        assert (v.status.last_command_source, v.status.last_operator) == ("wsjtx", "DL1ABC")
        v.heard("W1AW", "FN31")  # a new partner: the rotor follows, the lease changes nothing
        v.run_until(lambda h: angle_between(h.truth().az_deg, bearing("FN31")) <= 0.5, 90, "FN31")
