"""Attack pass 6 on lastword.py rule 15: "both topics refused, the markers are known denied
(rule 7)". Known denied for the rest of the connection: once ``markers_denied`` has run, no
marker is sent again (``_marker_sent_at`` cleared, ``_refused_now`` returns at once), delivery.py
keeps both topics in ``_denied`` (only this connection's hello or probe coming back, which
happens at connect, allows them again), and nothing asks the broker again. mosquitto reloads
its ACL on SIGHUP and keeps the connections: one reload that denied B/bridge/fence and
B/bridge/hello for the few seconds of one resend (an ACL file written in two steps, a typo
fixed by the next reload) leaves a bridge, connected for days, with rule 11's fences off and
rule 13's gap open although the broker takes its markers again.

What a neighbour then does with it: floods the main connection with targets (the backlog rule
11 is about), one of them published before the operator's rotctld S, read after it: the rotor
turns again after the S.
"""

from __future__ import annotations

from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.model import Target
from bridge.interfaces.mqtt.halts import FENCED
from tests.mqtt.test_attack5_refused_markers import _delivery
from tests.mqtt.test_service import RecordingRotator, saying_service


def test_after_a_short_acl_denial_of_the_markers_another_interfaces_stop_fences_again() -> None:
    clock, _said, pub, svc = saying_service()
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    delivery, paho_client = _delivery()
    svc.confirm_markers_with(
        lambda topic, payload: delivery.send(topic, payload.encode(), 1, retain=False),
        lambda topics: all(delivery.denied(t) for t in topics),
    )
    acl_denies = True  # the first reload (SIGHUP) denies B/bridge/# to the bridge's user
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP: the lane carries it out, holds
    for _ in range(5):  # its marker does not come back; sent again at QoS 1 (rule 15)
        clock.t += 1.0
        svc._halts.resend_if_due()  # noqa: SLF001 (the timer's work, halts._tick)
        svc._halts._refused_now()  # noqa: SLF001
        code = "Not authorized" if acl_denies else "Success"
        for mid, _topic, _data in paho_client.sent:
            delivery.on_publish(None, None, mid, ReasonCode(PacketTypes.PUBACK, code), None)  # type: ignore[arg-type]
        paho_client.sent.clear()
    assert not svc._halts.word.markers  # noqa: SLF001 (rule 15: known denied)
    acl_denies = False  # the administrator's next reload: the markers are allowed again
    svc.on_message("rotor/stop", b"", False)  # the STOP's copy: the hold ends (rule 7)
    for _ in range(3600):  # an hour of a live connection: the broker takes markers again
        clock.t += 1.0
        svc._halts.resend_if_due()  # noqa: SLF001
        svc._halts._refused_now()  # noqa: SLF001
        for mid, _topic, _data in paho_client.sent:
            ok = ReasonCode(PacketTypes.PUBACK, "Success")
            delivery.on_publish(None, None, mid, ok, None)  # type: ignore[arg-type]
        paho_client.sent.clear()
        for topic, payload, _retain in pub.take():  # whatever marker went comes back
            if topic in ("rotor/bridge/fence", "rotor/bridge/hello"):
                svc.on_message(topic, payload.encode(), False)
    tower.calls.clear()
    # rotctld's S, then a target published before it, read late (behind a flood of targets)
    svc.fence_asked("tower")
    svc.fence_carried("tower", lock=False)
    svc.on_message("rotor/target", b"300", False)
    moved = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not moved and ("refused", FENCED, "target '300'") in tower.calls, (
        "an hour after the ACL allowed the bridge's markers again, a target published before "
        "rotctld's S and read after it was sent to the controller (no fence: the markers are "
        f"still taken for denied, lastword.py rule 15): {tower.calls}"
    )
