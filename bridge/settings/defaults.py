"""The engine values a rotator gets for the keys its configuration leaves out.

The schema (settings/rotator.py) holds what the user wrote, ``None`` where a key is left out;
this module says what the engine uses then. check-config shows these values and
docs/configuration.md's model table is generated from them.

Rules:
1. Every default here is derived from the model spec and the line rate alone (and, for the
   silence timeout, the idle poll interval actually in use): no file, clock or port is read.
2. A value the user gave always wins; these functions are only asked about what is left out.
3. The silence timeout rides out one lost reply: it is never shorter than two idle polls and a
   reply time, and never shorter than DEFAULT_SILENCE_TIMEOUT_S.
"""

from __future__ import annotations

import math

from bridge.protocols.base import ModelSpec

DEFAULT_SILENCE_TIMEOUT_S = 3.0  # no valid reply this long: offline (unless polls are rarer)


def idle_poll_interval_s(spec: ModelSpec, baud: int | None) -> float:
    """The model's idle poll interval at ``baud`` (None: its default rate): idle polls take at
    most 5 % of the line (1.0 s on fast lines; Rot2Prog at 600 baud 9.3 s)."""
    return spec.default_idle_poll_interval_s(baud)


def silence_timeout_s(spec: ModelSpec, idle_poll_s: float) -> float:
    """DEFAULT_SILENCE_TIMEOUT_S, or two idle polls plus a reply time where polls are rarer than
    that allows (rule 3), rounded up to a tenth of a second."""
    two_polls = 2 * idle_poll_s + spec.reply_timeout_s
    return max(DEFAULT_SILENCE_TIMEOUT_S, math.ceil(two_polls * 10 - 1e-9) / 10)


def model_defaults(spec: ModelSpec) -> dict[str, float | int | str | None]:
    """Every key whose default is the model's, as a rotator of ``spec`` left at its defaults
    uses it (None: the model has no such axis)."""
    idle_s = idle_poll_interval_s(spec, None)
    az_speed, el_speed = spec.speeds_deg_s()
    el = spec.has_elevation
    return {
        "baud": spec.baud,
        "brake_delay_s": spec.brake_delay_s,
        "idle_poll_interval_s": idle_s,
        "silence_timeout_s": silence_timeout_s(spec, idle_s),
        "noise_deg": spec.noise_deg,
        "az_speed_deg_s": az_speed,
        "el_speed_deg_s": el_speed if el else None,
        "az_min_deg": spec.az_min_deg,
        "az_max_deg": spec.az_max_deg,
        "el_min_deg": spec.el_min_deg if el else None,
        "el_max_deg": spec.el_max_deg if el else None,
        "unasked_moves": spec.unasked_moves,
    }
