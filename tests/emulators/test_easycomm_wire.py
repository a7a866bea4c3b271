"""The Easycomm II/III controller emulator, sans-IO: what each command answers on the wire (only
questions are answered), the reply forms, the controller that answers AZ and EL only when asked
separately, III's status, errors and velocities, values it does not take, stops."""

from __future__ import annotations

from bridge import emulators
from bridge.emulators.easycomm import EasycommController, Outcome
from tests.emulators.conftest import ask


def test_the_reply_forms() -> None:
    device = EasycommController("easycomm2", start_az_deg=12.34, start_el_deg=34.56)
    assert ask(device, b"AZ EL\n", 0) == b"AZ12.3 EL34.6\n"
    assert ask(device, b"AZ\n", 0) == b"AZ12.3\n"
    assert ask(device, b"EL\r", 0) == b"EL34.6\n"
    assert ask(device, b"AZ\nEL\n", 0) == b"AZ12.3\nEL34.6\n"  # two lines, two answers
    whole = EasycommController("easycomm2", decimals=0, spacing=0, line_ending=b"\r\n")
    assert ask(whole, b"AZ EL\r\n", 0) == b"AZ0EL0\r\n"
    az_only = EasycommController("easycomm2-az", start_az_deg=200)
    assert ask(az_only, b"AZ EL\n", 0) == b"AZ200.0 EL0.0\n"


def test_a_separate_controller_answers_a_question_only_on_a_line_of_its_own() -> None:
    device = EasycommController("easycomm2-separate", start_az_deg=10, start_el_deg=20)
    assert ask(device, b"AZ EL\n", 0) == b""
    assert [f.outcome for f in device.log] == [Outcome.UNANSWERED] * 2
    assert ask(device, b"AZ\nEL\n", 0) == b"AZ10.0\nEL20.0\n"


def test_commands_are_not_answered_and_unknown_ones_ignored() -> None:
    device = EasycommController("easycomm2")
    for line in (b"AZ10.0 EL10.0\n", b"SA SE\n", b"ML\n", b"RESET\n", b"XX\n", b"UP000 XXX\n"):
        assert ask(device, line, 0) == b"", line
    outcomes = [f.outcome for f in device.log]
    assert outcomes == ["move", "move", "stop", "stop", "jog", "stop", "ignored", "ignored"] + [
        "ignored"
    ]


def test_values_it_does_not_take_move_nothing_and_the_rest_of_the_line_counts() -> None:
    device = EasycommController("easycomm2", start_az_deg=50)
    ask(device, b"AZ361.0 EL10.0\n", 0)
    state = device.state(0.0)
    assert (state.target_az_deg, state.target_el_deg) == (None, 10.0)
    ask(device, b"AZabc EL181\n", 0.0)
    assert [f.data for f in device.frames(Outcome.REFUSED)] == [b"AZ361.0", b"EL181"]
    assert [f.data for f in device.frames(Outcome.IGNORED)] == [b"AZABC"]


def test_a_move_runs_at_the_rotor_speed_and_each_stop_halts_its_axis() -> None:
    device = EasycommController("easycomm2", az_speed_deg_s=10.0, el_speed_deg_s=5.0)
    ask(device, b"AZ100.0 EL50.0\n", 0.0)
    state = device.state(5.0)
    assert (state.az_deg, state.el_deg, state.is_moving) == (50.0, 25.0, True)
    ask(device, b"SA\n", 5.0)  # azimuth only
    state = device.state(6.0)
    assert (state.az_deg, state.el_deg, state.is_moving) == (50.0, 30.0, True)
    ask(device, b"SA SE\n", 6.0)
    assert not device.state(9.0).is_moving and device.state(9.0).el_deg == 30.0


def test_easycomm3_status_errors_version_and_velocity() -> None:
    device = EasycommController("easycomm3", version="1.4", az_speed_deg_s=10.0)
    assert ask(device, b"VE\n", 0) == b"VE1.4\n"
    assert ask(device, b"GS\n", 0) == b"GS1\n"  # idle
    assert ask(device, b"GE\n", 0) == b"GE0\n"
    ask(device, b"VR2000\n", 0.0)  # 2 degrees a second to the right
    assert 9.0 < device.state(5.0).az_deg < 10.0  # (sent at 0.3: time went on with each answer)
    assert ask(device, b"GS\n", 5.0) == b"GS2\n"
    device.jam(5.0)
    assert ask(device, b"GS GE\n", 5.0) == b"GS10 GE2\n"  # moving, error; jam
    device.unjam(5.0)
    ask(device, b"SA\n", 5.0)
    start = device.state(6.0)
    device.receive(b"AZ30.0\n", 6.0)  # a bearing goes at the rotor's full speed again
    assert device.state(6.5).az_deg == start.az_deg + 5.0
    # Easycomm II has no registers and no velocities: ignored
    two = EasycommController("easycomm2")
    assert ask(two, b"GS\n", 0) == b"" and ask(two, b"VR2000\n", 0) == b""
    assert not two.state(1.0).is_moving


def test_park_and_power_cycle() -> None:
    device = EasycommController("easycomm2", start_az_deg=30, start_el_deg=10)
    ask(device, b"PARK\n", 0.0)
    assert (device.state(0.0).target_az_deg, device.state(0.0).target_el_deg) == (0.0, 0.0)
    device.receive(b"AZ", 1.0)  # half a line, then the power goes
    device.power_cycle(1.0)
    assert not device.state(1.0).is_moving
    assert ask(device, b"EL\n", 1.0) == b"EL4.0\n"  # not "AZEL": the half line was dropped


def test_every_model_is_in_the_registry() -> None:
    names = {n for n in emulators.EMULATORS if n.startswith("easycomm")}
    assert names == {f"easycomm{v}{s}" for v in (2, 3) for s in ("", "-az", "-separate")}


def test_satnogs_firmware_takes_a_bare_az_for_a_target_of_0() -> None:
    """Its easycomm.h (the emulator's rule 6): only a line beginning ``AZ EL`` asks."""
    device = EasycommController("easycomm2", firmware="satnogs", start_az_deg=200, start_el_deg=20)
    assert ask(device, b"AZ EL\n", 0) == b"AZ200.0 EL20.0\n"
    assert ask(device, b"AZ\n", 0) == b""  # no answer, and the rotor turns to 0
    assert device.state(0.1).target_az_deg == 0.0 and device.state(0.1).is_moving
    assert ask(device, b"SA SE\n", 0.2).startswith(b"AZ19")  # answered, and stopped
    assert not device.state(0.3).is_moving
    assert ask(device, b"AZ150.5 EL30\n", 1) == b""
    assert device.state(1.1).target_az_deg == 150.5
    assert ask(device, b"EL\n", 2) == ask(device, b"AZ1X\n", 2) == b""  # nothing, no move
    assert [f.outcome for f in device.log][-2:] == ["ignored", "refused"]


def test_k3ng_firmware_answers_each_word_with_its_value_and_its_ending_byte() -> None:
    device = EasycommController("easycomm2", firmware="k3ng", start_az_deg=200, start_el_deg=20)
    assert ask(device, b"AZ EL\n", 0) == b"+200.0 +20.0\n"
    assert ask(device, b"AZ\r\n", 0) == b"+200.0\r"  # the LF after the CR ends an empty word
    assert ask(device, b"AZ150.0 EL30.0\n", 0) == b" \n"  # targets: nothing but the endings
    assert device.state(0.1).target_az_deg == 150.0
    assert ask(device, b"SA SE\n", 1) == b" \n" and not device.state(1.1).is_moving
    assert ask(device, b"AZ999.0 AZ5 XX VE\n", 2) == b"? ? ? VE002\n"
    az_only = EasycommController("easycomm2-az", firmware="k3ng", start_az_deg=200)
    assert ask(az_only, b"AZ EL\n", 0) == b"+200.0 ?\n"
    assert ask(az_only, b"SA SE\n", 0) == b" ?\n"


def test_a_line_sent_on_its_own_goes_behind_the_reply_on_the_line() -> None:
    """twoaxes.py rule 6: an Easycomm III box's own ``VE`` line, sent while a reply is on its
    way at 9600 baud, comes whole after it; neither is cut into the other."""
    device = EasycommController("easycomm3", start_az_deg=12.34, start_el_deg=34.56)
    device.receive(b"AZ EL\n", 0.0)
    first = device.due_output(0.005)  # a few bytes of the reply out, the rest still coming
    assert 0 < len(first) < len(b"AZ12.3 EL34.6\n"), first
    device.transmit(b"VE7\n", 0.005)
    assert first + device.due_output(1.0) == b"AZ12.3 EL34.6\nVE7\n"
