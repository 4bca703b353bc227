"""The package's structure: data flows one way, and the licence-sensitive calls stay in one place each.

Imports are read from the source with :mod:`ast` — module-level and inside
functions alike — so an import hidden in a function cannot close a cycle.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "supportless"


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imported_modules(name: str, path: Path, known: set[str]) -> set[str]:
    """Modules of the package that ``name`` imports anywhere in its source."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                root = ".".join(base + ([node.module] if node.module else []))
            else:
                root = node.module or ""
            # "from . import io" names a submodule; "from .io import read_mesh" a module
            targets = [f"{root}.{alias.name}" if f"{root}.{alias.name}" in known else root for alias in node.names]
        else:
            continue
        for target in targets:
            while target and target not in known:  # "supportless.energies.arap.x" -> the module that holds x
                target = target.rpartition(".")[0]
            if target and target != name:
                found.add(target)
    return found


def import_graph() -> nx.DiGraph:
    """The package's import graph (a copy: a test may change it), read once per session."""
    return _import_graph().copy()


@functools.cache
def _import_graph() -> nx.DiGraph:
    mods = modules()
    graph = nx.DiGraph()
    graph.add_nodes_from(mods)
    for name, path in mods.items():
        for target in imported_modules(name, path, set(mods)):
            graph.add_edge(name, target)
    return graph


def test_the_graph_reader_sees_function_level_and_relative_imports(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from .sub import b\n    from . import c\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("from ..c import thing\n")
    (pkg / "c.py").write_text("import pkg.a\n")
    known = {"pkg", "pkg.a", "pkg.sub", "pkg.sub.b", "pkg.c"}
    assert imported_modules("pkg.a", pkg / "a.py", known) == {"pkg.sub.b", "pkg.c"}
    assert imported_modules("pkg.sub.b", pkg / "sub" / "b.py", known) == {"pkg.c"}
    assert imported_modules("pkg.c", pkg / "c.py", known) == {"pkg.a"}


def test_package_imports_form_a_dag():
    graph = import_graph()
    graph.remove_node("supportless")  # the package's front door imports its modules; none imports it
    cycles = list(nx.simple_cycles(graph))
    assert not cycles, f"import cycles: {cycles}"


def test_no_module_imports_the_package_front_door():
    graph = import_graph()
    assert list(graph.predecessors("supportless")) == []


# The stages, in the order data flows: a module imports only its own stage and the stages before it.
# A stage is one folder (two when they belong together); each folder's __init__ says what it holds.
# shapes/ and rig/ are two stages, not one: the rig is prepared from a shape (rig/load.py makes a
# demo figure), so shapes/ imports nothing of rig/ (its 2D figure's Triangle is in copyleft/triangle.py).
STAGES = [
    ("base", "copyleft"),
    ("files",),
    ("shapes",),
    ("rig",),
    ("energies",),
    ("search",),
    ("report",),
    ("slicing",),
    ("apps",),
]
FOLDERS = [folder for stage in STAGES for folder in stage]


def stage_of(name: str) -> int:
    """The index in :data:`STAGES` of module ``supportless.FOLDER...``."""
    folder = name.split(".")[1]
    for i, stage in enumerate(STAGES):
        if folder in stage:
            return i
    raise AssertionError(f"{name} is in no stage folder: put it in one of {FOLDERS}")


def test_every_module_is_in_a_stage_folder():
    loose = [name for name, path in modules().items() if name != "supportless" and path.parent == PACKAGE]
    assert not loose, f"modules beside the stage folders: {loose}"
    assert sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()) == sorted(FOLDERS)


@pytest.mark.parametrize("name", sorted(set(modules()) - {"supportless"}))
def test_imports_point_down_the_stages(name):
    graph = import_graph()
    for target in graph.successors(name):
        assert stage_of(target) <= stage_of(name), f"{name} imports {target}, a later stage"


# Stages that may not import each other although the order allows it: (importer, imported, why).
KEPT_APART = [
    ("slicing", "report", "choosing a slice must not load the report's pictures (matplotlib): "
                          "slicer_label and reduction are in files/printer.py"),
]


@pytest.mark.parametrize("importer, imported, why", KEPT_APART, ids=[f"{a}-{b}" for a, b, _ in KEPT_APART])
def test_kept_apart_stages_do_not_import_each_other(importer, imported, why):
    """Not even through another module: nothing ``importer`` reaches by its imports is in ``imported``."""
    graph = import_graph()
    ties = sorted((name, target) for name in graph if name.startswith(f"supportless.{importer}.")
                  for target in nx.descendants(graph, name) if target.startswith(f"supportless.{imported}."))
    assert not ties, f"{importer}/ reaches {imported}/ ({why}): {ties}"


def test_the_tests_mirror_the_stage_folders():
    tests = PACKAGE.parent / "tests"
    folders = sorted(p.name for p in tests.iterdir() if p.is_dir() and any(p.glob("test_*.py")))
    assert folders and set(folders) <= set(FOLDERS), folders
    assert not [p.name for p in tests.glob("test_*.py") if p.name != "test_architecture.py"], "tests beside the folders"


def folder_summary(folder: str) -> str:
    """The first line of a stage folder's ``__init__`` docstring."""
    doc = ast.get_docstring(ast.parse((PACKAGE / folder / "__init__.py").read_text()))
    assert doc, f"supportless/{folder}/__init__.py says nothing of what the folder holds"
    return doc.splitlines()[0]


def layout_block() -> str:
    """The README's Layout block: each stage folder with what it holds and its modules, in the stages' order."""
    import textwrap

    out = []
    for folder in FOLDERS:
        names = sorted(p.stem if p.suffix else p.name + "/" for p in (PACKAGE / folder).iterdir()
                       if (p.suffix == ".py" and p.stem != "__init__") or (p / "__init__.py").exists())
        out.append(f"{folder + '/':<11} {folder_summary(folder)}")
        out += textwrap.wrap(", ".join(names), 108, initial_indent=" " * 12, subsequent_indent=" " * 12)
    return "\n".join(out)


def test_the_readme_layout_is_the_stages():
    """The README's Layout block is :func:`layout_block` (print it with ``python tests/test_architecture.py``)."""
    readme = (PACKAGE.parent / "README.md").read_text()
    start = readme.index("## Layout")
    section = readme[start: readme.index("\n## ", start + 1)]
    assert section.count("```") == 2, "the Layout section holds one block: the stages"
    begin = readme.index("```text\n", start) + len("```text\n")
    block = readme[begin: readme.index("\n```", begin)]
    assert block == layout_block(), "the README's Layout block has drifted: paste python tests/test_architecture.py"


def test_energies_are_arrays_in_arrays_out():
    """The energies import nothing of the package but each other, the shared geometry and graph components, the
    threads a kernel's loop is split over, and the threshold rule."""
    graph = import_graph()
    for name in graph:
        if name.startswith("supportless.energies"):
            for target in graph.successors(name):
                assert target.startswith("supportless.energies") or target in (
                    "supportless.base.geometry", "supportless.base.graph", "supportless.base.errors",
                    "supportless.base.threads", "supportless.files.printer"), (name, target)


def external_imports(path: Path) -> set[str]:
    """Absolute module names ``path`` imports (``import a.b`` and ``from a.b import c`` give ``a.b``)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names.add(node.module)
            names |= {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def test_licence_sensitive_calls_stay_in_one_module_each():
    """TetGen (AGPL) only in copyleft/tetgen.py, CGAL (GPL) only in copyleft/cgal.py; Triangle (non-commercial) only in copyleft/triangle.py."""
    where = {"igl.copyleft.tetgen": set(), "igl.triangle": set(), "igl.copyleft.cgal": set()}
    for name, path in modules().items():
        imported = external_imports(path)
        for key in where:
            if key in imported:
                where[key].add(name)
    assert where == {"igl.copyleft.tetgen": {"supportless.copyleft.tetgen"}, "igl.triangle": {"supportless.copyleft.triangle"},
                     "igl.copyleft.cgal": {"supportless.copyleft.cgal"}}


def test_no_module_is_a_room_of_many_ideas():
    """No module over 650 lines (issue 53: none within 50 lines of the old 700): split one that grows past it."""
    long = {name: n for name, path in modules().items() if (n := len(path.read_text().splitlines())) > 650}
    assert not long, long


if __name__ == "__main__":
    print(layout_block())
