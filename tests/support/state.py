"""The bridge's state file as a test reads it while the bridge runs."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def kept(path: Path, rotator_id: str, key: str) -> Any:
    """What the state file at ``path`` keeps for a rotator under ``key``; None while the file
    is not written, or says nothing of it yet (a start writes it first with no rotator's table,
    and a save comes a moment after what it saves: a wait that read it then failed in CI)."""
    try:
        doc = json.loads(path.read_text())
    except (FileNotFoundError, ValueError):
        return None
    return doc.get("rotators", {}).get(rotator_id, {}).get(key)
