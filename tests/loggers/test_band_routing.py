"""Which rotator an N1MM turn goes to when rotators have bands (interfaces/loggers/commands.py rule
5): the pure choice, then Commands carrying it out on stand-in rotators (the wiring through the App,
mosquitto and two emulated controllers is tests/integration/test_band_map.py)."""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

import pytest

from bridge.core.model import RotatorStatus, Source, Stop, Target
from bridge.interfaces.loggers.commands import Commands, N1mmEndpoint, N1mmRotor, NoRotor, choose
from bridge.interfaces.loggers.datagrams import parse_n1mm
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from tests.support.clock import FakeClock
from tests.support.udp_logger import n1mm_turn


class Recording:
    def __init__(self, rid: str) -> None:
        self.id, self.spec = rid, REGISTRY["rotorez"]
        self.calls: list[Any] = []

    @property
    def status(self) -> RotatorStatus:
        """As the bridge's own rotator reads one at 10 (the raw bearing beside the bearing)."""
        return RotatorStatus(self.id, available=True, bearing_deg=10.0, raw_bearing_deg=10.0)

    @property
    def pointing(self) -> Pointing:
        """Its judge's terms, the model's (commands.py ``heading`` asks which way it turns)."""
        return Pointing.of(self.spec)

    def halts_for(self, source: Any) -> int:
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
        self.calls.append(replace(command, origin=None))

    def report_refusal(self, message: str, command: str | None, **_kw: Any) -> None:
        self.calls.append(("refused", message))


HIGH, LOW, PLAIN = Recording("high"), Recording("low"), Recording("plain")
HIGH_BANDS, LOW_BANDS = ("20m", "15m", "10m"), ("40m", "80m")


def shared(name: str = "Tower") -> list[N1mmRotor]:
    """One antenna per band, both under one N1MM name."""
    return [N1mmRotor(name, HIGH, HIGH_BANDS), N1mmRotor(name, LOW, LOW_BANDS)]  # type: ignore[arg-type]


def ids(choice: N1mmRotor | NoRotor) -> str | None:
    return choice.rotator.id if isinstance(choice, N1mmRotor) else None


@pytest.mark.parametrize(
    ("mhz", "rid"),
    [(14, "high"), (21.0, "high"), (28.0, "high"), (7, "low"), (3.5, "low"), (14.074, "high")],
)
def test_a_shared_name_turns_the_rotator_whose_bands_hold_the_messages_band(
    mhz: float, rid: str
) -> None:
    assert ids(choose(shared(), "Tower", mhz)) == rid


@pytest.mark.parametrize("mhz", [14, 7])
def test_star_is_chosen_by_band_too(mhz: float) -> None:
    assert ids(choose(shared(), "*", mhz)) == ("high" if mhz == 14 else "low")


@pytest.mark.parametrize(
    ("mhz", "why"),
    [
        (1.8, "no rotator is for 160m (high: 20m, 15m, 10m; low: 40m, 80m)"),
        (12.0, "<freqband> 12 MHz is no amateur band"),
        (None, "rotor 'Tower' is chosen by band, and the message has no <freqband>"),
    ],
)
def test_a_band_nobody_has_is_refused_to_every_rotator_it_could_have_gone_to(
    mhz: float | None, why: str
) -> None:
    choice = choose(shared(), "Tower", mhz)
    assert isinstance(choice, NoRotor) and choice.why == why
    assert [r.rotator.id for r in choice.could] == ["high", "low"]


def test_a_name_one_rotator_answers_to_turns_it_whatever_the_band() -> None:
    """The sender chose it (N1MM's Antennas tab, or the operator by hand): as before bands."""
    rotors = [N1mmRotor("Yagi", HIGH, HIGH_BANDS), N1mmRotor("Dipole", LOW, LOW_BANDS)]  # type: ignore[arg-type]
    assert ids(choose(rotors, "Yagi", 7)) == "high"
    assert ids(choose(rotors, "Dipole", 14)) == "low"
    assert ids(choose(rotors, "Yagi", None)) == "high"
    assert ids(choose(rotors, "*", 14)) == "high"  # "*": the band


def test_a_name_that_is_not_ours_is_ignored_not_refused() -> None:
    choice = choose(shared(), "Elsewhere", 14)
    assert choice == NoRotor()


def test_without_bands_it_is_as_before() -> None:
    one = [N1mmRotor("Yagi", PLAIN)]  # type: ignore[arg-type]
    assert ids(choose(one, "*", 14)) == "plain"  # "*" with one rotator on the port
    assert ids(choose(one, "*", None)) == "plain"
    two = [*one, N1mmRotor("Other", LOW)]  # type: ignore[arg-type]
    assert choose(two, "*", 14) == NoRotor()  # ambiguous: nothing, as before


def test_star_passes_over_a_rotator_without_bands() -> None:
    rotors = [N1mmRotor("Plain", PLAIN), *shared()]  # type: ignore[arg-type]
    assert ids(choose(rotors, "*", 7)) == "low"
    none = choose(rotors, "*", 1.8)
    assert isinstance(none, NoRotor) and [r.rotator.id for r in none.could] == ["high", "low"]


# -- carried out ------------------------------------------------------------------------------
def endpoint() -> tuple[N1mmEndpoint, Recording, Recording]:
    high, low = Recording("high"), Recording("low")
    e = N1mmEndpoint("127.0.0.1", 12040)
    e.rotors += [N1mmRotor("Tower", high, HIGH_BANDS), N1mmRotor("Tower", low, LOW_BANDS)]  # type: ignore[arg-type]
    return e, high, low


def carry(e: N1mmEndpoint, data: bytes, commands: Commands | None = None) -> Commands:
    commands = commands or Commands(FakeClock(), lambda where, exc: None)
    commands.n1mm(e, parse_n1mm(data), data, "127.0.0.1")
    return commands


def test_turns_go_by_band_and_a_band_nobody_has_moves_nothing_and_says_so(
    caplog: pytest.LogCaptureFixture,
) -> None:
    e, high, low = endpoint()
    commands = carry(e, n1mm_turn("Tower", 90, freqband="14"))
    carry(e, n1mm_turn("Tower", 200, freqband="7"), commands)
    assert high.calls == [Target(90.0, None, Source.N1MM)]
    assert low.calls == [Target(200.0, None, Source.N1MM)]
    with caplog.at_level(logging.WARNING, "bridge.interfaces.loggers.commands"):
        carry(e, n1mm_turn("Tower", 300, freqband="1.8"), commands)
    refusal = (
        "refused",
        "n1mm: no rotator is for 160m (high: 20m, 15m, 10m; low: 40m, 80m): nothing turned",
    )
    assert high.calls[1:] == [refusal] and low.calls[1:] == [refusal]
    assert "no rotator is for 160m" in caplog.text
    assert commands.counts["n1mm"].no_band == 1 and commands.counts["n1mm"].commands == 2


def test_a_stop_to_the_shared_name_stops_both_whatever_the_band() -> None:
    e, high, low = endpoint()
    carry(e, b"<N1MMRotor><stop><rotor>Tower</rotor><freqband>1.8</freqband></stop></N1MMRotor>")
    assert high.calls == low.calls == [Stop(Source.N1MM)]


@pytest.mark.parametrize("freqband", ["abc", "1e308", "nan", "14,074"])
def test_a_band_field_that_is_no_number_moves_nothing_and_the_refusal_quotes_it(
    freqband: str,
) -> None:
    """A review: ``<freqband>abc</freqband>`` was refused as "the message has no <freqband>",
    which sends the operator looking for a field that is there."""
    e, high, low = endpoint()
    carry(e, n1mm_turn("Tower", 90, freqband=freqband))
    refusal = (
        "refused",
        f"n1mm: rotor 'Tower' is chosen by band, and <freqband> {freqband!r} is no number of "
        "MHz: nothing turned",
    )
    assert high.calls == [refusal] and low.calls == [refusal]


def test_a_turn_without_a_band_field_says_it_has_none() -> None:
    e, high, low = endpoint()
    data = b"<N1MMRotor><rotor>Tower</rotor><goazi>90</goazi></N1MMRotor>"
    carry(e, data)
    refusal = (
        "refused",
        "n1mm: rotor 'Tower' is chosen by band, and the message has no <freqband>: nothing turned",
    )
    assert high.calls == [refusal] and low.calls == [refusal]
