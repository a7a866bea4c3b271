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

from tests.mqtt.test_attack5_refused_markers import ConfirmedRig


def test_after_a_short_acl_denial_of_the_markers_another_interfaces_stop_fences_again() -> None:
    rig = ConfirmedRig()
    svc = rig.svc
    # the first reload (SIGHUP) denies B/bridge/# to the bridge's user
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP: the lane carries it out, holds
    rig.run(5, "Not authorized")  # its marker does not come back; sent again at QoS 1
    assert not svc._halts.word.markers  # noqa: SLF001 (rule 15: known denied)
    # the administrator's next reload: the markers are allowed again
    svc.on_message("rotor/stop", b"", False)  # the STOP's copy: the hold ends (rule 7)
    rig.run(3600, "Success", back=True)  # an hour: the broker takes markers, they come back
    fenced, calls = rig.fenced_against_rotctlds_stop()
    assert fenced, (
        "an hour after the ACL allowed the bridge's markers again, a target published before "
        "rotctld's S and read after it was sent to the controller (no fence: the markers are "
        f"still taken for denied, lastword.py rule 15): {calls}"
    )
