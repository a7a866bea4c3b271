"""Review 31 on 324b100f (halts.py ``keep_after_off``, ``_ends``): a tracking or following OFF
behind a waiting lock OFF goes at once and "drops a kept start it ends, as the mailbox would
(a track OFF a target or track start; a follow OFF a follow start)". The mailbox's track OFF
ends a follow start put before it too (session/mailbox.py ``put_track``: ``follow = None``,
"rule 9: the later command wins"); ``_ends`` keeps it. Published: lock ON, lock OFF, follow
wsjtx, track off. Without a hold the follow start is put before the track OFF, which drops it
in the mailbox. Behind the waiting OFF the track OFF goes now and the follow start, published
before it, is put after it at the marker: the rotor follows QSOs after the operator's last
word on moving said off. So does a park (or a preset, a nudge: a target in the mailbox,
which the track OFF replaces there).
"""

from __future__ import annotations

import pytest

from tests.mqtt.test_attack5_after_off import LockJudged
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import service


@pytest.mark.parametrize(
    ("topic", "payload", "kept"),
    [("rotor/follow", b"wsjtx", ("follow", True)), ("rotor/park", b"PARK", ("park",))],
)
def test_a_track_off_behind_a_waiting_lock_off_ends_the_kept_move(
    topic: str, payload: bytes, kept: tuple[object, ...]
) -> None:
    svc, pub, _rots = service({"tower": "rotorez"})
    tower = LockJudged("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried, on hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy, counted
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker (rule 13)
    svc.on_message(topic, payload, False)  # kept behind the OFF
    svc.on_message("rotor/track", b"off", False)  # the last word: goes now
    markers_back(svc, pub)
    calls = tower.calls
    off_at = max(i for i, c in enumerate(calls) if c[:2] == ("track", "off"))
    after = [c for c in calls[off_at:] if c[: len(kept)] == kept]
    assert ("lock", False) in calls and not after, (
        "a follow start or park published before a track OFF was put after it at the marker "
        f"(the mailbox drops it: put_track replaces a target and ends following): {calls}"
    )
