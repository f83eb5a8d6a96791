"""The page uses the public API of Bokeh, Panel, param and Tornado only (issue 32 item 4): no
private module, attribute or hook of theirs, so that a new minor release of them, which may change
anything private without notice, cannot break the page unseen (and pyproject.toml need not refuse
it: its bounds are those of the tests, docs/commands/serve.md).

A scan of the syntax tree of every module under src/explorer/app:

1. an import of a private module or name of those libraries (``from bokeh.core import _x``,
   ``import panel.io._y``);
2. a private attribute (``_x``, not a dunder) on a name bound to them (``pn.state._busy``,
   ``pn.widgets.Checkbox._rename``);
3. in a class derived from one of their classes, a private name the class defines or reads on
   ``self``, ``cls`` or ``super()`` that one of their base classes defines (an override of a
   private hook such as ``_process_param_change``, or a read of their private state); the bases are
   the real classes (the module is imported), so the class's own private helpers pass;
4. in the page's package (app/serve) and every module that imports one of those libraries, a
   private attribute on any other object (a document, an event, a figure, a session: ``doc._held``)
   or a constant private name given to ``getattr``/``setattr``/``hasattr``; only ``self``, ``cls``,
   explorer's own modules and modules of other packages (``os._exit``, documented public) may be
   followed by one.

There are no allowed exceptions (``ALLOWED`` is empty).  The scanner itself is tested on snippets
of each kind, so an empty result means a clean package, not a blind scan.
"""
from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
APP = SRC / "explorer" / "app"
#: the web libraries whose private API the page must not use
LIBRARIES = ("bokeh", "panel", "param", "tornado", "pyviz_comms")
#: (module path relative to src, the flagged text) pairs tolerated, each with its reason: none
ALLOWED: frozenset = frozenset()


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _library(dotted: str) -> bool:
    return dotted.split(".")[0] in LIBRARIES


def _bindings(tree) -> dict:
    """Every name an import binds in the module (anywhere: lazy imports count) -> what it is."""
    bound = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                bound[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for a in node.names:
                bound[a.asname or a.name] = f"{node.module}.{a.name}"
        elif isinstance(node, ast.ImportFrom):
            for a in node.names:                       # a relative import: explorer's own
                bound[a.asname or a.name] = f"explorer.{a.name}"
    return bound


def _root(node):
    """The name at the left of an attribute chain (``pn`` of ``pn.state.x``), else None."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _is_super(node) -> bool:
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "super"


def _library_privates(cls) -> set:
    """The private names that a web library's class in ``cls``'s MRO defines."""
    return {n for k in cls.__mro__[1:] if _library(getattr(k, "__module__", "") or "")
            for n in vars(k) if _private(n)}


def _class_findings(node: ast.ClassDef, bound: dict, module) -> list:
    """Check 3 for one class (the module docstring)."""
    if not any(_library(bound.get(_root(b) or "", "")) for b in node.bases):
        return []
    cls = getattr(module, node.name, None) if module is not None else None
    if cls is None:                      # (not a module-level class: every private name is suspect)
        theirs = None
    else:
        theirs = _library_privates(cls)
    own = set()
    for item in node.body:
        if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
            own.add(item.name)
        elif isinstance(item, (ast.Assign, ast.AnnAssign)):
            targets = item.targets if isinstance(item, ast.Assign) else [item.target]
            own.update(t.id for t in targets if isinstance(t, ast.Name))
    used = {n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute) and _private(n.attr)
            and (isinstance(n.value, ast.Name) and n.value.id in ("self", "cls") or _is_super(n.value))}
    names = {n for n in own | used if _private(n)}
    hit = names if theirs is None else names & theirs
    return [f"class {node.name}: {n} (private to its base class {cls.__mro__[1].__name__ if cls else '?'})"
            for n in sorted(hit)]


def scan(source: str, module=None, strict: bool = True) -> list:
    """What the source uses of the web libraries' private API (module docstring; ``module``: the
    imported module, for the MRO of its classes; ``strict``: check 4 applies)."""
    tree = ast.parse(source)
    bound = _bindings(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [f"import {a.name}" for a in node.names
                      if _library(a.name) and any(_private(p) for p in a.name.split("."))]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level and _library(node.module):
            found += [f"from {node.module} import {a.name}" for a in node.names
                      if any(_private(p) for p in node.module.split(".") + [a.name])]
        elif isinstance(node, ast.ClassDef):
            found += _class_findings(node, bound, module)
        elif isinstance(node, ast.Attribute) and _private(node.attr):
            receiver = node.value
            if isinstance(receiver, ast.Name) and receiver.id in ("self", "cls") or _is_super(receiver):
                continue                                              # check 3
            origin = bound.get(_root(receiver) or "")
            if origin is not None and _library(origin):
                found.append(f"{ast.unparse(node)} (line {node.lineno})")
            elif strict and origin is None:
                found.append(f"{ast.unparse(node)} (line {node.lineno}: a private attribute of an object "
                             "that may be the libraries')")
        elif (strict and isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id in ("getattr", "setattr", "hasattr", "delattr") and len(node.args) > 1
              and isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value, str)
              and _private(node.args[1].value)):
            found.append(f"{ast.unparse(node)} (line {node.lineno})")
    return found


def _modules():
    for path in sorted(APP.rglob("*.py")):
        rel = path.relative_to(SRC)
        yield path, ".".join(rel.with_suffix("").parts).removesuffix(".__init__")


def _uses_a_library(source: str) -> bool:
    return any(_library(v) for v in _bindings(ast.parse(source)).values())


def test_the_app_uses_no_private_api_of_bokeh_panel_param_or_tornado():
    found = []
    for path, dotted in _modules():
        source = path.read_text()
        strict = "serve" in dotted.split(".") or _uses_a_library(source)
        module = importlib.import_module(dotted) if strict else None
        rel = str(path.relative_to(SRC))
        found += [f"{rel}: {f}" for f in scan(source, module, strict) if (rel, f) not in ALLOWED]
    assert not found, f"private API of {', '.join(LIBRARIES)} used: {found}"


#: snippets the scan must flag, one per kind (the first is the page's check box before issue 32 item 4)
FLAGGED = {
    "override of private hooks": (
        "import panel as pn\n"
        "class Box(pn.widgets.Checkbox):\n"
        "    _rename = {**pn.widgets.Checkbox._rename, 'value': 'active'}\n"
        "    def _process_param_change(self, params):\n"
        "        return super()._process_param_change(params)\n",
        ["class Box: _process_param_change", "class Box: _rename", "pn.widgets.Checkbox._rename"]),
    "private import": ("from bokeh.core.property import _sentinel\nimport panel.io._state\n",
                       ["from bokeh.core.property import _sentinel", "import panel.io._state"]),
    "private module attribute": ("import panel as pn\nx = pn.state._thread_pool\n", ["pn.state._thread_pool"]),
    "private state of an object": ("def f(doc):\n    doc._held_events.clear()\n    getattr(doc, '_session_context')\n",
                                   ["doc._held_events", "getattr(doc, '_session_context')"]),
}


@pytest.mark.parametrize("kind", FLAGGED)
def test_the_scan_flags_each_kind_of_private_use(kind):
    source, expected = FLAGGED[kind]
    module = None
    if kind == "override of private hooks":              # (the real MRO: the class is made)
        namespace: dict = {}
        exec(compile(source, "<snippet>", "exec"), namespace)
        module = type("M", (), namespace)
    found = scan(source, module)
    for e in expected:
        assert any(f.startswith(e) for f in found), (e, found)


def test_the_scan_passes_public_use_and_a_subclass_s_own_private_helpers():
    source = ("import os\nimport panel as pn\nimport param\n"
              "class Box(pn.viewable.Viewer):\n"
              "    value = param.Boolean()\n"
              "    def _my_helper(self):\n"
              "        return self._mine\n"
              "    def __panel__(self):\n"
              "        return pn.widgets.CheckBoxGroup(options=['a'])\n"
              "def stop(doc):\n"
              "    doc.add_next_tick_callback(print)\n"
              "    os._exit(0)\n")
    namespace: dict = {}
    exec(compile(source, "<snippet>", "exec"), namespace)
    assert scan(source, type("M", (), namespace)) == []
