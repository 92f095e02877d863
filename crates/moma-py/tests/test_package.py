"""The package's surface: every public name has a docstring and a stub."""

import ast
from pathlib import Path

import moma

STUB = Path(moma.__file__).with_name("__init__.pyi")


def test_every_public_name_is_documented_and_stubbed():
    tree = ast.parse(STUB.read_text())
    stubbed = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    stubbed |= {t.id for n in tree.body if isinstance(n, ast.AnnAssign) for t in [n.target]}
    stubbed |= {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names}
    for name in moma.__all__:
        assert name in stubbed, f"{name} has no type stub"
        obj = getattr(moma, name)
        if callable(obj) or name == "sweep":
            assert obj.__doc__ and len(obj.__doc__) > 20, f"{name} has no docstring"
    assert Path(moma.__file__).with_name("py.typed").is_file()
    assert moma.__version__ == "0.1.0"
