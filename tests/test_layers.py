"""The layers of sewgen/ as folders, each importing only from those below it (DESIGN.md §8).

Read from the source with ``ast`` (nothing is imported): every ``import`` of a sewgen module, at module top
or inside a function, counts; those under ``if TYPE_CHECKING:`` do not (they never run).

    leaves   units, errors, files, abi, roles, hermite, version   (import only each other)
    derive   the SymPy derivation
    engine   description, build, loader, mechanism, designs, results, forces, loads, frames
    machine  assembly, plan, modelfile, tables, shaking, feed, cams, timing, thread, balance, ...
    study    design tables, influence, tolerance, Dask
    report   tables, summary, output folders, plots
    cli      the sewgen command

``sewgen/__init__.py`` is the public facade above them all: no module imports from it.
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "sewgen"
LEAVES = {"sewgen.units", "sewgen.errors", "sewgen.files", "sewgen.abi", "sewgen.roles", "sewgen.hermite",
          "sewgen.version"}
LAYERS = ("leaves", "derive", "engine", "machine", "study", "report", "cli", "facade")


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def layer(module: str) -> str:
    if module in LEAVES:
        return "leaves"
    if module in ("sewgen", "sewgen.__main__"):
        return "facade"
    parts = module.split(".")
    if len(parts) >= 2 and parts[1] in LAYERS:
        return parts[1]
    if len(parts) >= 2 and parts[1].startswith("_"):  # compiled modules, sewgen._csrc: below everything
        return "leaves"
    raise AssertionError(f"{module}: in no layer (a new module belongs in a layer's folder or among the leaves)")


def _type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or \
        (isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def imports(path: Path) -> list[tuple[str, list[str], int]]:
    """(module imported, names taken from it, line) for every sewgen import in ``path``."""
    me = module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out = []

    def visit(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _type_checking(child):
                continue
            if isinstance(child, ast.Import):
                out.extend((a.name, [], child.lineno) for a in child.names if a.name.split(".")[0] == "sewgen")
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")[: len(package.split(".")) - (child.level - 1)]
                    mod = ".".join(base + ([child.module] if child.module else []))
                else:
                    mod = child.module or ""
                if mod.split(".")[0] == "sewgen":
                    out.append((mod, [a.name for a in child.names], child.lineno))
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    return out


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def edges() -> list[tuple[str, str, int, list[str]]]:
    """(importer, imported module, line, names) with ``from pkg import submodule`` resolved to the submodule."""
    known = modules()
    out = []

    def module(dotted):  # a source module, or a compiled one (sewgen._kernels, built at install time)
        return dotted in known or dotted.startswith("sewgen._kernels")

    for me, path in known.items():
        for mod, names, line in imports(path):
            subs = [f"{mod}.{n}" for n in names if module(f"{mod}.{n}")]
            if subs:
                out.extend((me, s, line, []) for s in subs)
                rest = [n for n in names if not module(f"{mod}.{n}")]
                if rest:
                    out.append((me, mod, line, rest))
            else:
                out.append((me, mod, line, names))
    return out


def test_every_module_is_in_a_layer():
    for name in modules():
        layer(name)


def test_no_module_imports_from_a_layer_above_its_own():
    upward = []
    for me, mod, line, _ in edges():
        if me == mod or mod.startswith(me + "."):  # a package's __init__ re-exporting its own modules
            continue
        a, b = LAYERS.index(layer(me)), LAYERS.index(layer(mod))
        if b > a:
            upward.append(f"{modules()[me].relative_to(ROOT)}:{line} ({layer(me)}) imports {mod} ({layer(mod)})")
    assert upward == []


def test_leaves_import_only_leaves():
    bad = [f"{me} imports {mod}" for me, mod, _, _ in edges() if layer(me) == "leaves" and layer(mod) != "leaves"]
    assert bad == []


def test_no_import_cycle():
    graph: dict[str, set[str]] = {}
    for me, mod, _, _ in edges():
        if me != mod and not mod.startswith(me + "."):
            graph.setdefault(me, set()).add(mod)
    # a package's __init__ is imported with any of its modules: an edge to a module goes through its packages
    cycles = []
    state: dict[str, int] = {}
    stack: list[str] = []

    def walk(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                cycles.append(" -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                walk(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            walk(node)
    assert cycles == []


def test_no_private_name_is_read_across_modules():
    """``from sewgen.x import _y`` and ``sewgen.x._y`` outside sewgen/x: a name with a leading underscore is
    its module's own (the compiled ``_kernels`` modules are named so, and are imported by the loader)."""
    known = modules()
    bad = []
    for me, mod, line, names in edges():
        if mod == me:
            continue
        bad += [f"{me}:{line} takes {mod}.{n}" for n in names if n.startswith("_") and not n.startswith("__")
                and f"{mod}.{n}" not in known and not n.startswith("_kernels")]
    for me, path in known.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
                base = node.value
                dotted = []
                while isinstance(base, ast.Attribute):
                    dotted.append(base.attr)
                    base = base.value
                if isinstance(base, ast.Name) and base.id == "sewgen":
                    bad.append(f"{me}:{node.lineno} reads sewgen.{'.'.join(reversed(dotted))}.{node.attr}")
    assert bad == []


#: Private attributes of other libraries that sewgen uses on purpose: SymPy's printer dispatch (a printer
#: subclass's documented extension point) and pint's unit container of a quantity's root units.
FOREIGN_PRIVATE = {"_print", "_units"}


def test_no_private_attribute_of_another_module_is_read():
    """``obj._x`` where ``_x`` is defined nowhere in the reading module (not as a function, class, assignment,
    argument or attribute of its own): another module's private attribute (a Mechanism's ``_fast``, say)."""
    bad = []
    for me, path in modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        own = set()
        for n in ast.walk(tree):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                own.add(n.name)
            elif isinstance(n, ast.Attribute) and isinstance(n.ctx, ast.Store):
                own.add(n.attr)
            elif isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
                own.add(n.id)
            elif isinstance(n, ast.arg):
                own.add(n.arg)
            elif isinstance(n, ast.keyword) and n.arg:
                own.add(n.arg)
            elif isinstance(n, ast.Constant) and isinstance(n.value, str):
                own.add(n.value)  # __slots__, object.__setattr__(self, "_x", ...), fields dicts
        for n in ast.walk(tree):
            if (isinstance(n, ast.Attribute) and isinstance(n.ctx, ast.Load) and n.attr.startswith("_")
                    and not n.attr.startswith("__") and n.attr not in own and n.attr not in FOREIGN_PRIVATE
                    and not (isinstance(n.value, ast.Name) and n.value.id in ("self", "cls"))):
                bad.append(f"{path.relative_to(ROOT)}:{n.lineno} reads {ast.unparse(n)}")
    assert bad == []
