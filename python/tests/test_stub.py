"""The type stub (osgbtf.pyi) names what the module has, and the module what the stub names."""
import ast
import pathlib

import osgbtf

STUB = pathlib.Path(__file__).resolve().parents[1] / "osgbtf.pyi"
HELPERS = {"FloatArray", "Direction", "ProgressCallback", "OptionSchema", "MethodSchema",
           "ErrorSummary"}  # typing aliases and TypedDicts of the stub alone


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            target = node.targets[0] if isinstance(node, ast.Assign) else node.target
            top.add(target.id)
    return top, members


def test_the_stub_and_the_module_name_the_same_things():
    top, members = stub_names()
    public = {n for n in dir(osgbtf) if not n.startswith("_")} | {"__version__"}
    assert top - HELPERS == public
    for cls in ("Btf", "Material"):
        have = {n for n in dir(getattr(osgbtf, cls)) if not n.startswith("_")}
        assert members[cls] == have, cls


def test_the_stub_has_the_module_functions_keywords():
    tree = ast.parse(STUB.read_text())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name in ("load", "sample", "compare"):
            doc = getattr(osgbtf, node.name).__doc__
            for arg in node.args.args:
                assert arg.arg in doc, (node.name, arg.arg)
