"""The model registry (protocols/__init__.py): every family's models, and a start that imports
only the families its rotators use."""

from __future__ import annotations

import importlib
import json
import pkgutil
import subprocess
import sys
from pathlib import Path

import bridge.protocols
from bridge.protocols import MODULES, REGISTRY
from tests.support import bridge_env


def test_the_table_lists_every_model_of_every_family_in_order() -> None:
    listed: dict[str, str] = {}
    for info in pkgutil.iter_modules(bridge.protocols.__path__):
        module = importlib.import_module(f"bridge.protocols.{info.name}")
        for name in getattr(module, "MODELS", {}):
            listed[name] = info.name
    assert MODULES == listed  # the same names and families
    families = list(dict.fromkeys(MODULES.values()))
    for family in families:  # each family's models in its own order
        models = importlib.import_module(f"bridge.protocols.{family}").MODELS
        assert [m for m in MODULES if MODULES[m] == family] == list(models)
        assert all(REGISTRY[m] is spec for m, spec in models.items())
    assert list(REGISTRY) == list(MODULES) and len(REGISTRY) == len(MODULES)
    assert "rotor-ez" not in REGISTRY and REGISTRY.get("rotor-ez") is None


def families_loaded(tmp_path: Path, *models: str) -> list[str]:
    """The families a fresh interpreter has imported once it has read a configuration of
    rotators of ``models`` and built the bridge from it (not started)."""
    rotators = [
        {"id": f"r{i}", "model": m, "port": f"{tmp_path}/tty{i}"} for i, m in enumerate(models)
    ]
    code = f"""
import sys
from bridge.app import App
from bridge.protocols import MODULES
from bridge.settings import settings_from
settings = settings_from({{
    "state_file": {str(tmp_path / "state.json")!r}, "mqtt": {{"host": "127.0.0.1", "port": 1}},
    "rotators": {rotators!r}}}, {{}})
App(settings)
import json
loaded = [f for f in set(MODULES.values()) if "bridge.protocols." + f in sys.modules]
print(json.dumps(sorted(loaded)))
"""
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=bridge_env()
    )
    names: list[str] = json.loads(run.stdout)
    return names


def test_a_start_imports_only_the_families_its_rotators_use(tmp_path: Path) -> None:
    """A family's code is start-up CPU (benchmarks/exchange_cpu.py): 16 Rotor-EZ bring in the
    Rotor-EZ family alone, and a SPID beside them its own family too, and it works."""
    assert families_loaded(tmp_path, "rotorez") == ["rotorez"]
    assert families_loaded(tmp_path, "rotorez", "rot2prog") == ["rotorez", "spid"]
