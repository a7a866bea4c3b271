"""Attack pass 6 on lastword.py rules 7 and 9: a lane hold put while the main connection's
markers are not known readable, and that connection's hello coming back late.

Rule 7 supports an ACL that denies the fence topic: the markers come back on the hello topic.
Until this connection's hello is back (``markers_allowed``) they are taken for denied when the
look's time runs out (``markers_denied``): a neighbour who planted a backlog of retained
messages under the base topic (or floods it at the connect) makes the hello that late. The stop
lane connects once the main connection is up, so it subscribes after the main connection's
``main_gone``: ``_lane_sub`` is newer than ``_main_past``, and no marker goes for it (markers
off). A STOP the lane reads then holds with no marker out (none is sent while markers are off).
The hello comes back: markers on. The STOP's own copy on the main connection is not counted
(rule 9: ``after > _main_past and self.markers``), so it sends no fresh marker; nothing is out
for ``resend_due`` to send again. The hold has no end: every MQTT target for that rotator is
refused as "published before a STOP" for as long as the connection lasts, until some other
halt's marker happens to come back.
"""

from __future__ import annotations

from bridge.core.model import Target
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import RecordingRotator, saying_service


def test_a_lane_stop_while_the_hello_is_late_does_not_hold_the_targets_for_ever() -> None:
    clock, _said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    svc.main_gone()  # a new main connection (app.py _main_new), before any message
    svc.markers_denied()  # its look's time ran out: the fence topic denied, the hello late
    svc.lane_connected()  # the stop lane connects once the main connection is up
    svc.lane_subscribed()
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP: carried out at once, on hold
    svc.markers_allowed()  # the main connection's hello comes back, after the backlog
    svc.on_message("rotor/stop", b"", False)  # the STOP's own copy on the main connection
    for _ in range(3600):  # an hour: the timer sends again whatever marker is out ...
        clock.t += 1.0
        svc._halts.resend_if_due()  # noqa: SLF001 (the timer's work, halts._tick)
        markers_back(svc, pub)  # ... and the main connection reads every one back
    tower.calls.clear()
    svc.on_message("rotor/target", b"120", False)  # published an hour after the STOP
    moved = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    released = svc._halts.word._holds == {}  # noqa: SLF001
    assert moved and released, (
        "an hour after the STOP, with the main connection reading its markers, a target "
        f"published then is refused as older than the STOP (the hold never ends): {tower.calls}"
    )
