"""No import circle anywhere in bridge/, TYPE_CHECKING imports included (docs/architecture.md,
"dependencies point down"). import-linter's acyclic_siblings contract (pyproject.toml) keeps it
so in the static checks; this test says the same in the suite and names the circle it finds."""

from __future__ import annotations

import grimp


def find_cycle(graph: grimp.ImportGraph, package: str) -> list[str] | None:
    """One import circle among the modules of ``package`` (first module repeated at the end),
    or None."""
    modules = sorted(m for m in graph.modules if m == package or m.startswith(package + "."))
    done: set[str] = set()
    for root in modules:
        if root in done:
            continue
        path: list[str] = []
        on_path: set[str] = set()
        stack: list[tuple[str, list[str]]] = [(root, _imports(graph, root, package))]
        path.append(root)
        on_path.add(root)
        while stack:
            module, todo = stack[-1]
            if not todo:
                stack.pop()
                path.pop()
                on_path.discard(module)
                done.add(module)
                continue
            nxt = todo.pop()
            if nxt in on_path:
                return [*path[path.index(nxt) :], nxt]
            if nxt not in done:
                stack.append((nxt, _imports(graph, nxt, package)))
                path.append(nxt)
                on_path.add(nxt)
    return None


def _imports(graph: grimp.ImportGraph, module: str, package: str) -> list[str]:
    found = graph.find_modules_directly_imported_by(module)
    return sorted((m for m in found if m.startswith(package + ".")), reverse=True)


def test_bridge_has_no_import_circle() -> None:
    graph = grimp.build_graph("bridge", cache_dir=None)  # TYPE_CHECKING imports included
    cycle = find_cycle(graph, "bridge")
    assert cycle is None, "import circle: " + " -> ".join(cycle or [])


def test_the_guard_finds_and_names_a_circle() -> None:
    graph = grimp.ImportGraph()
    for name in ("p", "p.a", "p.b", "p.c", "p.d"):
        graph.add_module(name)
    graph.add_import(importer="p.a", imported="p.b")
    graph.add_import(importer="p.b", imported="p.c")
    graph.add_import(importer="p.d", imported="p.c")
    assert find_cycle(graph, "p") is None
    graph.add_import(importer="p.c", imported="p.a")  # as a TYPE_CHECKING import would
    assert find_cycle(graph, "p") == ["p.a", "p.b", "p.c", "p.a"]


def test_the_service_loads_neither_the_web_server_nor_the_astronomy_before_they_are_used() -> None:
    """aiohttp and the console's server, numpy, skyfield and sgp4 are a third of the CPU the
    bridge takes to start (a second or more on a small single-board computer): importing the
    service loads none of them; the console imports its server when it is on, the sky its
    astronomy and sgp4 on first use (sky/positions.py rule 6, sky/bodies.py rule 5)."""
    heavy = [
        "aiohttp",
        "numpy",
        "skyfield",
        "sgp4",
        "bridge.interfaces.web.server",
        "bridge.interfaces.web.live",
    ]
    assert loaded_of(heavy, "bridge.app, bridge.cli") == "[]"


def test_the_stop_express_child_loads_no_table_but_the_brokers() -> None:
    """The stop express's child (interfaces/mqtt/express.py rule 1) is a second interpreter
    started with the bridge and again after each of its ends: it takes the broker's table
    (settings/mqtt.py) and nothing of the rest of the configuration, pydantic-settings among it
    (a third of what it took to start, the package importing every table at once)."""
    heavy = [
        "pydantic_settings",
        "bridge.settings.config",
        "bridge.settings.rotator",
        "bridge.settings.dxcluster",
        "bridge.session",
        "bridge.runtime",
    ]
    assert loaded_of(heavy, "bridge.interfaces.mqtt.express") == "[]"


def loaded_of(heavy: list[str], imported: str) -> str:
    """Which of ``heavy`` a fresh interpreter has loaded once it imported ``imported`` (a
    comma-separated list of modules), as Python prints a sorted list."""
    import subprocess
    import sys

    check = f"import sys, {imported}; print(sorted(m for m in sys.modules if m in W))"
    out = subprocess.run(
        [sys.executable, "-c", f"W = {set(heavy)!r}; {check}"],
        capture_output=True,
        text=True,
        check=True,
    )
    return out.stdout.strip()
