"""The control lease, in virtual time: the clock is a number handed in."""

from __future__ import annotations

import pytest

from bridge.core.model import Control
from bridge.runtime.lease import Lease, LeaseError, held_text, valid_operator

T0 = 1_790_000_000.0  # 2026-09-21 14:13:20 UTC (any fixed time: nothing reads the real clock)


def test_a_claim_holds_it_until_it_ends_by_itself() -> None:
    lease = Lease()
    held = lease.claim("DL1ABC", 30, T0)
    assert held == Control("DL1ABC", T0 + 1800)
    assert lease.holder(T0 + 1799) == held
    assert lease.expired(T0 + 1799) is None
    assert lease.holder(T0 + 1800) is None  # rule 3: nobody had to call anything
    assert lease.expired(T0 + 1800) == held  # said once...
    assert lease.expired(T0 + 1801) is None  # ...and not again


def test_another_operator_is_refused_naming_the_holder_and_the_end() -> None:
    lease = Lease()
    lease.claim("DL1ABC", 30, T0)
    why = lease.refusal("G4XYZ", T0 + 300)
    assert why == (
        "DL1ABC holds the rotator until 14:43 UTC (25 min left): only they may turn it "
        "(control lease)"
    )
    assert lease.refusal("rotctld 192.168.1.20", T0) is not None
    assert lease.refusal("DL1ABC", T0 + 300) is None
    assert lease.refusal("G4XYZ", T0 + 1800) is None  # ended


def test_a_claim_while_held_by_another_is_refused_and_changes_nothing() -> None:
    lease = Lease()
    held = lease.claim("DL1ABC", 30, T0)
    with pytest.raises(LeaseError, match="DL1ABC holds the rotator until 14:43 UTC"):
        lease.claim("G4XYZ", 10, T0 + 60)
    assert lease.holder(T0 + 60) == held
    renewed = lease.claim("DL1ABC", 5, T0 + 60)  # the holder renews, from now
    assert renewed.until_unix == T0 + 60 + 300
    assert lease.claim("G4XYZ", 10, T0 + 360).operator == "G4XYZ"  # once it has ended


@pytest.mark.parametrize(
    ("operator", "minutes", "why"),
    [
        ("", 30, "operator"),
        ("x" * 33, 30, "operator"),
        ("DL1\nABC", 30, "operator"),
        (None, 30, "operator"),
        (5, 30, "operator"),
        ("DL1ABC", 0, "minutes"),
        ("DL1ABC", 0.5, "minutes"),
        ("DL1ABC", 1441, "minutes"),
        ("DL1ABC", "30", "minutes"),
        ("DL1ABC", True, "minutes"),
        ("DL1ABC", float("nan"), "minutes"),
        ("DL1ABC", float("inf"), "minutes"),
        pytest.param("DL1ABC", 10**400, "minutes", id="minutes-past-a-float"),
    ],
)
def test_a_bad_claim_is_refused_and_changes_nothing(
    operator: object, minutes: object, why: str
) -> None:
    lease = Lease(Control("G4XYZ", T0 + 600))
    with pytest.raises(LeaseError, match=why):
        lease.claim(operator, minutes, T0)
    assert lease.holder(T0) == Control("G4XYZ", T0 + 600)


def test_anyone_may_release_it() -> None:
    lease = Lease(Control("DL1ABC", T0 + 600))  # as the state file kept it
    assert lease.release(T0) == Control("DL1ABC", T0 + 600)
    assert lease.holder(T0) is None and lease.refusal("G4XYZ", T0) is None
    assert lease.release(T0) is None  # free already


def test_operator_names() -> None:
    assert valid_operator("  DL1ABC ") == "DL1ABC"
    assert valid_operator("Anna at the club") == "Anna at the club"
    assert valid_operator("\x1b[2J") is None
    assert valid_operator("   ") is None


def test_the_minutes_left_round_up() -> None:
    held = Control("DL1ABC", T0 + 61)
    assert held_text(held, T0) == "DL1ABC holds the rotator until 14:14 UTC (2 min left)"
    assert held_text(held, T0 + 60) == "DL1ABC holds the rotator until 14:14 UTC (1 min left)"


def test_the_wall_clock_set_far_back_ends_the_lease_rather_than_stretch_it() -> None:
    """Rule 3: the lease is on the wall clock; set back a year (a bad NTP step, a hand-set
    date) it would otherwise hold the rotator for a year and 30 minutes. More than a claim
    may ask left (rule 1) means the clock moved: the lease has ended."""
    lease = Lease()
    held = lease.claim("DL1ABC", 30, T0)
    assert lease.holder(T0 - 3600) == held  # an hour back: 90 min left, still a lease
    back = T0 - 365 * 86400
    assert lease.holder(back) is None and lease.refusal("G4XYZ", back) is None
    assert lease.expired(back) == held  # said once, so the status says it is free
    assert lease.claim("G4XYZ", 10, back).operator == "G4XYZ"


def test_a_name_whose_joiner_follows_a_virama_claims_the_lease_wherever_the_joiner_stands() -> None:
    """core/model.py ``valid_operator``: a joiner at a name's end or before a space was refused
    as joining nothing, but after a virama it makes the consonant's other form: Malayalam's
    chillu typed the older way (consonant, virama, joiner) ends a word, and Mohan so typed
    could not claim the lease ("operator must be a name ..."). A joiner after a call sign's
    letter still joins nothing."""
    mohan = "\u0d2e\u0d4b\u0d39\u0d28\u0d4d\u200d"
    for name in (mohan, f"{mohan} VU2ABC"):
        assert Lease().claim(name, 30, T0).operator == name
    with pytest.raises(LeaseError, match="operator must be a name"):
        Lease().claim("DL1ABC\u200d", 30, T0)


def test_an_operators_name_is_its_compatibility_form_without_invisible_characters() -> None:
    """A review: a name typed with a no-break space (a Mac's Option-Space) and the same with a
    space were two operators, the lease refusing its own holder; a zero-width space made a
    look-alike of another's name; a direction override showed the console's line reversed, the
    lease's end with it. Persian's zero-width non-joiner stays a letter's."""
    assert valid_operator("DL1ABC\u00a0Jo") == "DL1ABC Jo"
    assert valid_operator("\uff24\uff2c\uff11ABC") == "DL1ABC"  # fullwidth letters
    for hidden in ("\u200b", "\u2060", "\ufeff", "\u202e", "\u2066", "\u2028", "\U000e0041"):
        assert valid_operator(f"DL1{hidden}ABC") is None, hex(ord(hidden))
    persian = "\u0645\u062d\u0645\u062f\u200c\u0631\u0636\u0627"
    assert valid_operator(persian) == persian
    lease = Lease()
    held = lease.claim("DL1ABC\u00a0Jo", 30, T0)
    assert lease.refusal(valid_operator("DL1ABC Jo"), T0) is None and held.operator == "DL1ABC Jo"


@pytest.mark.parametrize(
    "name", ["mqtt", "MQTT", "rotctld 127.0.0.1", "web 10.0.0.2", "pst", "rotctld\u00a0127.0.0.1"]
)
def test_an_interfaces_name_cannot_claim_the_lease(name: str) -> None:
    """Rule 1: 'mqtt' would make every nameless MQTT client, Home Assistant too, the holder."""
    lease = Lease()
    with pytest.raises(LeaseError, match="names an interface"):
        lease.claim(name, 30, 1_000.0)
    assert lease.holder(1_000.0) is None
    lease.claim("DL1ABC", 30, 1_000.0)  # a call sign is a name


def test_an_operators_call_is_one_whatever_its_case() -> None:
    """Rules 2 and 5: a call sign typed in capitals on the console and in small letters in a
    Node-RED flow is one operator (an attack pass: DL1ABC held the lease and dl1abc was
    refused, named as the holder), who renews it; another call is still refused."""
    lease = Lease()
    lease.claim("DL1ABC", 30, T0)
    assert lease.refusal("dl1abc", T0 + 60) is None
    assert lease.claim("dl1abc", 60, T0 + 60).until_unix == T0 + 60 + 3600
    assert lease.refusal("dl1abd", T0 + 120) is not None
