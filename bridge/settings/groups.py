"""The ``[[groups]]`` tables: rotators turned together from one topic (stacked antennas), each
member with its offset and, if it needs them, narrower limits (interfaces/mqtt/groups.py fans a
group's command out; each member's own judge has the last word).

Rules:
1. A group names rotators by their ``id`` (``rotators = ["upper", "lower"]``), at least two,
   none twice; a rotator may be in several groups (the stack, and every antenna of the tower).
2. ``offsets`` and ``limits`` are tables keyed by a member's id; a key that names no member is
   an error, not ignored (a typo must not leave an antenna pointing the wrong way).
3. An offset is added to the group's bearing for that member (0 to 360 exclusive, as a
   compass reads: ``lower = 180`` points the lower antenna the other way). A member's limits
   are true bearings (after its offset) within 0..360, the lower first; they only narrow what
   the member's own judge accepts.
4. The cross-checks against the rotators (an unknown id, a box made for an elevation rotor
   alone, whose bearing is an elevation, an id that clashes with a rotator's topic or a word
   of the bridge's own topics) are settings/'s, which sees both. The words are
   the core's (``CORE_WORDS``, written here) and each registered feature's first topic words,
   from its declaration (``reserved``): a new feature needs no line here.
5. A rotator's topic is held to the same (settings/ ``_rotator_topics``): one that lies under
   another rotator's takes no word of ``reserved`` as its next level, and one under the base
   topic none of ``station_words`` (a rotator at rotor/bridge published its state on the
   bridge's own rotor/bridge/state, every Home Assistant entity's availability).
6. Every key carries its meaning (``description``) for docs/configuration.md.
"""

from __future__ import annotations

import re

from pydantic import Field, field_validator, model_validator

from bridge.feature import registered, topic_words
from bridge.settings.base import Strict, check_name

_ID = re.compile(r"^[a-z0-9_-]{1,32}$")

# rule 4: the first level of every core topic under a rotator's root and of the bridge's own
# under the base topic (interfaces/mqtt/topics.py; tests/mqtt/test_groups.py keeps the two in
# step): a group named so, under a rotator whose root is the base topic, would take over that
# rotator's topic. The features' words are their declarations' (``reserved``).
CORE_WORDS = frozenset(
    (
        "target stop lock preset park nudge option bearing elevation state status version "
        "availability error presets info audit bridge"
    ).split()
)


def reserved() -> frozenset[str]:
    """Rule 4: every word a group id may not take, the core's and each registered feature's
    (bridge/feature.py rule 3), the registry found by name at the first group checked."""
    return CORE_WORDS | frozenset(topic_words())


def station_words() -> frozenset[str]:
    """Rule 5: the first levels of the bridge's own topics under the base topic (its
    ``bridge/...`` and each station feature's, bridge/feature.py ``base_topics``)."""
    return frozenset(("bridge", *(s.split("/")[0] for f in registered() for s in f.base_topics)))


class GroupSettings(Strict):
    """One ``[[groups]]`` table."""

    id: str = Field(
        description="the group's id: its topics are <base_topic>/<id>/target and /stop; "
        "lower-case letters, digits, - and _ (at most 32), not a rotator's id",
        examples=["stack"],
    )
    name: str | None = Field(
        None,
        description="what dashboards and Home Assistant call the group (at most 64 "
        "characters, no control character, no blank at either end)",
        examples=["Stacked 20 m yagis"],
        json_schema_extra={"unset": "the id"},
    )
    rotators: list[str] = Field(
        description="the ids of the rotators turned together, at least two",
        examples=[["upper", "lower"]],
    )
    offsets: dict[str, float] = Field(
        default_factory=dict,
        description="degrees added to the group's azimuth for a member, by its id "
        "(0 to 360): a member left out turns to the group's bearing",
        examples=[{"lower": 180}],
        json_schema_extra={"unset": "every member at the group's bearing"},
    )
    limits: dict[str, tuple[float, float]] = Field(
        default_factory=dict,
        description="a member's narrower azimuth limits in this group, true bearings after "
        "its offset, [lowest, highest]: a group target outside them is refused for that "
        "member, and its turn stays inside them (the side that does, or none)",
        examples=[{"upper": [20, 340]}],
        json_schema_extra={"unset": "each member's own limits only"},
    )

    @field_validator("name")
    @classmethod
    def _name(cls, v: str | None) -> str | None:
        return check_name(v)  # settings/base.py rule 5

    @field_validator("id")
    @classmethod
    def _id(cls, v: str) -> str:
        if not _ID.fullmatch(v):  # not match: its $ passes a final newline
            raise ValueError(
                "must be 1 to 32 lower-case letters, digits, - or _ (it is a topic level, and "
                "Home Assistant's entity ids, made from it, are lower case), as a rotator's id"
            )
        return v

    @field_validator("offsets")
    @classmethod
    def _offsets(cls, v: dict[str, float]) -> dict[str, float]:
        for rid, offset in v.items():
            if not 0 <= offset < 360:
                raise ValueError(f"{rid} = {offset:g}: an offset is 0 to 360 (exclusive)")
        return v

    @field_validator("limits")
    @classmethod
    def _limits(cls, v: dict[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
        for rid, (lo, hi) in v.items():
            if not 0 <= lo < hi <= 360:
                raise ValueError(
                    f"{rid} = [{lo:g}, {hi:g}]: limits are true bearings 0..360, the lower first"
                )
        return v

    @model_validator(mode="after")
    def _members(self) -> GroupSettings:
        if len(self.rotators) < 2:
            raise ValueError(f"group {self.id!r}: rotators must name at least two rotators")
        twice = sorted({r for r in self.rotators if self.rotators.count(r) > 1})
        if twice:
            raise ValueError(f"group {self.id!r}: rotator {twice[0]!r} is named twice")
        for key in ("offsets", "limits"):
            stray = sorted(set(getattr(self, key)) - set(self.rotators))
            if stray:
                raise ValueError(
                    f"group {self.id!r}: {key}.{stray[0]} names no member of the group "
                    f"(its rotators are {', '.join(self.rotators)})"
                )
        return self

    @property
    def label(self) -> str:
        return self.name or self.id
