"""Review 35's fix (lastword.py rule 15): markers a new connection's look found unreadable (its
hello never back, both topics refused 0x87) are asked again every RESEND_MAX_S; a PUBACK that
takes them clears the topics' refusals from ``B/bridge/info`` (delivery.py rule 11) but says
nothing of reading them, so they stay off until one comes back. Meanwhile ``B/bridge/info``
says so (else it would show nothing wrong while fences are off), and stops saying it once one
comes back and they are on again.
"""

from __future__ import annotations

from tests.mqtt.test_attack5_refused_markers import ConfirmedRig


def test_markers_taken_but_not_read_back_are_said_until_one_comes_back() -> None:
    rig = ConfirmedRig()
    svc, halts = rig.svc, rig.svc._halts  # noqa: SLF001
    for topic in ("rotor/bridge/fence", "rotor/bridge/hello"):  # the look's probe and hello
        rig.delivery.deny(topic, "publish to", "Not authorized")
    svc.main_gone()
    svc.markers_denied()  # the look's time up, its hello never back
    rig.run(120, "Success")  # the ACL lets the bridge publish them; none comes back
    assert not halts.word.markers, "a PUBACK alone turned on markers the look found unreadable"
    said = [problem for problem, on in rig.said if on and "takes the bridge's markers" in problem]
    assert len(said) == 1, f"B/bridge/info did not say the markers stay off: {rig.said}"
    rig.run(60, "Success", back=True)  # the ACL lets it read them too: the next one comes back
    assert halts.word.markers, "a marker asked with came back, and the markers stayed off"
    assert (said[0], False) in rig.said, f"B/bridge/info still says they are off: {rig.said}"
    fenced, calls = rig.fenced_against_rotctlds_stop()
    assert fenced, f"the markers back on, rotctld's S fenced nothing: {calls}"
