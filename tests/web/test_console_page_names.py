"""A script's page name across its runs (commands.py rule 5, ``Order.carried`` and ``scoped``):
a cold review found that a console script restarted under the same page name numbered from 1
again, and its STOP was answered ok and not carried out (taken for a copy of its last run's
halt), while its targets were refused as numbered before that halt. Real mosquitto, the
Rotor-EZ emulator on a pty, the console over HTTP."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.support.console import ConsoleClient, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow


@pytest.fixture
def console(rig: Rig) -> Iterator[tuple[Rig, ConsoleClient]]:
    web = rig.sections["web"] = web_section()
    rig.add("hf", emu={"start_az_deg": 10.0})
    rig.start()
    rig.ready("hf")
    client = ConsoleClient(web["port"])
    client.session()
    yield rig, client


def test_a_fresh_login_under_the_same_page_name_is_a_fresh_page(
    console: tuple[Rig, ConsoleClient],
) -> None:
    rig, client = console
    assert client.command("hf", command="stop", page="logger", seq=7).status == 200
    again = ConsoleClient(client.port)
    again.session()  # the script restarted: a fresh login
    answer = again.command("hf", command="target", az=120, page="logger", seq=1)
    assert answer.status == 200, answer
    rig.arrived("hf", 120)


def test_a_page_name_guessed_from_another_session_does_not_eat_the_pages_stop(
    console: tuple[Rig, ConsoleClient],
) -> None:
    """An attack pass: a console page name is chosen by the client, and another session that
    sent a halt under it, numbered high, made the page's later STOPs count as carried out."""
    rig, client = console
    emu = rig.emus["hf"]
    other = ConsoleClient(client.port)
    other.session()
    assert other.command("hf", command="stop", page="logger", seq=1000).status == 200
    assert client.command("hf", command="target", az=300, page="logger", seq=1).status == 200
    emu.wait_for(lambda s: s.is_moving, slow(10))
    assert client.command("hf", command="stop", page="logger", seq=2).status == 200
    emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert emu.state().az_deg < 290, "the STOP was answered ok and not carried out"
