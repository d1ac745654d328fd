"""The code's layout rules (README, "How the code is laid out"): no two modules of
mocap import each other, even through others; the methods (silhouette, track) and the
lift do not import one another, nor io a method; mocap never imports the app but for
`mocap serve`; the app reaches the methods only through the session and the pipeline;
at most six modules directly in mocap/, none over 400 lines, docstrings under 15 %."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path, known: set[str]) -> set[str]:
    """The modules of ``known`` a file imports anywhere in it (functions too); ``from
    a import b`` counts a.b where that is a module, else a."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out |= {
                f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in known else node.module for a in node.names
            }
    return out & known


def import_graph(folder: str) -> dict[str, set[str]]:
    files = {module_name(p): p for p in (ROOT / folder).rglob("*.py")}
    return {name: imports_of(path, set(files)) - {name} for name, path in files.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_cycles_are_found():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_two_mocap_modules_import_each_other():
    assert cycles(import_graph("mocap")) == []


def test_mocap_never_imports_the_app_but_to_serve():
    for path in (ROOT / "mocap").rglob("*.py"):
        tree = ast.parse(path.read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        uses_app = {m for m in names if m == "app" or m.startswith("app.")}
        assert uses_app <= ({"app.serve"} if path.parent.name == "cli" else set()), path


def package_of(module: str) -> str:
    return ".".join(module.split(".")[:2])


APART = {
    "mocap.lift": {"mocap.track", "mocap.silhouette"},
    "mocap.track": {"mocap.lift"},
    "mocap.silhouette": {"mocap.lift"},
    "mocap.io": {"mocap.track", "mocap.silhouette"},
}


def test_the_methods_the_lift_and_io_keep_apart():
    crossings = [
        (a, b)
        for a, imported in import_graph("mocap").items()
        for b in imported
        if package_of(b) in APART.get(package_of(a), ())
    ]
    assert crossings == []


def test_few_modules_at_the_top_none_long():
    assert len(list((ROOT / "mocap").glob("*.py"))) <= 6
    long = [
        (str(p.relative_to(ROOT)), n)
        for folder in ("mocap", "app")
        for p in (ROOT / folder).rglob("*.py")
        if (n := len(p.read_text().splitlines())) > 400
    ]
    assert long == []


def docstring_lines(path: Path) -> int:
    count = 0
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                count += first.end_lineno - first.lineno + 1
    return count


def test_docstrings_are_short():
    files = [p for folder in ("mocap", "app") for p in (ROOT / folder).rglob("*.py")]
    share = sum(map(docstring_lines, files)) / sum(len(p.read_text().splitlines()) for p in files)
    assert share < 0.15, f"{share:.1%} of the lines are docstrings"


APP_MAY_IMPORT = {
    "mocap.session",
    "mocap.pipeline",
    "mocap.body",
    "mocap.errors",
    "mocap.person",
    "mocap.io",
    "mocap.image",
}


def test_the_app_talks_to_the_session_only():
    for path in (ROOT / "app").rglob("*.py"):
        tree = ast.parse(path.read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        reached = {package_of(m) for m in names if m.startswith("mocap")}
        assert reached <= APP_MAY_IMPORT, f"{path.name} imports {sorted(reached - APP_MAY_IMPORT)}"
