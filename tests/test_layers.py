"""Every top-level module and package of fieldtwin has its place in the layers contract."""

from __future__ import annotations

import importlib
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "fieldtwin"


def _layered() -> set[str]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (layers,) = [c for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "layers"]
    names: set[str] = set()
    for layer in layers["layers"]:
        for part in layer.replace("|", ":").split(":"):
            names.add(part.strip().removeprefix("fieldtwin."))
    return names


def test_every_module_and_package_is_in_a_layer() -> None:
    found = {p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"}
    found |= {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    missing = sorted(found - _layered())
    assert not missing, f"add {missing} to a layer of the import-linter contract (pyproject.toml)"


# --- issue 21: no file-level cycle, no door from a core upward, glue out of the cores ---

CORES = ("tsx", "tes")
# The one cycle left to the windows' rewrite of fieldtwin.testing (targets.target_of asks
# process for RunningPlant, process asks helpers and targets): remove it there.
KNOWN_CYCLES = [
    {"fieldtwin.testing.helpers", "fieldtwin.testing.process", "fieldtwin.testing.targets"}
]


def _cycles() -> list[set[str]]:
    """Strongly connected groups of modules (TYPE_CHECKING and lazy imports count)."""
    import grimp

    graph = grimp.build_graph("fieldtwin", include_external_packages=False)
    edges = {m: graph.find_modules_directly_imported_by(m) for m in graph.modules}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []

    def visit(start: str) -> None:  # Tarjan, iterative
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                group = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.add(member)
                    if member == node:
                        break
                if len(group) > 1:
                    found.append(group)

    for module in sorted(edges):
        if module not in index:
            visit(module)
    return found


def test_no_file_level_import_cycle_in_src() -> None:
    cycles = [c for c in _cycles() if c not in KNOWN_CYCLES]
    assert not cycles, f"file-level import cycles: {[sorted(c) for c in cycles]}"


def test_no_ignored_import_and_no_colon_sibling_in_the_layers_contract() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    for contract in config["tool"]["importlinter"]["contracts"]:
        assert not contract.get("ignore_imports"), contract["name"]
        if contract["type"] == "layers":
            # ':' joins siblings that may import each other; '|' makes them independent
            assert not [layer for layer in contract["layers"] if ":" in layer]


def test_the_cores_hold_no_plant_glue_and_no_console_text() -> None:
    for core in CORES:
        folder = PACKAGE / core
        assert not [p for p in folder.rglob("plant*.py")], core
        assert not list(folder.rglob("plantkeys.py")), core
        for path in folder.rglob("*.py"):
            text = path.read_text()
            for word in ("console_input", "configure_from_plant", "*args: Any"):
                assert word not in text, f"{path.relative_to(ROOT)}: {word}"


def test_the_moved_public_names_keep_working() -> None:
    from fieldtwin.facade.tes import build_tes as new_build
    from fieldtwin.facade.tes import start_tes_endpoints as new_start
    from fieldtwin.objects import ObjectRef as KernelRef
    from fieldtwin.tsx.addressing import ObjectRef, parse_object

    old = importlib.import_module("fieldtwin.tes.plant")  # documented in docs/tes.md
    assert (old.start_tes_endpoints, old.build_tes) == (new_start, new_build)
    assert ObjectRef is KernelRef and parse_object("IW5,0").slot == 5


WINDOWS = (
    "fieldtwin.runtime",
    "fieldtwin.control",
    "fieldtwin.testing",
    "fieldtwin.console",
    "fieldtwin.console_prog",
    "fieldtwin.console_syntax",
    "fieldtwin.console_trace",
    "fieldtwin.live",
    "fieldtwin.plant",
    "fieldtwin.replay",
    "fieldtwin.scenario",
    "fieldtwin.session",
)
KIND_MODULES = (
    "fieldtwin.devices.aem811",
    "fieldtwin.devices.dem24",
    "fieldtwin.devices.scm",
    "fieldtwin.devices.tes",
    "fieldtwin.devices.discrete",
    "fieldtwin.tes",
    "fieldtwin.tsx.aem811",
    "fieldtwin.tsx.dem24",
    "fieldtwin.tsx.scm",
    "fieldtwin.tsx.discrete",
)


def _window_files() -> list[Path]:
    files: list[Path] = []
    for window in WINDOWS:
        path = PACKAGE / window.removeprefix("fieldtwin.")
        files.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path.with_suffix(".py")])
    return files


def test_the_forbidden_contract_keeps_the_windows_from_every_device_kind() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (forbidden,) = [
        c for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "forbidden"
    ]
    assert set(forbidden["source_modules"]) == set(WINDOWS)
    assert set(forbidden["forbidden_modules"]) == set(KIND_MODULES)
    assert not forbidden.get("ignore_imports")


def test_no_window_source_names_a_device_kind() -> None:
    """The same rule read in the text, lazy imports in functions included (lint-imports
    sees them too; this runs with the tests)."""
    kinds = "|".join(re.escape(k) for k in KIND_MODULES)
    pattern = re.compile(rf"^\s*(?:from|import)\s+(?:{kinds})(?:[.\s]|$)", re.MULTILINE)
    files = _window_files()
    assert len(files) > len(WINDOWS)  # the packages' files were found
    found = [
        f"{path.relative_to(ROOT)}: {m.group(0).strip()}"
        for path in files
        for m in pattern.finditer(path.read_text())
    ]
    assert not found, found
