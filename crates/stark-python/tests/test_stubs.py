"""The type stubs describe exactly the runtime API (names and parameter names), and everything
public has a docstring."""

import ast
import inspect
from pathlib import Path

import pytest

import starkrs
from starkrs import _starkrs, geometry, meshes, sym

PACKAGE = Path(starkrs.__file__).parent
ALIASES = {"geometry", "meshes", "sym", "__version__"}


def stub_names(path):
    """Top-level names of a stub, and the members of each class."""
    tree = ast.parse(path.read_text())
    top, classes = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    members.add(item.target.id)
            classes[node.name] = members
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
        elif isinstance(node, ast.Assign):
            top.update(t.id for t in node.targets)
    # Private names (`_Vector`, `_Points`, ...) are type aliases that exist only in the stubs.
    return {n for n in top if not n.startswith("_") or n == "__version__"}, classes


def public(obj):
    return {n for n in dir(obj) if not n.startswith("_")}


def test_stub_files_ship_with_the_package():
    for name in ("__init__.pyi", "geometry.pyi", "meshes.pyi", "sym.pyi", "py.typed"):
        assert (PACKAGE / name).exists(), name


def test_module_stub_matches_the_runtime():
    top, classes = stub_names(PACKAGE / "__init__.pyi")
    runtime = public(_starkrs) - {"geometry", "meshes"}
    assert runtime - top == set(), "missing in __init__.pyi"
    assert top - runtime - ALIASES == set(), "in __init__.pyi but not at run time"
    for name, members in classes.items():
        cls = getattr(_starkrs, name)
        if issubclass(cls, Exception):
            continue
        runtime_members = {n for n in vars(cls) if not n.startswith("_")}
        assert runtime_members - members == set(), f"{name}: missing in the stub"
        assert members - runtime_members - {"__new__", "__len__", "__copy__", "__deepcopy__"} == set(), name


@pytest.mark.parametrize("module, stub", [(geometry, "geometry.pyi"), (meshes, "meshes.pyi"), (sym, "sym.pyi")])
def test_submodule_stubs_match_the_runtime(module, stub):
    top, _ = stub_names(PACKAGE / stub)
    assert public(module) == top - ALIASES


def stub_functions(path):
    """(class name or None, function node) for every function and method of a stub, but
    properties, overloads and dunder methods."""
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.FunctionDef):
            yield None, node
        elif isinstance(node, ast.ClassDef):
            for item in node.body:
                if not isinstance(item, ast.FunctionDef):
                    continue
                decorators = {d.id for d in item.decorator_list if isinstance(d, ast.Name)}
                if (not item.name.startswith("__") and not decorators & {"property", "overload"}
                        and not any(isinstance(d, ast.Attribute) for d in item.decorator_list)):
                    yield node.name, item


@pytest.mark.parametrize("module, stub", [(_starkrs, "__init__.pyi"), (geometry, "geometry.pyi"),
                                          (meshes, "meshes.pyi")])
def test_stub_parameter_names_match_the_runtime(module, stub):
    # Keyword arguments are part of the API: a renamed parameter (units in names) must be renamed
    # in the stub too.
    checked, wrong = 0, []
    for cls, fn in stub_functions(PACKAGE / stub):
        obj = getattr(getattr(module, cls), fn.name) if cls else getattr(module, fn.name)
        runtime = [n for n in inspect.signature(obj).parameters if n not in ("self", "$self")]
        a = fn.args
        stubbed = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs if x.arg not in ("self", "cls")]
        if runtime != stubbed:
            wrong.append(f"{cls}.{fn.name}: runtime {runtime}, stub {stubbed}")
        checked += 1
    assert checked > 0 and wrong == []


def test_everything_public_has_a_docstring():
    missing = []
    for name in public(_starkrs):
        obj = getattr(_starkrs, name)
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                if not (getattr(value, "__doc__", None) or "").strip():
                    missing.append(f"{name}.{member}")
    for module in (geometry, meshes, sym):
        for name in public(module):
            if not (getattr(module, name).__doc__ or "").strip():
                missing.append(f"{module.__name__}.{name}")
    assert missing == []


def test_parameter_class_docs_match_the_generated_stubs():
    # The parameter classes and their section of the stub (`gen_stubs`) are both made from the
    # library's field tables; this checks the extension and the committed stub agree.
    text = (PACKAGE / "__init__.pyi").read_text()
    section = ast.parse(text[text.index("# <generated>"):text.index("# </generated>")])
    checked = 0
    for node in section.body:
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(_starkrs, node.name)
        assert inspect.cleandoc(cls.__doc__) == ast.get_docstring(node), node.name
        fields = [a.target.id for a in node.body if isinstance(a, ast.AnnAssign)]
        assert set(fields) == set(cls().to_dict()), node.name
        for a, b in zip(node.body, node.body[1:]):
            if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr):
                runtime = inspect.cleandoc(getattr(cls, a.target.id).__doc__)
                assert runtime == inspect.cleandoc(b.value.value), f"{node.name}.{a.target.id}"
                checked += 1
            elif isinstance(a, ast.FunctionDef) and not a.name.startswith("__") and ast.get_docstring(a):
                assert inspect.cleandoc(getattr(cls, a.name).__doc__) == ast.get_docstring(a), a.name
                checked += 1
    assert checked >= 50
