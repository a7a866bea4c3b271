"""Cold review 29: a lock OFF that waited under a lane hold and is refused at the marker for
another interface's lock ON (the console's, counted in ``_lock_ons`` by ``fence_carried``),
or for another interface's halt under way, is said with LOCK_OFF_OLDER: "a lock ON that may
have been published after it came on the stop connection". Nothing came on the stop
connection; the words that fit are LOCK_OFF_FENCED's ("a lock ON that another interface
(the console, a logger) carried out first"), which the same OFF gets when read a moment
later. (test_lock_off_waits.py asserts the wrong words as they are.)
"""

from __future__ import annotations

from bridge.core.model import Lock, Source
from tests.mqtt.test_lock_off_waits import _refused, _waiting
from tests.mqtt.test_review22_lost_lane_copy import markers_back


def test_a_waiting_off_refused_for_the_consoles_lock_on_names_another_interface() -> None:
    svc, pub, tower = _waiting()
    svc.fence_asked("tower")
    tower.submit(Lock(True, source=Source.WEB))  # the console's lock ON
    svc.fence_carried("tower", lock=True)
    markers_back(svc, pub)
    why, what = _refused(tower.calls)[0]
    assert what == "lock OFF"
    assert "another interface" in str(why) and "stop connection" not in str(why), why
