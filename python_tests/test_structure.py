"""The add-on's modules import one way (no cycles, lazy imports included), the reload list in
__init__.py names every module, and each module's docstring says what it owns."""

import ast

import pytest

from conftest import ROOT

PACKAGE = ROOT / "addon" / "hairdyn"


def module_names():
    """Dotted names inside the package ("simulation", "methods.lcp", "methods"); the bundled
    preset scripts are data Blender executes, not modules."""
    names = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[0] == "presets" and len(parts) > 1:
            continue
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def imports(name, path, known):
    """The package modules `name` imports, anywhere in the file."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
            elif node.module and node.module.split(".")[0] == "hairdyn":
                base = []
            else:
                continue
            module = ".".join(base + (node.module.split(".") if node.module else []))
            module = module.removeprefix("hairdyn.").removeprefix("hairdyn")
            for alias in node.names:
                child = f"{module}.{alias.name}".strip(".")
                found.add(child if child in known else module)
    return {m for m in found if m in known and m not in (name, "")}


def graph():
    known = module_names()
    return {name: imports(name, path, known) for name, path in known.items() if name}


def test_imports_have_no_cycles():
    edges = graph()
    state = {}

    def visit(node, stack):
        state[node] = "open"
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == "open":
                pytest.fail("import cycle: " + " -> ".join(stack + [node, nxt]))
            if nxt not in state:
                visit(nxt, stack + [node])
        state[node] = "done"

    for node in sorted(edges):
        if node not in state:
            visit(node, [])
    # The seams the design names: simulation and playback no longer import each other.
    assert "playback" not in edges["simulation"] and "bake" not in edges["simulation"]
    assert not any(name.startswith("methods") for name in edges["playback"])


def test_reload_list_names_every_module():
    import hairdyn

    # cli.py is the headless entry point: run as a script, it imports the package itself.
    assert set(hairdyn._MODULES) == set(module_names()) - {"", "cli"}


@pytest.mark.parametrize("name", sorted(set(module_names()) - {""}))
def test_every_module_says_what_it_does(name):
    docstring = ast.get_docstring(ast.parse(module_names()[name].read_text()))
    assert docstring and len(docstring) > 40, name
