"""The layers of the package and the direction of its imports.

explorer is built in layers, each allowed to import only from layers below it (or its own):

    _jit  <-  kernels  <-  model  <-  integrate  <-  analysis  <-  io  <-  app

- ``kernels``: model-agnostic numerics (DOP853 tableau and step, Taylor step control,
  splitting compositions, event roots, tangent-vector accumulators);
- ``model``: the physics of docs/model.md (parameters, vector field, sub-flows, exact solutions);
- ``integrate``: the stepping loops applied to the model's compiled system;
- ``analysis``: sections, chaos indicators, fixed points, Melnikov, trajectories, sweeps
  (arrays in, arrays out);
- ``io``: scenes and the HDF5 store;
- ``app``: command line, sweep runner, figures, the interactive explorer.

The test reads every module's imports (including those inside functions) from its syntax
tree, so a lazy import cannot hide an upward dependency.  matplotlib may be imported only
in ``app`` (and so may panel and bokeh, the web page of ``explorer serve``), h5py only in ``io`` and
``app``.
"""
import ast
import functools
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "explorer"
LAYERS = ["_jit", "kernels", "model", "integrate", "analysis", "io", "app"]
#: third-party packages that only the upper layers may import
RESTRICTED = {"matplotlib": "app", "h5py": "io", "panel": "app", "bokeh": "app"}


def layer_of(dotted: str):
    """Layer index of a module ``explorer.<layer>...`` (None for the package root)."""
    parts = dotted.split(".")
    if parts[0] != "explorer" or len(parts) < 2:
        return None
    return LAYERS.index(parts[1]) if parts[1] in LAYERS else None


def modules():
    for f in sorted(SRC.rglob("*.py")):
        rel = f.relative_to(SRC.parent).with_suffix("")
        yield ".".join(p for p in rel.parts if p != "__init__") if rel.name == "__init__" else ".".join(rel.parts), f


@functools.cache
def syntax_tree(path: Path) -> ast.Module:
    """The module's syntax tree, parsed once for all the tests (each walks every module)."""
    return ast.parse(path.read_text())


@functools.cache
def imports(path: Path, dotted: str) -> tuple:
    """(module imported, line) for every import statement, relative ones resolved."""
    return tuple(_imports(syntax_tree(path), path, dotted))


def _imports(tree: ast.Module, path: Path, dotted: str):
    pkg = dotted if path.name == "__init__.py" else dotted.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            if mod == "explorer":   # from explorer import model -> explorer.model
                for a in node.names:
                    yield f"explorer.{a.name}", node.lineno
            else:
                yield mod, node.lineno


def test_every_module_lives_in_a_layer():
    loose = [d for d, _ in modules() if layer_of(d) is None and d not in ("explorer", "explorer.__main__")]
    assert not loose, f"modules outside the layer packages {LAYERS}: {loose}"


def test_imports_point_down_the_layers():
    bad = []
    for dotted, path in modules():
        mine = layer_of(dotted)
        if mine is None:
            continue
        for mod, line in imports(path, dotted):
            other = layer_of(mod)
            if other is not None and other > mine:
                bad.append(f"{path.relative_to(SRC.parent)}:{line} ({LAYERS[mine]}) imports {mod} ({LAYERS[other]})")
    assert not bad, "imports against the layer order:\n" + "\n".join(bad)


@pytest.mark.parametrize("package, lowest", sorted(RESTRICTED.items()))
def test_heavy_io_packages_only_in_upper_layers(package, lowest):
    bad = []
    for dotted, path in modules():
        mine = layer_of(dotted)
        if mine is None or mine >= LAYERS.index(lowest):
            continue
        for mod, line in imports(path, dotted):
            if mod.split(".")[0] == package:
                bad.append(f"{path.relative_to(SRC.parent)}:{line}")
    assert not bad, f"{package} imported below {lowest}: {bad}"


def module_graph():
    """Each module's set of explorer modules it imports (``from pkg import submodule`` included)."""
    mods = dict(modules())
    graph = {}
    for dotted, path in mods.items():
        deps = set()
        tree = syntax_tree(path)
        pkg = dotted if path.name == "__init__.py" else dotted.rpartition(".")[0]
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module
                targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in mods else mod for a in node.names]
            else:
                continue
            for target in targets:
                while target and target not in mods:
                    target = target.rpartition(".")[0]
                if target and target != dotted and target != "explorer":
                    deps.add(target)
        graph[dotted] = deps
    return graph


def import_circles(graph):
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, circles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return circles


def test_import_circles_are_found_by_the_check():
    assert import_circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert import_circles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_itself_through_a_circle():
    """Runtime, lazy and ``TYPE_CHECKING`` imports all count; a package's ``__init__`` counts as the
    package, so re-exporting a submodule's names is no circle unless that submodule imports the package."""
    circles = import_circles(module_graph())
    assert not circles, "import circles:\n" + "\n".join(" <-> ".join(c) for c in circles)


#: docs/contributing.md: docstrings state the contract and cite the docs; the reference is docs/
MAX_PROSE_SHARE = 0.15


def prose_lines(text: str, tree: ast.Module | None = None) -> tuple[int, int]:
    """(docstring and comment lines, all lines) of one module's source (``tree``: its syntax
    tree, if parsed already)."""
    import io
    import tokenize
    marked = {tok.start[0] for tok in tokenize.generate_tokens(io.StringIO(text).readline)
              if tok.type == tokenize.COMMENT}
    for node in ast.walk(ast.parse(text) if tree is None else tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                marked.update(range(first.lineno, first.end_lineno + 1))
    return len(marked), len(text.splitlines())


def test_prose_lines_are_counted_as_docstrings_and_comments():
    text = '"""Module.\n\nMore."""\nx = 1  # why\n\n\ndef f():\n    """One."""\n    return "not a docstring"\n'
    assert prose_lines(text) == (5, 9)


def test_docstrings_and_comments_are_at_most_15_percent_of_src():
    """Docstrings and comments over all lines of src (generated files aside) stay within
    MAX_PROSE_SHARE: the contract and a citation at the line, the rest in docs/."""
    prose = total = 0
    for _, path in modules():
        if "_generated" not in path.name:
            p, n = prose_lines(path.read_text(), syntax_tree(path))
            prose, total = prose + p, total + n
    assert prose / total <= MAX_PROSE_SHARE, f"{prose} of {total} lines are prose ({prose / total:.1%})"


#: the page's code (src/explorer/app/serve), every line counted: issue 50's budget, every feature kept
MAX_SERVE_LINES = 3200


def test_the_page_code_stays_within_its_line_budget():
    """src/explorer/app/serve holds at most MAX_SERVE_LINES lines: the page's work is Panel's and
    Bokeh's machinery and the layers below, not code of its own (docs/architecture.md)."""
    lines = sum(len(p.read_text().splitlines()) for p in sorted((SRC / "app" / "serve").rglob("*.py")))
    assert lines <= MAX_SERVE_LINES, f"src/explorer/app/serve has {lines} lines"
