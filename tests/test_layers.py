"""Imports run down the layers of docs/architecture.md: every import in keyin/ (inside functions and
``TYPE_CHECKING`` blocks too) read with ``ast``, none pointing from a package to one above it."""

import ast
import textwrap
from pathlib import Path

import keyin

PACKAGE = Path(keyin.__file__).parent
ENTRY_LAYERS = ("keyin.lit", "keyin.planning", "keyin.pipelines", "keyin.cli")
# package -> what it must not import: cli -> pipelines -> lit/planning -> eval -> decode -> losses -> models -> data/envs.
# Allowed within the middle row: lit/ -> eval/ (validation F1) and planning/ -> lit/ (loading checkpoints), planning/ -> eval/.
BELOW_DECODE = (*ENTRY_LAYERS, "keyin.eval", "keyin.viz", "keyin.decode")
BANNED = {
    "keyin.pipelines": ("keyin.cli",),
    "keyin.lit": ("keyin.cli", "keyin.pipelines"),
    "keyin.planning": ("keyin.cli", "keyin.pipelines"),
    "keyin.pretrained": (*BELOW_DECODE, "keyin.models", "keyin.losses", "keyin.data", "keyin.envs"),
    "keyin.viz": (*ENTRY_LAYERS, "keyin.eval"),
    "keyin.eval": ENTRY_LAYERS,
    "keyin.decode": (*ENTRY_LAYERS, "keyin.eval", "keyin.viz"),
    "keyin.models": (*BELOW_DECODE, "keyin.losses"),  # losses score what the models compute, on their positions
    "keyin.losses": BELOW_DECODE,
    "keyin.data": BELOW_DECODE,
    "keyin.envs": BELOW_DECODE,
}


def module_name(path: Path) -> str:
    """``keyin/eval/video.py`` -> ``keyin.eval.video``; a package's ``__init__.py`` -> the package."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(source: str, package: str) -> list[tuple[int, str]]:
    """(line, dotted name) of everything ``source``, a module of ``package``, imports anywhere in it;
    ``from a import b`` gives ``a.b``, relative imports are resolved."""
    names = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            parts = package.split(".")
            base = ".".join(parts[: len(parts) - node.level + 1]) if node.level else ""
            module = ".".join(part for part in (base, node.module) if part)
            names += [(node.lineno, f"{module}.{alias.name}") for alias in node.names]
    return names


def within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def test_no_package_imports_a_layer_above_it():
    offences = []
    for path in sorted(PACKAGE.rglob("*.py")):
        name = module_name(path)
        banned = [above for package, aboves in BANNED.items() if within(name, package) for above in aboves]
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for line, target in imported(path.read_text(encoding="utf-8"), package):
            if any(within(target, above) for above in banned):
                offences.append(f"{path.relative_to(PACKAGE.parent)}:{line} imports {target}")
    assert not offences, "imports that point up the layers (docs/architecture.md):\n" + "\n".join(offences)


def test_deferred_relative_and_type_checking_imports_are_seen():
    source = textwrap.dedent(
        """
        from typing import TYPE_CHECKING
        import keyin.io
        from ..lit import keyframes
        from keyin import planning
        if TYPE_CHECKING:
            from keyin.cli.app import fail

        def score():
            from .f1 import keyframe_lists
        """
    )
    assert sorted(name for _, name in imported(source, "keyin.eval")) == [
        "keyin.cli.app.fail", "keyin.eval.f1.keyframe_lists", "keyin.io", "keyin.lit.keyframes",
        "keyin.planning", "typing.TYPE_CHECKING",
    ]


def module_graph() -> dict[str, set[str]]:
    """keyin module → the keyin modules it imports anywhere in it (``from a import b`` counts as a
    or as a.b, whichever is a module)."""
    modules = {module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for _, target in imported(path.read_text(encoding="utf-8"), package):
            target = target if target in modules else target.rpartition(".")[0]
            if target in modules and target != name:
                targets.add(target)
        graph[name] = targets
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, found, counter = {}, {}, [], set(), [], [0]

    def visit(node: str) -> None:
        index[node] = low[node] = counter[0]
        counter[0] += 1
        stack.append(node)
        on_stack.add(node)
        for target in graph.get(node, ()):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_modules_import_each_other_in_a_circle():
    """A circle held open only by an import inside a function is still a circle."""
    circles = cycles(module_graph())
    assert not circles, f"modules that import each other in a circle: {circles}"


def test_the_circle_finder_finds_a_circle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
