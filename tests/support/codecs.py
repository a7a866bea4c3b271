"""Feeding a sans-IO parser (a codec, the rotctld request parser) the three ways the house rules
ask for: the whole buffer at once, one byte at a time, and split in two in the middle."""

from __future__ import annotations

from typing import Any, Protocol


class Feedable(Protocol):
    def feed(self, data: bytes) -> Any: ...  # an iterable of what was read


HOW = ("whole", "bytewise", "split")
STOPS = ("none", "behind the poll", "before the poll")  # given_up's orderings


class Polled(Protocol):
    def encode_query(self) -> Any: ...
    def encode_stop(self) -> Any: ...
    def expire_query(self) -> None: ...


def given_up(codec: Polled, stop: str) -> None:
    """A poll given up after its reply time (a STOP before it or behind it, or none: one of
    STOPS), then the next poll open: protocols/base.py rule 7's orderings."""
    if stop == "before the poll":
        codec.encode_stop()
    codec.encode_query()
    if stop == "behind the poll":
        codec.encode_stop()
    codec.expire_query()
    codec.encode_query()


def feed(parser: Feedable, data: bytes, how: str = "whole") -> list[Any]:
    """Everything ``parser`` reads from ``data`` fed ``how`` (one of HOW)."""
    if how == "whole":
        return list(parser.feed(data))
    if how == "bytewise":
        return [r for i in range(len(data)) for r in parser.feed(data[i : i + 1])]
    if how == "split":
        mid = len(data) // 2
        return [*parser.feed(data[:mid]), *parser.feed(data[mid:])]
    raise ValueError(f"feed how? {how!r}: one of {HOW}")
