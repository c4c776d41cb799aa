"""The layers of docs/architecture.md: every import points down the table (or within a layer),
function-level imports included; imports for type checkers only are not dependencies."""

from __future__ import annotations

import ast
from pathlib import Path

import visviva

SOURCE = Path(visviva.__file__).parent

#: The layers, lowest first (docs/architecture.md, "Layers").
LAYERS = [
    {
        "errors",
        "_validation",
        "_registry",
        "_memo",
        "_lazy",
        "_version",
        "_blas",
        "_compiling",
        "_stop",
    },
    {"ode", "geometry"},
    {"integrators", "mechanics"},
    {"analysis"},
    {"forces", "collision", "particles", "deformables", "rigid"},
    {"entities"},
    {"model"},
    {"simulation"},
    {"studies"},
    {"io"},
    {"viz"},
    {"scenes", "sweeps", "demos", "cli", "__init__", "__main__"},
]
LAYER = {package: level for level, packages in enumerate(LAYERS) for package in packages}
#: Modules with a layer of their own: the mesh file reader imports only the base, and the kinds
#: that take a mesh file (entities) read it when they are added to a builder.
LAYER["io.meshes"] = 0


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            lines |= {child.lineno for child in ast.walk(node) if hasattr(child, "lineno")}
    return lines


def _layered(parts: list[str]) -> str:
    """The entry of :data:`LAYER` that holds the module ``visviva.<parts>``."""
    dotted = ".".join(parts[:2])
    return dotted if dotted in LAYER else parts[0].removesuffix(".py")


def _imported_packages(path: Path) -> list[tuple[int, str]]:
    """``(line, entry of LAYER)`` of each import in ``path`` that type checkers are not
    alone to see."""
    module = ["visviva", *path.relative_to(SOURCE).with_suffix("").parts]
    tree = ast.parse(path.read_text())
    skip = _type_checking_lines(tree)
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or node.lineno in skip:
            continue
        if node.level:
            base = module[: len(module) - node.level]
            full = base + (node.module.split(".") if node.module else [])
        else:
            full = (node.module or "").split(".")
        if full[0] != "visviva":
            continue
        targets = [_layered(full[1:])] if len(full) > 1 else [a.name for a in node.names]
        found += [(node.lineno, target) for target in targets]
    return found


def test_every_package_has_a_layer():
    packages = {p.stem for p in SOURCE.glob("*.py")} | {
        p.parent.name for p in SOURCE.glob("*/__init__.py")
    }
    assert packages <= set(LAYER), sorted(packages - set(LAYER))


def test_imports_point_down_the_layers():
    wrong = []
    for path in sorted(SOURCE.rglob("*.py")):
        own = _layered(list(path.relative_to(SOURCE).with_suffix("").parts))
        for line, target in _imported_packages(path):
            if target in LAYER and LAYER[target] > LAYER[own]:
                wrong.append(f"{path.relative_to(SOURCE)}:{line}: {own} imports {target}")
    assert not wrong, "\n".join(wrong)
