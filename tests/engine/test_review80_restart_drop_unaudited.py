"""Review 80: a newer target a restarted SatEL's report drops is never a refusal in the audit trail.

dbb4a840 (session.py rule 24) says every drop of a command taken (``executed`` in the audit
trail) before it moved the rotor is its sender's refusal, said by one path (``_refuse_dropped``:
the report carries the sender's ``origin``, which runtime/rotator.py ``_session_event`` audits).
The SatEL's restart found by its clock (controller.py rule 14, ``Forgot``) drops the target
waiting -- a newer operator's target that stopped the slew -- and says it on R/error naming that
target (``command``), but by its own ``_error`` without the origin: the judge writes no line,
and the operator's target stays ``executed`` in the trail though it never went out.

In virtual time on the emulated SatEL (test_session_satel's scene: power-cycled mid-slew, then
redirected)."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import Origin, Source, Target
from tests.engine.test_session_satel import points, ready
from tests.engine.virtual import VirtualRotator

G4XYZ = Origin(Source.MQTT, "G4XYZ")
Rig = Callable[..., VirtualRotator]


def test_a_target_a_restarted_satel_drops_is_its_senders_refusal(rig: Rig) -> None:
    v = ready(rig)
    v.target(200, 40)
    v.run_for(10)
    v.power_cycle()  # its report never comes; its clock starts again at 2001/00/00
    t = v.now
    v.command(Target(100.0, 20.0, source=Source.MQTT, origin=G4XYZ))  # stops the slew
    v.run_for(200)
    assert points(v) == [b"p200 40\r"]  # the newer point never went out
    said = [e for e in v.errors(since=t) if e.command == "target az 100 el 20"]
    assert said, "the drop was said on R/error"
    assert any(e.origin == G4XYZ for e in said), (
        "the drop of G4XYZ's target is said without its sender, so the judge audits no "
        f"refusal: {[(e.kind, e.message, e.origin) for e in said]}"
    )
