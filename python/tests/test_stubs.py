"""The type stubs name exactly what the module exports, and each class's public methods."""

import ast
import pathlib

import ocellus
from ocellus import _ocellus

STUB = pathlib.Path(ocellus.__file__).with_name("_ocellus.pyi")


def test_stubs_match_the_module():
    tree = ast.parse(STUB.read_text())
    top = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    exported = set(ocellus.__all__)
    assert exported == set(top), f"missing stubs {exported - set(top)}, stale stubs {set(top) - exported}"
    assert all(hasattr(_ocellus, name) for name in exported)
    for name, node in top.items():
        if isinstance(node, ast.ClassDef) and name != "OcellusError":
            stubbed = {f.name for f in node.body if isinstance(f, ast.FunctionDef) and not f.name.startswith("_")}
            actual = {a for a in dir(getattr(_ocellus, name)) if not a.startswith("_")}
            assert stubbed == actual, f"{name}: stubs {sorted(stubbed)} vs module {sorted(actual)}"
