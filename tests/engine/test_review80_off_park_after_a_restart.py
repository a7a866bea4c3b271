"""Review 80: after a restart of the bridge in the storm, a rotor turned off its reached park is
said "parked for the storm" again.

16eb7df1 (wind.py rule 10) says a park reached and then turned off by a hand at the front
panel is "turned off its park after reaching it": R/status's ``off_park`` true, Home
Assistant's "Parked for the storm" OFF, the refusal saying where the rotor stands. The part
judges it against ``_wire``, the park's wire the session tells it when the park is sent. A
restart in the storm whose park was seen reached (``arrived``, kept by runtime/kept.py rule 4)
rightly sends no park again (rule 7) -- so ``_wire`` is never told, ``seen`` always clears
``_off``, and the rotor 160 degrees off its park is "parked for the storm" in R/status, Home
Assistant and every refusal until the storm ends: attack 25's defect again, one restart away.
(A rotor turned off after the restart is likewise never judged.)

In virtual time on the emulated MD-01 (test_wind's ``windy``, park at 90, turned to 250), the
state file the real one (test_wind_park_restart's ``restart``)."""

from __future__ import annotations

from pathlib import Path

from tests.engine.test_review63_storm_park_held_said_parked import ha_parked
from tests.engine.test_wind import windy
from tests.engine.test_wind_park_offline import parked_then_turned_by_hand
from tests.engine.test_wind_park_restart import restart

AFTER_S = 60.0  # virtual: the restarted bridge reads the rotor many times over


def test_a_rotor_turned_off_its_park_is_not_said_parked_after_a_restart(tmp_path: Path) -> None:
    with windy() as v:
        parked_then_turned_by_hand(v)
        assert v.status.wind is not None and v.status.wind.off_park  # (said so before)
        restart(v, tmp_path / "state.json")
        v.run_until(lambda h: h.status.available, 20, "the controller answers again")
        v.run_for(AFTER_S)
        assert abs(v.truth().az_deg - 250.0) < 1.0  # (rule 7: not turned back by itself)
        v.target(20.0)  # refused for the storm
        refusal = v.errors("refused")[-1].message
        wind = v.status.wind
        assert wind is not None and wind.storm
        assert wind.off_park and ha_parked(v) == "OFF" and "parked for the storm" not in refusal, (
            f"the rotor stands at {v.truth().az_deg:.0f}, its park is 90; R/status wind "
            f"off_park={wind.off_park}, Home Assistant {ha_parked(v)}, the refusal {refusal!r}"
        )
