"""Review 31 on 51f4ba95 (attack 6 D3): markers refused on a live connection are asked again
every RESEND_MAX_S (``Halts._refused_at``) and come back on once a PUBACK takes them. But
``main_gone`` forgets the asking ("the next connection's look asks"), and the next
connection's look only asks once: while the ACL still denies B/bridge/fence and
B/bridge/hello, its probe is refused and its hello never comes back, the markers are said
lost (client.py rule 16, ``markers_denied``), and nothing asks the broker again for the
rest of that connection. An ACL mended a minute after a reconnect (a broker restarted with a
typo in its ACL file, fixed by the next SIGHUP, which keeps the connections) leaves the
bridge with rule 11's fences off and rule 13's gap open for days, as D3 said of one resend:
a target published before rotctld's S and read after it turns the rotor again.
"""

from __future__ import annotations

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.model import Target
from bridge.interfaces.mqtt.halts import FENCED
from tests.mqtt.test_attack5_refused_markers import _delivery
from tests.mqtt.test_service import RecordingRotator, saying_service


@pytest.mark.xfail(
    strict=True,
    reason="review 31, open: markers said lost by a new connection's look are judged again "
    "on the next connect only (lastword.py rule 7), not asked again under the connection "
    "when the ACL is mended by a SIGHUP: fences off until the main connection reconnects",
)
def test_markers_denied_across_a_reconnect_are_asked_again_once_the_acl_is_mended() -> None:
    clock, _said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    delivery, paho_client = _delivery()
    svc.confirm_markers_with(
        lambda topic, payload: delivery.send(topic, payload.encode(), 1, retain=False),
        lambda topics: all(delivery.denied(t) for t in topics),
    )

    def run(seconds: int, code: str) -> None:
        for _ in range(seconds):
            clock.t += 1.0
            svc._halts.resend_if_due()  # noqa: SLF001 (the timer's work, halts._tick)
            svc._halts._refused_now()  # noqa: SLF001
            for mid, _topic, _data in paho_client.sent:
                ok = ReasonCode(PacketTypes.PUBACK, code)
                delivery.on_publish(None, None, mid, ok, None)  # type: ignore[arg-type]
            paho_client.sent.clear()
            for topic, payload, _retain in pub.take():  # whatever marker is taken comes back
                if code == "Success" and topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
                    svc.on_message(topic, payload.encode(), False)

    # an ACL reload (SIGHUP) with a typo denies B/bridge/# to the bridge's user: a lane
    # STOP's marker, sent again at QoS 1, is refused on both topics (0x87): known denied, and
    # asked again every RESEND_MAX_S (D3)
    svc.on_lane_message("rotor/stop", b"", False)
    run(20, "Not authorized")
    assert not svc._halts.word.markers  # noqa: SLF001
    svc.on_message("rotor/stop", b"", False)  # the STOP's copy: its hold ends (rule 7)
    # the administrator restarts the broker, the typo still there: the bridge reconnects; the
    # new connection's probe is refused (0x87), its hello never comes back: the look's time
    # up, the markers are said lost (client.py rule 16)
    svc.main_gone()
    svc.markers_denied()
    run(60, "Not authorized")
    # the typo fixed, a SIGHUP a minute later: the broker takes the markers again
    run(3600, "Success")
    tower.calls.clear()
    # rotctld's S, then a target published before it, read late (behind a flood of targets)
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)
    svc.on_message("rotor/target", b"300", False)
    moved = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not moved and ("refused", FENCED, "target '300'") in tower.calls, (
        "an hour after the ACL allowed the bridge's markers again, a target published before "
        "rotctld's S and read after it was sent to the controller (the markers said lost at "
        f"the reconnect are never asked again, lastword.py rule 15): {tower.calls}"
    )
