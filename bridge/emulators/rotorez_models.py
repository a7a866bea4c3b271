"""What each member of the Rotor-EZ family understands, as data (see rotorez.py for behaviour).

What the devices are: Idiom Press Rotor-EZ (Hy-Gain rotors, brake, option letters), Idiom Press
RotorCard (Yaesu rotors, no brake, calibration letters), Hy-Gain DCU-1 (AP1xxx; AM1; AS1; only,
never transmits).

Frame: see rotorez.py. This module only names the commands each model accepts.

Source documents: Idiom Press "Rotor-EZ Rotator Control Protocol" (command table: which letters
exist on which board; brake FAQ), Idiom Press's 2003 command reference letter to Hamlib (DCU-1
subset), Hamlib 4.5.4's rotorez backend (it stops a DCU-1 with AS1;).

Rules:
1. A model is a ModelSpec: flags only, no code. A command a model lacks is an invalid command.
2. Outcome strings are part of the emulator's public ground truth: tests of the bridge match on
   them, so they change only together with those tests.
3. Jumper defaults are not documented; the values here are a stated assumption.
4. Where the rotor's travel ends (``stop_at_south``): a Hy-Gain rotor (Rotor-EZ, DCU-1) has its
   mechanical stop at south, so north is the middle of its travel and 350 -> 010 turns 20
   degrees across north; a Yaesu rotor (RotorCard) stops at north, so the same turn goes 340
   degrees round through south. The emulator turns so when asked to (rotorez.py rule 12).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum

POWER_ON_JUNK = b"\xe0"
MAX_FRAME_BODY_BYTES = 6  # "AP1xxx" is the longest body; the terminator makes seven bytes
OPTION_LETTERS: Mapping[int, tuple[str, bool]] = {
    ord("E"): ("endpoint", True),
    ord("e"): ("endpoint", False),
    ord("J"): ("jam", True),
    ord("j"): ("jam", False),
    ord("O"): ("overshoot", True),
    ord("o"): ("overshoot", False),
    ord("S"): ("unstick", True),
    ord("s"): ("unstick", False),
}
#: Jumper positions at power-on. Undocumented; jam protection on because Idiom calls turning it
#: off "NOT recommended", the rest off.
DEFAULT_JUMPERS: Mapping[str, bool] = {
    "endpoint": False,
    "jam": True,
    "overshoot": False,
    "unstick": False,
}


class Outcome(StrEnum):
    """What the controller did with a frame (the `outcome` of a LoggedFrame)."""

    EXECUTED = "executed"
    STORED = "stored"
    QUERY = "query"
    STOP = "stop"
    OPTION = "option"
    CALIBRATION = "calibration"
    VERSION = "version"
    IGNORED_BRAKE_DELAY = "ignored: brake delay"
    IGNORED_RETARGET = "ignored: re-target while turning (stopped)"
    IGNORED_NO_TARGET = "ignored: no stored target"
    INVALID = "invalid"


#: Outcomes of frames that carried or triggered a bearing (rule 5).
BEARING_OUTCOMES: frozenset[str] = frozenset(
    {
        Outcome.EXECUTED,
        Outcome.STORED,
        Outcome.IGNORED_BRAKE_DELAY,
        Outcome.IGNORED_RETARGET,
        Outcome.IGNORED_NO_TARGET,
    }
)


@dataclass(frozen=True)
class ModelSpec:
    """What one member of the family understands."""

    name: str
    title: str
    transmits: bool
    has_query: bool
    executes_on_cr: bool
    semicolon_stops: bool
    as1_stops: bool
    has_options: bool
    has_calibration: bool
    has_version: bool
    brake_delay_s: float
    stop_at_south: bool  # the rotor's travel ends at south (rule 4): a Hy-Gain's; else at north


MODELS: Mapping[str, ModelSpec] = {
    "rotorez": ModelSpec(
        name="rotorez",
        title="Idiom Press Rotor-EZ (Hy-Gain rotors)",
        transmits=True,
        has_query=True,
        executes_on_cr=True,
        semicolon_stops=True,
        as1_stops=False,
        has_options=True,
        has_calibration=False,
        has_version=True,
        brake_delay_s=5.0,
        stop_at_south=True,
    ),
    "rotorcard": ModelSpec(
        name="rotorcard",
        title="Idiom Press RotorCard (Yaesu rotors)",
        transmits=True,
        has_query=True,
        executes_on_cr=True,
        semicolon_stops=True,
        as1_stops=False,
        has_options=False,
        has_calibration=True,
        has_version=True,
        brake_delay_s=0.0,
        stop_at_south=False,  # a Yaesu rotor's stop is at north
    ),
    "dcu1": ModelSpec(
        name="dcu1",
        title="Hy-Gain DCU-1 / DCU-1X",
        transmits=False,
        has_query=False,
        executes_on_cr=False,
        semicolon_stops=False,
        as1_stops=True,
        has_options=False,
        has_calibration=False,
        has_version=False,
        brake_delay_s=5.0,
        stop_at_south=True,
    ),
}
