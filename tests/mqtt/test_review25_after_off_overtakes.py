"""COLD REVIEW 25 (f68d30a8), finding R25-5: FAILS at f68d30a8.

halts.py ``after_off`` keeps an MQTT move read after a waiting lock OFF *outside* the mailbox,
and puts it only when the marker comes back. Every other interface's target put meanwhile is
in the mailbox already (it waits under the hold: lastword.py rule 13, "another interface's
target waits too"), so the MQTT move, put later, replaces it (mailbox.py rule 2: the newer
put wins) though it was sent earlier. Published/sent, in order, while a lane STOP's hold is
up (its copy read): MQTT lock OFF (a script's "unlock, then turn"), MQTT target 300, then the
operator's logger (rotctld, PstRotator, the console) P 100. Expected: the rotor ends at 100,
the last word. Got: 300, sent before it, put after it. Without the waiting OFF (no ``after_off``)
the MQTT target goes into the mailbox when read, and the logger's 100 replaces it.
"""

from __future__ import annotations

from bridge.core.model import Source, Target
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import service


def test_r25_5_a_move_kept_behind_a_waiting_lock_off_does_not_overtake_a_newer_target() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # STOP, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy (rule 13: what follows waits)
    svc.on_message("rotor/lock", b"OFF", False)  # a script: unlock ... (waits in halts.py)
    svc.on_message("rotor/target", b"300", False)  # ... then turn (kept behind the OFF)
    tower.submit(Target(100.0, source=Source.ROTCTLD))  # the logger, after both: waits in the box
    markers_back(svc, pub)
    reached, _locked = controller(tower.calls)
    assert reached and reached[-1] == 100.0, (
        "the logger's P 100, sent after the MQTT target 300, was overtaken by it (the MQTT "
        f"target was put only when the marker came back): the controller got {reached}"
    )
