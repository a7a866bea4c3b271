"""Controller families. REGISTRY maps the configuration's ``model`` name to its ModelSpec.

Rules:
1. A family's module is imported when one of its models is first looked up, never before: a
   start imports only the families its rotators use (the rest is start-up CPU for nothing,
   benchmarks/exchange_cpu.py). Asking whether a name is a model, or listing the names, imports
   nothing; going through the specs (``values()``, ``items()``) imports every family.
2. MODULES lists every model of every family's ``MODELS``, in REGISTRY's order
   (tests/protocols/test_registry.py holds it to them).
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping

from bridge.protocols.base import ModelSpec

__all__ = ["MODULES", "REGISTRY"]

#: each model's family: the module of bridge.protocols whose MODELS holds it (rule 2)
MODULES: dict[str, str] = {
    "rotorez": "rotorez",
    "rotorcard": "rotorez",
    "dcu1": "rotorez",
    "rot2prog": "spid",
    "rot1prog": "spid",
    "md01": "spid",
    "satel": "satel",
    "gs232a": "gs232",
    "gs232a-450": "gs232",
    "gs232a-az": "gs232",
    "gs232a-az-450": "gs232",
    "gs232b": "gs232",
    "gs232b-450": "gs232",
    "gs232b-az": "gs232",
    "gs232b-az-450": "gs232",
    "easycomm2": "easycomm",
    "easycomm2-az": "easycomm",
    "easycomm2-separate": "easycomm",
    "easycomm3": "easycomm",
    "easycomm3-az": "easycomm",
    "easycomm3-separate": "easycomm",
    "rt21": "rt21",
    "prosistel": "prosistel",
    "prosistel-el": "prosistel",
    "prosistel-el-a": "prosistel",
    "prosistel-combi": "prosistel",
    "rc2800": "rc2800",
    "rc2800-az": "rc2800",
}


class _Registry(Mapping[str, ModelSpec]):
    """The model names of MODULES, each looked up in its family's MODELS on first use (rule 1)."""

    def __init__(self, modules: dict[str, str]) -> None:
        self._modules = modules
        self._specs: dict[str, ModelSpec] = {}

    def __getitem__(self, name: str) -> ModelSpec:
        spec = self._specs.get(name)
        if spec is None:
            family = self._modules[name]  # KeyError for a name that is no model, as a dict's
            # (two threads at once: the import system imports it once, both add the same specs)
            self._specs.update(importlib.import_module(f"{__name__}.{family}").MODELS)
            spec = self._specs[name]
        return spec

    def __contains__(self, name: object) -> bool:
        return name in self._modules

    def __iter__(self) -> Iterator[str]:
        return iter(self._modules)

    def __len__(self) -> int:
        return len(self._modules)


REGISTRY: Mapping[str, ModelSpec] = _Registry(MODULES)
