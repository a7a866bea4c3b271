"""A command's JSON with a key given twice is refused, not read as its last value: json's own
reading keeps the last, so ``{"azimuth": 10, "azimuth": 350}`` turned the rotor to 350, while
the first value was as much what the sender wrote (every command parser: the MQTT payloads, the
lease's claim, the console's commands)."""

from __future__ import annotations

KEY_SHOWN = 40  # of a key given twice, in the refusal: no payload floods a log line


class DuplicateKey(ValueError):
    """A key given twice in one JSON object."""


def unique_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """``json.loads``' ``object_pairs_hook``: each object's keys, each once (DuplicateKey)."""
    doc: dict[str, object] = {}
    for key, value in pairs:
        if key in doc:
            raise DuplicateKey(f"key {key[:KEY_SHOWN]!r} given twice")
        doc[key] = value
    return doc
