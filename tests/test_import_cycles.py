"""No import cycle between sibling modules of any ftkin package, lazy imports included.

``lint-imports`` keeps the contract "No import cycle" (``acyclic_siblings``, pyproject.toml);
this test finds the cycles itself (Tarjan's strongly connected components on grimp's graph,
with each child package taken as one node, as the contract does) and names every import line
that closes one, so that a failure says where to cut. A function-level import counts: an
import that climbs back up is a cycle, only hidden from the reader.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

grimp = pytest.importorskip("grimp")

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def graph():
    return grimp.build_graph("ftkin", cache_dir=None)


def _sibling_edges(graph, package: str) -> dict[str, set[str]]:
    """Imports between the children of ``package``, each child with its descendants as one node."""
    children = graph.find_children(package)

    def child_of(module: str) -> str | None:
        if not module.startswith(package + "."):
            return None
        child = package + "." + module[len(package) + 1 :].split(".")[0]
        return child if child in children else None

    edges: dict[str, set[str]] = {child: set() for child in children}
    for child in children:
        for importer in (child, *graph.find_descendants(child)):
            for imported in graph.find_modules_directly_imported_by(importer):
                target = child_of(imported)
                if target is not None and target != child:
                    edges[child].add(target)
    return edges


def strongly_connected(edges: dict[str, set[str]]) -> list[list[str]]:
    """The components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, targets = work[-1]
            target = next(targets, None)
            if target is not None:
                if target not in index:
                    index[target] = low[target] = len(index)
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(edges[target]))))
                elif target in on_stack:
                    low[node] = min(low[node], index[target])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_search_finds_a_cycle_and_only_a_cycle():
    """The component search on hand-made graphs: a 3-cycle with a tail, a 2-cycle, a chain."""
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"f"}, "f": {"e"}}
    assert sorted(strongly_connected(edges)) == [["a", "b", "c"], ["e", "f"]]
    assert strongly_connected({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def _packages(graph) -> list[str]:
    return sorted(module for module in graph.modules if graph.find_children(module))


def test_every_package_has_its_siblings_acyclic(graph):
    problems = []
    for package in _packages(graph):
        edges = _sibling_edges(graph, package)
        for component in strongly_connected(edges):
            lines = []
            for importer in component:
                for imported in sorted(edges[importer] & set(component)):
                    for module in (importer, *graph.find_descendants(importer)):
                        for target in (imported, *graph.find_descendants(imported)):
                            for detail in graph.get_import_details(
                                importer=module, imported=target
                            ):
                                lines.append(
                                    f"  {detail['importer']}:{detail['line_number']} "
                                    f"{detail['line_contents']}"
                                )
            problems.append(f"cycle in {package}: {', '.join(component)}\n" + "\n".join(lines))
    assert not problems, "\n".join(problems)


def test_lint_imports_checks_the_same_rule():
    """``make lint`` runs ``lint-imports``: the acyclic contract must stay in its configuration."""
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    contracts = [c for c in settings["contracts"] if c["type"] == "acyclic_siblings"]
    assert [c["ancestors"] for c in contracts] == [["ftkin"]]
