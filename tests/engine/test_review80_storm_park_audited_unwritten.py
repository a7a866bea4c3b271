"""Review 80: a storm's park that never went out is an ``executed`` line of the audit trail.

e5cbce17 (session.py rule 25) hands the judge ``Audit(wind, "park")`` -- written to the audit
file as the wind's command, executed -- the moment the wind part proposes its park, before the
park is written. A park that waits under the hold of a STOP put just before the storm (wind.py
rule 8) and is dropped, unsaid, when a calm reading ends the storm first (session.py ``_storm``,
review 60) never reaches the controller: no frame, the rotor never moves. The trail still
says the bridge parked the rotor, and no line says that park was dropped (rule 24's
``_refuse_dropped`` is not its path: the storm's end drops it unsaid). An auditor reading the
trail believes the rotor went to its storm park at that time.

In virtual time, a Rotor-EZ at 90 with its storm park at 180 (review 60's setting)."""

from __future__ import annotations

from bridge.core.model import Origin, Source
from tests.engine.test_review60_storm_park_after_the_storm import (
    MARKER,
    PARK_TIME_S,
    WIND,
    at_rest_at,
    held_through_a_short_storm,
)
from tests.engine.virtual import VirtualRotator


def test_a_storm_park_never_written_is_no_executed_line_in_the_audit_trail() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        held_through_a_short_storm(v, express=False)
        v.mailbox.put_release(MARKER)  # the hold's marker comes back, after the storm
        v._take()
        v.run_for(PARK_TIME_S)
        assert at_rest_at(v, 90.0)  # the park never went: the rotor stands where it stood
        audited = [a for _t, a in v.audited]
        # its drop as the wind's refusal (rule 24's way) would set the trail right too
        undone = [e for e in v.errors() if e.origin == Origin(Source.WIND)]
        assert audited == [] or undone, (
            f"the audit trail says {audited}: the storm's park executed, but it was never "
            "written, no line says it was dropped, and the rotor stayed at 90"
        )
