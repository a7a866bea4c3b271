"""Device emulators: controller behaviour written from the documents, served on a pty.

What this is: a registry (python-can style) of controller emulators that tests, the demo and
`rotor-bridge emulate MODEL` start by name. Each entry builds a sans-IO responder (base.Responder);
`start()` puts it on a pseudo-terminal (pty.EmulatedPort).

Rules:
1. Nothing here imports bridge.protocols, bridge.engine or paho: an emulator written from our own
   codec would share its misreadings, and every test would pass with both wrong.
2. EMULATORS maps a model name to a factory taking keyword options and `now`; a new family
   (SPID, SatEL, GS-232, Easycomm, RT-21, RC2800, Prosistel) adds entries here and reuses
   physics.Axis, base.PacedLine and pty.EmulatedPort.
3. ``as_built(model)``: the options that make a model's emulator turn as the real device's rotor
   does where its default does not (a Hy-Gain rotor's stop at south, rotorez.py rule 12; a
   SatEL's ten-degree steps, satel.py rule 10); the demo and `rotor-bridge emulate` start
   every emulator with them.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping
from functools import partial
from typing import Any

from bridge.emulators.base import LoggedFrame, Responder, RotatorState
from bridge.emulators.easycomm import MODELS as _EASYCOMM_MODELS
from bridge.emulators.easycomm import EasycommController
from bridge.emulators.gs232 import MODELS as _GS232_MODELS
from bridge.emulators.gs232 import Gs232
from bridge.emulators.prosistel import MODELS as _PROSISTEL_MODELS
from bridge.emulators.prosistel import Prosistel
from bridge.emulators.pty import EmulatedPort
from bridge.emulators.rc2800 import MODELS as _RC2800_MODELS
from bridge.emulators.rc2800 import Rc2800
from bridge.emulators.rotorez import RotorEZ
from bridge.emulators.rotorez_models import MODELS as _ROTOREZ_MODELS
from bridge.emulators.rt21 import Rt21
from bridge.emulators.satel import SatEL
from bridge.emulators.spid import Spid

#: model name -> factory(**options, now=...) returning a responder.
EMULATORS: Mapping[str, Callable[..., Responder]] = {
    "rotorez": partial(RotorEZ, "rotorez"),
    "rotorcard": partial(RotorEZ, "rotorcard"),
    "dcu1": partial(RotorEZ, "dcu1"),
    "rot2prog": partial(Spid, "rot2prog"),
    "rot1prog": partial(Spid, "rot1prog"),
    "md01": partial(Spid, "md01"),
    "satel": SatEL,
    **{name: partial(Gs232, name) for name in _GS232_MODELS},
    **{name: partial(EasycommController, name) for name in _EASYCOMM_MODELS},
    "rt21": Rt21,
    **{name: partial(Rc2800, name) for name in _RC2800_MODELS},
    **{name: partial(Prosistel, name) for name in _PROSISTEL_MODELS},
}


def as_built(model: str) -> dict[str, Any]:
    """Rule 3: the options that make ``model``'s emulator turn as its real rotor does."""
    if model == "satel":
        return {"step_deg": 10}
    spec = _ROTOREZ_MODELS.get(model)
    return {"stop_at_south": spec.stop_at_south} if spec is not None else {}


def create(model: str, *, now: float = 0.0, **options: Any) -> Responder:
    """Build the sans-IO responder for `model` (no pty)."""
    try:
        factory = EMULATORS[model]
    except KeyError:
        known = ", ".join(sorted(EMULATORS))
        raise ValueError(f"unknown emulator model {model!r}; known: {known}") from None
    return factory(now=now, **options)


def start(
    model: str,
    *,
    link: str | os.PathLike[str] | None = None,
    clock: Callable[[], float] = time.monotonic,
    hold_output_until_open: bool = True,
    on_frame: Callable[[LoggedFrame], None] | None = None,
    **options: Any,
) -> EmulatedPort[Any]:
    """Start `model` on a fresh pty (and at `link`); options go to the controller."""
    device = create(model, now=clock(), **options)
    return EmulatedPort(
        device,
        link=link,
        clock=clock,
        hold_output_until_open=hold_output_until_open,
        on_frame=on_frame,
        name=model,
    )


__all__ = [
    "EMULATORS",
    "as_built",
    "EasycommController",
    "EmulatedPort",
    "Gs232",
    "LoggedFrame",
    "Prosistel",
    "Rc2800",
    "Responder",
    "RotatorState",
    "Rt21",
    "RotorEZ",
    "SatEL",
    "Spid",
    "create",
    "start",
]
