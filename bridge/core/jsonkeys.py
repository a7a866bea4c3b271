"""A command's JSON with a key given twice, with two values, is refused, not read as its last
value: json's own reading keeps the last, so ``{"azimuth": 10, "azimuth": 350}`` turned the
rotor to 350, while the first value was as much what the sender wrote (the command parsers: the
MQTT payloads, the lease's claim, the console's commands). The same value twice says one thing
and is taken. (Not where only a stop or a lock word is read, the console's live socket: a stop
is never refused.)"""

from __future__ import annotations

KEY_SHOWN = 40  # of a key given twice, in the refusal: no payload floods a log line


class DuplicateKey(ValueError):
    """A key given twice in one JSON object."""


def unique_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """``json.loads``' ``object_pairs_hook``: each object's keys, each with one value
    (DuplicateKey). (``==`` on JSON values: ``1`` and ``1.0`` are one number, as the parsers
    read them; ``true`` and ``1`` too, and the parsers refuse a bool where a number goes.)"""
    doc: dict[str, object] = {}
    for key, value in pairs:
        if key in doc and doc[key] != value:
            raise DuplicateKey(f"key {key[:KEY_SHOWN]!r} given twice, with two values")
        doc[key] = value
    return doc
