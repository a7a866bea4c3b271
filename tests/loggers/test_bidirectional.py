"""N1MM's ``bidirectional`` (interfaces/loggers/commands.py rule 4) in virtual time: the real
command handler, a rotator whose status and mailbox are a virtual rotator's, an emulated
controller on the rotor's own travel (a Hy-Gain rotor's stop at south, a Yaesu's at north)."""

from __future__ import annotations

import math
import socket
from typing import Any

import pytest

from bridge.core.model import RotatorStatus, Source, Target
from bridge.interfaces.loggers.commands import Commands, N1mmEndpoint, N1mmRotor, PstEndpoint
from bridge.interfaces.loggers.datagrams import N1mmRequest, PstRequest
from bridge.pointing import Pointing
from tests.engine.virtual import VirtualRotator


class _Through:
    """The loggers' view of a rotator (commands.py ``Rotator``): the virtual rotator's status
    and judge; a target handed to it is judged and put in its mailbox, as Rotator.submit does."""

    def __init__(self, v: VirtualRotator) -> None:
        self.v, self.id = v, "v"
        self.last_halt_s = -math.inf
        self.sent: list[Target] = []

    @property
    def status(self) -> RotatorStatus:
        return self.v.status

    @property
    def pointing(self) -> Pointing:
        return self.v.cfg.aim

    @property
    def spec(self) -> Any:
        return self.v.cfg.spec

    @property
    def halts(self) -> int:
        return 0

    def halts_for(self, source: Source) -> int:
        return 0

    def submit(
        self,
        command: Any,
        described: str | None = None,
        *,
        since: Any = None,
        seen_s: Any = None,
        reader: Any = None,
        read_s: Any = None,
    ) -> None:
        self.sent.append(command)
        self.v.aim(command)

    def report_refusal(self, message: str, command: str | None, **_kw: Any) -> None:
        raise AssertionError(message)


@pytest.mark.parametrize(
    ("model", "emulator", "keep_out", "heading"),
    [
        ("rotorcard", {}, [[80, 95]], 90.0),
        ("rot2prog", {}, [[80, 95]], 90.0),
        ("satel", {"step_deg": 10}, [[80, 95]], 90.0),
        ("satel", {"step_deg": 10}, [[88, 92]], 86.0),  # 86 goes out as 90, in the sector
    ],
)
def test_a_bidirectional_heading_the_judge_refuses_turns_to_its_reciprocal(
    model: str, emulator: dict[str, Any], keep_out: list[list[float]], heading: float
) -> None:
    """An attack pass: the heading the rotor turned less to was chosen though the judge
    refused it (a keep-out sector), and nothing turned, where its reciprocal was free."""
    settings = {"keep_out": keep_out}
    v = VirtualRotator(model, emulator={**emulator, "start_az_deg": 100.0}, settings=settings)
    with v:
        v.run_until(lambda h: h.status.available, 20, "the controller answers")
        v.run_for(8.0)
        rot = _Through(v)
        endpoint = N1mmEndpoint("127.0.0.1", 12040, [N1mmRotor("Tower", rot)])  # type: ignore[arg-type]
        req = N1mmRequest("Tower", azimuth=heading, bidirectional=True, freqband_mhz=14.0)
        Commands(lambda: v.now, lambda what, exc: None).n1mm(endpoint, req, b"<N1MMRotor/>")
        assert [t.az_deg for t in rot.sent] == [heading + 180.0]
        there = heading + 180.0
        v.run_until(
            lambda h: not h.truth().is_moving and abs(h.truth().az_deg - there) <= 5.0, 300, "there"
        )


@pytest.mark.parametrize(
    ("model", "emulator", "start", "heading", "goes"),
    [
        # a Hy-Gain rotor at 170: 185 is 15 degrees away on the compass but 345 along its
        # travel, round through north; 5 is 165 the other way
        ("rotorez", {"stop_at_south": True}, 170.0, 5.0, 5.0),
        ("rotorez", {"stop_at_south": True}, 190.0, 355.0, 355.0),  # ... and the other side
        ("rotorez", {"stop_at_south": True}, 100.0, 280.0, 100.0),  # there already
        # a Yaesu rotor (stop at north) at 350: 5 is 15 on the compass and 345 back round south
        ("rotorcard", {}, 350.0, 185.0, 185.0),
        ("rotorcard", {}, 10.0, 5.0, 5.0),
    ],
)
def test_a_bidirectional_heading_turns_the_rotor_the_lesser_way_along_its_travel(
    model: str, emulator: dict[str, Any], start: float, heading: float, goes: float
) -> None:
    """A review: the heading or its reciprocal was the one nearer the bearing on the compass,
    and a Hy-Gain rotor at 170 sent 5 turned to 185: 345 degrees, a minute, for a beam that
    170 to 5 (165) points the same two ways."""
    v = VirtualRotator(model, emulator={**emulator, "start_az_deg": start})
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(8.0)  # (its brake window over: idle)
        rot = _Through(v)
        endpoint = N1mmEndpoint("127.0.0.1", 12040, [N1mmRotor("Tower", rot)])  # type: ignore[arg-type]
        req = N1mmRequest("Tower", azimuth=heading, bidirectional=True, freqband_mhz=14.0)
        Commands(lambda: v.now, lambda what, exc: None).n1mm(endpoint, req, b"<N1MMRotor/>")
        assert [t.az_deg for t in rot.sent] == [goes]
        travel = abs(goes - start) if abs(goes - start) <= 180 else 360 - abs(goes - start)
        v.run_for(travel / 6.0 + 15.0)  # the lesser way at 6 degrees a second, and the brake
        assert abs(v.truth().az_deg - goes) <= 3.0 and not v.truth().is_moving


@pytest.mark.parametrize("bidirectional", [False, True])
@pytest.mark.parametrize(
    ("model", "start", "goes"), [("rotorcard", 355.0, 360.0), ("gs232b", 5.0, 0.0)]
)
def test_a_logger_s_north_is_the_end_of_a_yaesu_s_travel_nearer_the_rotor(
    model: str, start: float, goes: float, bidirectional: bool
) -> None:
    """commands.py rule 3: a logger folds its heading into 0..360, so its north was 0, the
    anticlockwise end of a Yaesu's travel: at 355 the rotor turned 355 degrees back through
    south, and bidirectional took 180 instead (an attack pass). North goes to the nearer end."""
    v = VirtualRotator(model, emulator={"start_az_deg": start})
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(8.0)
        rot = _Through(v)
        endpoint = N1mmEndpoint("127.0.0.1", 12040, [N1mmRotor("Tower", rot)])  # type: ignore[arg-type]
        req = N1mmRequest("Tower", azimuth=0.0, bidirectional=bidirectional, freqband_mhz=14.0)
        Commands(lambda: v.now, lambda what, exc: None).n1mm(endpoint, req, b"<N1MMRotor/>")
        assert [t.az_deg for t in rot.sent] == [goes]
        v.run_for(15.0)  # 5 degrees, and the brake
        assert abs(v.truth().az_deg - goes) <= 2.0 and not v.truth().is_moving


def test_pstrotator_s_north_is_the_end_of_a_yaesu_s_travel_nearer_the_rotor() -> None:
    """The same for PstRotator's ``<AZIMUTH>0``: a Yaesu at 355 goes to 360, not round to 0."""
    v = VirtualRotator("rotorcard", emulator={"start_az_deg": 355.0})
    with v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(8.0)
        rot = _Through(v)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        with sock:
            Commands(lambda: v.now, lambda what, exc: None).pst(
                PstEndpoint(rot, "127.0.0.1", 12000),  # type: ignore[arg-type]
                sock,
                12000,
                PstRequest(azimuth=0.0),
                ("127.0.0.1", 12001),
                b"<PST><AZIMUTH>0</AZIMUTH></PST>",
            )
        assert [t.az_deg for t in rot.sent] == [360.0]
        v.run_for(15.0)
        assert abs(v.truth().az_deg - 360.0) <= 2.0 and not v.truth().is_moving
