"""Review 49: wsjtx/server.py rule 5 (dfb087e4) keeps budget room for the senders of the first
STATUS_INSTANCES (two) instances heard since the bridge started, for as long as it runs. The
programs following listens to are another set (follow.py rule 8: the first heard since
following was switched on, or the first on the antenna's bands): a bridge up for weeks heard
JTDX one evening and WSJT-X under a rig name (``WSJT-X - IC7300``, ``-r``) the next, and both
keep the room; the WSJT-X running today (Id ``WSJT-X``, another rig's configuration) has none,
and a flood of statuses of another name from local sockets (the attack 11 pass dfb087e4
answers) spends the cap for all and drops its statuses undecoded again: the transmission's
hold and the next partner missed. Before WSJT-X starts, two forged names take the room the same
way for good. The room is now the programs heard most recently (server.py rules 5, 6). Real
UDP sockets, virtual time, as tests/wsjtx/test_attack11_status_flood.py."""

from __future__ import annotations

import socket
from collections.abc import Callable

import pytest

from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.waiting import slow
from tests.wsjtx.test_attack11_status_flood import (
    Ears,
    _read,
    flood_of_another_name,
    listening,
    transmits_through,
)


@pytest.mark.parametrize(
    "before", [("JTDX", "WSJT-X - IC7300"), ("forged-1", "forged-2")], ids=["earlier", "forged"]
)
def test_wsjtx_is_heard_through_a_flood_after_two_other_programs_were_heard_first(
    before: tuple[str, str],
) -> None:
    with listening(Ears()) as (listener, ears, clock, stack):
        sent = 0
        for instance in before:  # heard once, their sockets gone
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as other:
                other.sendto(
                    w.status(w.StatusFields(dx_call="W1AW", instance=instance)),
                    listener.address,
                )
            sent += 1
            wait_until(lambda n=sent: _read(listener) >= n, slow(10), "heard")
        clock.t += 3600.0  # hours later (every budget full again)
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        sent += 1
        wait_until(lambda n=sent: _read(listener) >= n, slow(10), "WSJT-X heard")
        sent = flood_of_another_name(stack, listener, sent)
        transmits_through(wsjtx, listener, sent)
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", "JA1ABC", "VK2XYZ"], f"WSJT-X's statuses handed on: {ours}"


@pytest.mark.parametrize(
    "name",
    [lambda n: ("forged-1", "forged-2")[n % 2], lambda n: f"forged-{n}"],
    ids=["two-names-in-turn", "a-new-name-each"],
)
def test_wsjtx_keeps_its_room_through_a_flood_of_names_heard_after_it(
    name: Callable[[int], str],
) -> None:
    """The room is the programs heard last (server.py rules 5, 6), not any names heard last: a
    flood of statuses of two names in turn (each flooded far past a program's pace), or of a
    new name in every datagram (from senders flooding past their own budget), takes none of
    it, and WSJT-X, heard before the flood, is heard through it."""
    with listening(Ears()) as (listener, ears, clock, stack):
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        wait_until(lambda: _read(listener) >= 1, slow(10), "WSJT-X heard")
        sent = flood_of_another_name(stack, listener, 1, name)
        transmits_through(wsjtx, listener, sent)
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", "JA1ABC", "VK2XYZ"], f"WSJT-X's statuses handed on: {ours}"
        assert {h.instance for h in ears.got} - {"WSJT-X"}  # (the flood was heard, in part)


def test_wsjtx_followed_keeps_its_room_after_two_names_heard_at_a_programs_pace() -> None:
    """The room is the program the follow part listens to (server.py rule 5), whatever was
    heard after it: two names sent at a program's pace from sockets of their own after WSJT-X's
    status are the programs heard last and take the room for programs followed by none; a
    rotator following WSJT-X keeps its statuses' room, and they are heard through the flood."""
    with listening(Ears(followed="WSJT-X")) as (listener, ears, clock, stack):
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        sent = 1
        wait_until(lambda: _read(listener) >= 1, slow(10), "WSJT-X heard")
        for instance in ("paced-1", "paced-2"):
            paced = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            for _ in range(3):
                fields = w.StatusFields(dx_call="W1AW", instance=instance)
                paced.sendto(w.status(fields), listener.address)
                sent += 1
                wait_until(lambda n=sent: _read(listener) >= n, slow(10), "heard")
                clock.t += 1.0  # a program's pace
        sent = flood_of_another_name(stack, listener, sent)
        transmits_through(wsjtx, listener, sent)
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", "JA1ABC", "VK2XYZ"], f"WSJT-X's statuses handed on: {ours}"
