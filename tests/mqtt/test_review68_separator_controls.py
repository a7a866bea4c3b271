"""Review 68: docs/mqtt.md (a78850c1) says every topic drops blanks at the ends, a BOM at the
start and NULs at the end, and "any other control character ... is refused, naming it". But
``_words`` lets through every character Python calls a space, and U+001C..U+001F (the ASCII
information separators) and U+0085 (NEL) are control characters Python calls spaces: inside a
target they part its two fields, and the rotor turns where the docs say the payload is
refused."""

from __future__ import annotations

import pytest

from bridge.core.model import Target
from tests.mqtt.test_service import service


@pytest.mark.parametrize("control", ["\x1c", "\x1d", "\x1e", "\x1f", "\x85"])
def test_a_control_character_inside_a_target_is_refused_naming_it(control: str) -> None:
    svc, _, rots = service({"tower": "gs232b"})
    rot = rots["tower"]
    svc.on_message("rotor/target", f"120{control}30".encode(), False)
    moved = [c for c in rot.calls if c[0] == "submit" and isinstance(c[1], Target)]
    refused = [c[1] for c in rot.calls if c[0] == "refused"]
    assert moved == [], "the rotor was sent a target"
    assert len(refused) == 1 and f"U+{ord(control):04X}" in refused[0]
