"""The user documentation cannot drift from the code: every link resolves, docs/mqtt.md names
every topic bridge/interfaces/mqtt/topics.py builds and every error kind the bridge publishes, and
the README stays short enough to read."""

from __future__ import annotations

import inspect
import os
import re
from pathlib import Path

import pytest

from bridge.core.geo import parse_locator
from bridge.core.model import ErrorKind
from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
MQTT_DOC = ROOT / "docs" / "mqtt.md"
DOCS = [README, *sorted((ROOT / "docs").glob("*.md"))]
README_MAX_BYTES = 12 * 1024

_FENCE = re.compile(r"^(```|~~~).*?^\1[ \t]*$", re.M | re.S)
_INLINE_CODE = re.compile(r"`[^`\n]*`")
_LINK = re.compile(r"!?\[(?:[^\]\n]|\][^(])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def _prose(text: str) -> str:
    """The text outside code blocks and inline code: a link written as code is not a link."""
    return _INLINE_CODE.sub("", _FENCE.sub("", text))


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: the text of links and code kept, lower case, punctuation
    dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading).replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return text.replace(" ", "-")


def anchors(doc: Path) -> set[str]:
    seen: dict[str, int] = {}
    found = set()
    for match in re.finditer(r"^#{1,6}[ \t]+(.+?)[ \t#]*$", _FENCE.sub("", doc.read_text()), re.M):
        slug = _slug(match.group(1))
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        found.add(slug if n == 0 else f"{slug}-{n}")
    return found


def links(doc: Path) -> list[str]:
    return [t for t in _LINK.findall(_prose(doc.read_text())) if not re.match(r"[a-z]+:", t)]


@pytest.mark.parametrize("doc", DOCS, ids=lambda d: d.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves_to_a_file_and_its_heading(doc: Path) -> None:
    broken = []
    for target in links(doc):
        path_part, _, anchor = target.partition("#")
        path = (doc.parent / path_part).resolve() if path_part else doc
        if not path.is_file() or not path.is_relative_to(ROOT):
            broken.append(f"{target}: no file {path_part}")
        elif anchor and (path.suffix != ".md" or anchor not in anchors(path)):
            broken.append(f"{target}: no heading #{anchor} in {path.relative_to(ROOT)}")
    assert not broken, f"{doc.relative_to(ROOT)}: " + "; ".join(broken)


def test_the_readme_links_every_page_in_docs() -> None:
    linked = {(README.parent / t.partition("#")[0]).resolve() for t in links(README)}
    pages = {p.resolve() for p in DOCS[1:]}
    missing = sorted(p.name for p in pages - linked)
    assert not missing, f"README.md has no link to docs/{', docs/'.join(missing)}"


def test_the_readme_stays_short() -> None:
    size = len(README.read_bytes())
    assert size <= README_MAX_BYTES, (
        f"README.md is {size} bytes, over {README_MAX_BYTES}: move the detail into docs/"
    )


def test_the_readme_starts_with_the_two_commands_and_both_run() -> None:
    """The demo and the test suite, as a newcomer types them from the top of a clone."""
    text = README.read_text()
    start = text.index("## Try it")
    (block,) = re.findall(r"```sh\n(.*?)```", text[start : text.index("\n## ", start + 1)], re.S)
    commands = [line.split("#")[0].strip() for line in block.splitlines()]
    assert commands == ["./demo", "./tests/run"]
    for command in commands:
        path = ROOT / command
        assert path.is_file() and os.access(path, os.X_OK), command


@pytest.mark.parametrize("doc", DOCS, ids=lambda d: d.relative_to(ROOT).as_posix())
def test_user_docs_carry_no_issue_numbers_or_dates(doc: Path) -> None:
    text = doc.read_text()
    months = "January|February|March|April|May|June|July|August|September|October|November|December"
    found = re.findall(r"\bissues? #?\d+", text, re.I) + re.findall(
        rf"\b\d{{1,2}} (?:{months}) \d{{4}}\b", text
    )
    assert not found, f"{doc.relative_to(ROOT)}: {found}"


# ---------------------------------------------------------------------------------------------
# docs/mqtt.md against the code
# ---------------------------------------------------------------------------------------------
def built_topics() -> set[str]:
    """Every topic the topics module builds, for base topic ``B``, one rotator at ``R``, one
    group at ``G`` and the discovery prefix ``homeassistant``; a method's arguments stand as
    ``<name>`` placeholders. Wildcard filters are left out (they are made of these topics)."""
    topics = Topics("B", {"r": "R"}, {"g": "G"})
    found: set[str] = set()
    groups = topics.group("g")
    for obj in (topics, topics.rotator("r"), groups, DiscoveryTopics("homeassistant")):
        for name, attr in inspect.getmembers(type(obj)):
            if name.startswith("_"):
                continue
            if isinstance(attr, property):
                value = getattr(obj, name)
            elif name == "feature":  # a registered feature's topics (bridge/feature.py)
                value = [
                    getattr(obj, name)(x.suffix)
                    for f in topics.features
                    for x in (*f.commands, *f.states)
                ]
            elif name == "under_base":  # a registered feature's under the base topic
                value = [obj.under_base(x) for f in topics.features for x in f.base_topics]
            elif inspect.isfunction(attr):
                params = list(inspect.signature(attr).parameters)[1:]
                try:
                    value = getattr(obj, name)(*(f"<{p}>" for p in params))
                except (KeyError, ValueError, TypeError):
                    continue  # not a builder (a look-up by id)
            else:
                continue
            values = value if isinstance(value, list) else [value]
            found |= {v for v in values if isinstance(v, str)}
    return {t for t in found if "+" not in t and "#" not in t and not t.endswith("/")}


def documented_topics() -> set[str]:
    """The topics in the first column of docs/mqtt.md's tables."""
    found = set()
    for line in _FENCE.sub("", MQTT_DOC.read_text()).splitlines():
        if line.startswith("|") and not line.startswith("|---"):
            first = line.split("|")[1]
            found |= set(re.findall(r"`([^`\s]+/[^`\s]*)`", first))
    return found


def test_built_topics_are_found_at_all() -> None:
    topics = built_topics()
    assert {"R/target", "R/stop", "R/status", "B/bridge/state"} <= topics, topics
    assert "R/option/<name>/state" in topics


def test_mqtt_doc_lists_every_topic_the_bridge_builds() -> None:
    missing = sorted(built_topics() - documented_topics())
    assert not missing, f"docs/mqtt.md has no table row for: {', '.join(missing)}"


def test_mqtt_doc_lists_no_topic_the_bridge_does_not_build() -> None:
    built = built_topics() | {"homeassistant/status"}  # homeassistant.status_topic's default
    extra = sorted(t for t in documented_topics() if t not in built)
    assert not extra, f"docs/mqtt.md lists topics the bridge does not build: {', '.join(extra)}"


def test_mqtt_doc_lists_every_error_kind_and_no_other() -> None:
    text = _FENCE.sub("", MQTT_DOC.read_text())
    start = text.index("### Error kinds")
    end = text.find("\n#", start + 1)
    section = text[start : end if end != -1 else len(text)]
    documented = set(re.findall(r"^\| `([a-z_]+)` \|", section, re.M))
    kinds = {kind.value for kind in ErrorKind}
    missing, extra = sorted(kinds - documented), sorted(documented - kinds)
    assert not missing, f"docs/mqtt.md 'Error kinds' lacks: {', '.join(missing)}"
    assert not extra, f"docs/mqtt.md 'Error kinds' lists kinds the bridge has not: {extra}"


# ---------------------------------------------------------------------------------------------
# The checker itself
# ---------------------------------------------------------------------------------------------
def test_slugs_are_githubs() -> None:
    assert _slug("The bridge's own topics") == "the-bridges-own-topics"
    assert _slug("`R/status`") == "rstatus"
    assert _slug("A stable device name (udev)") == "a-stable-device-name-udev"
    assert _slug("Pointing: offset, presets, park") == "pointing-offset-presets-park"


def test_links_in_code_are_not_links(tmp_path: Path) -> None:
    doc = tmp_path / "d.md"
    doc.write_text(
        "# T\n[a](x.md#t) ![b](img/p.png) [c](https://e.org) `[d](no.md)`\n"
        "```md\n[e](nope.md)\n```\n"
    )
    assert links(doc) == ["x.md#t", "img/p.png"]
    assert anchors(doc) == {"t"}


def test_the_module_map_names_every_module_in_bridge() -> None:
    """architecture.md's module map is the newcomer's way into the code: a module added or
    moved without a line there fails here. A row names a module by its path under bridge/
    (`session/stops.py`), by a pattern (`settings_*.py`) or by its package (`sky/`)."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    section = text.split("## Module map", 1)[1].split("\n## ", 1)[0]
    named = set(re.findall(r"`([\w/*.]+)`", section))
    packages = {n for n in named if n.endswith("/")}
    missing = []
    for path in sorted((ROOT / "bridge").rglob("*.py")):
        rel = path.relative_to(ROOT / "bridge").as_posix()
        if path.name == "__init__.py":  # a package is named by its modules or as a package
            continue
        if any(rel.startswith(p) for p in packages):
            continue
        if not any(Path(rel).match(n) for n in named if not n.endswith("/")):
            missing.append(rel)
    assert not missing, f"modules missing from docs/architecture.md's module map: {missing}"


def test_the_mqtt_pages_field_example_says_where_the_bridge_aims() -> None:
    """A two-letter locator's example says the place the bridge turns to, the field's centre
    (``JA`` read like Japan, and is a field at 85 degrees south)."""
    text = (ROOT / "docs" / "mqtt.md").read_text()
    found = re.findall(
        r'`\{"locator": "([A-R]{2})"\}` \(a field alone: its centre, (\d+)° ([NS]) (\d+)° ([EW])\)',
        text,
    )
    assert found
    for field, lat, north_south, lon, east_west in found:
        centre = (float(lat) * (1 if north_south == "N" else -1), float(lon))
        assert parse_locator(field) == (centre[0], centre[1] * (1 if east_west == "E" else -1))
