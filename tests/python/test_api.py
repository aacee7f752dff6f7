"""The package's stub (__init__.pyi) and its runtime agree, and help() reads as documentation."""
import ast
import os
import pydoc

import sinew


def stub_names():
    path = os.path.join(os.path.dirname(sinew.__file__), "__init__.pyi")
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = [n.name for n in node.body
                                if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")
                                ] + [n.target.id for n in node.body if isinstance(n, ast.AnnAssign)]
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = []
        elif isinstance(node, ast.AnnAssign) and node.target.id not in (
                "PathLike", "Float64Array", "Int32Array", "Int64Array"):
            names[node.target.id] = []
    return names


def test_every_stub_name_exists_and_every_public_name_is_in_the_stub():
    names = stub_names()
    assert set(names) == set(sinew.__all__)
    instance_only = {"file", "folder", "scene", "field", "problem", "index"}  # set in __init__
    for name, members in names.items():
        obj = getattr(sinew, name)
        for member in members:
            assert member in instance_only or hasattr(obj, member), f"sinew.{name}.{member}"


def test_help_reads_well():
    text = pydoc.render_doc(sinew.Simulation, renderer=pydoc.plaintext)
    for phrase in ("stepped from Python", "Ctrl-C", "set_force", "Needs `loads`",
                   "u(n), m: N × 3", "bit for bit"):
        assert phrase in text, phrase
    for obj in (sinew.run, sinew.voxelize, sinew.Scene.with_, sinew.Results, sinew.Model,
                sinew.Model.load, sinew.Results.export, sinew.UnstableError):
        assert obj.__doc__ and len(obj.__doc__) > 40, obj
