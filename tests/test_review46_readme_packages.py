"""Review 46 (a cold read of the README as a new user): "Both commands do their own set-up:
they install the Debian packages they need (`mosquitto`, `mosquitto-clients`; the tests also
...)". A user on a minimal Debian reads that list to know what ``./tests/run`` will put on the
machine with ``sudo``; ``tests/run`` installs two more than the README names: ``iproute2``
(whose ``ss`` a test reads a listener's backlog with) and, where ``npm`` is missing, ``npm``
(for aedes; ``nodejs`` alone does not bring it on Debian)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _installed_by(script: str) -> list[str]:
    """The Debian packages a set-up script hands to scripts/bootstrap or apt-get install."""
    text = (ROOT / script).read_text()
    (line,) = re.findall(r"^source scripts/bootstrap (.*)$", text, re.M)
    words = line.split()
    for apt in re.findall(r"apt-get install ([^>\n]*)", text):
        words += apt.split()
    return [w for w in words if not w.startswith(("-", '"'))]


def _readme_try_it() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("## Try it")
    return text[start : text.index("\n## ", start + 1)]


def test_the_readme_names_every_debian_package_the_test_command_installs() -> None:
    named = set(re.findall(r"`([a-z0-9][a-z0-9.+-]*)`", _readme_try_it()))
    for script in ("demo", "tests/run"):
        missing = [p for p in _installed_by(script) if p not in named]
        assert not missing, f"{script} installs {missing}, which README's Try it does not name"
