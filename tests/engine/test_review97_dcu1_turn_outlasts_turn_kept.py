"""Review 97 (High), of 6311424a (motion.py rule 6 ``turn_kept``, kept.py rule 13): the state
file keeps a DCU-1's turn only till TURN_KEPT_S past the end the bridge assumed for it, and
that end is counted from where the bridge last sent the rotor (``assumed_deg``). A DCU-1
reports nothing, so a hand's turn at its panel since goes unseen: the operator turns it to the
far end of its travel, a logger then sends a bearing 3 degrees from the bridge's last one, and
the bridge assumes a turn of 3 degrees (some 3 s) while the rotor runs the whole way round. A
minute later the file says no turn while the rotor still turns to that target; a bridge
killed then (a crash, or ``systemctl restart``, whose end stops nothing the bridge takes for at
rest) starts with none kept, and a follow start refused at once halts nothing: the DCU-1 turns
on to the old target under "refused" (review 89's case, which every start halted before).
The rotor here turns at 5 degrees a second, its nominal 6 (a sixth slower: cold grease, wind
load, a motor rated for 60 Hz mains run from 50 Hz), well within the 1.5 times slower rule 6
allows for (BLIND_SLOW_FACTOR); at its nominal speed the same turn ends some 4 s inside the hold."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.test_attack19_follow_start_refused_grid import PARTNER
from tests.engine.test_follow import STATION
from tests.engine.test_review93_dcu1_turn_kept_in_the_state_file import Filed
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between

SLOWER = 5.0  # degrees a second, its nominal 6: a sixth slower (rule 6 allows down to 4)
LAST = round(PARTNER + 140.0)  # the bridge's last bearing (182), off the keep-out sector
HAND = LAST - 4  # the operator's, at the panel: 178, the far end of a south-stop travel
NEXT = LAST + 3  # a logger's next bearing: 3 degrees from the last the bridge sent


def test_a_dcu1_still_turning_after_its_turn_kept_ran_out_is_halted_by_a_refused_start(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    sector = [round(PARTNER) - 10, round(PARTNER) + 10]
    emulator = {"start_az_deg": round(PARTNER) + 20, "speed_deg_s": SLOWER, "stop_at_south": True}
    settings = {"keep_out": [sector]}
    with VirtualRotator("dcu1", emulator=emulator, follow=STATION, settings=settings) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        f = Filed(tmp_path / "state.json", v, monkeypatch)
        motion = v.cfg.motion
        v.target(LAST)
        # (the first connect's stop first and its brake, the turn's end assumed for the whole
        # range, and the hold after it: not a deadline)
        whole = mo.blind_busy_s(motion.az_span_deg, motion)
        v.run_for(motion.brake_delay_s + whole + mo.TURN_KEPT_S + 5.0)
        f.feed()
        assert angle_between(v.truth().az_deg, LAST) <= 1.0
        assert not f.says_turn()  # (at rest, a while after the bridge's turn)
        v.manual_rotate(HAND)  # the operator, at the panel: unseen by the bridge
        v.run_until(lambda h: not h.truth().is_moving, 120, "the hand's turn over")
        v.run_for(motion.brake_delay_s + 1.0)  # (its brake off: not a deadline)
        v.target(NEXT)  # a logger's next bearing: the rotor runs the whole way round
        # (the end assumed for 3 degrees, and the hold after it: not a deadline)
        v.run_for(mo.blind_busy_s(NEXT - LAST, motion) + mo.TURN_KEPT_S + 1.0)
        f.feed()
        assert v.truth().is_moving  # the bridge's turn still under way...
        # ...and the file keeps it (the whole range at the slowest, from when it was sent: it
        # said none here before the fix, the defect's cause)
        assert f.says_turn()
        f.restarted()  # killed here, started again from the file
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 7 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert "stop" in {fr.outcome for fr in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
