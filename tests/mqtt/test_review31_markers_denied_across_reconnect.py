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

from tests.mqtt.test_attack5_refused_markers import ConfirmedRig


def test_markers_denied_across_a_reconnect_are_asked_again_once_the_acl_is_mended() -> None:
    rig = ConfirmedRig()
    svc = rig.svc

    def run(seconds: int, code: str) -> None:  # (whatever marker is taken comes back)
        rig.run(seconds, code, back=code == "Success")

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
    fenced, calls = rig.fenced_against_rotctlds_stop()
    assert fenced, (
        "an hour after the ACL allowed the bridge's markers again, a target published before "
        "rotctld's S and read after it was sent to the controller (the markers said lost at "
        f"the reconnect are never asked again, lastword.py rule 15): {calls}"
    )
