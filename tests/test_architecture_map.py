"""docs/architecture.md's map from the paper's equations to functions names functions that exist."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENTRY = re.compile(r"`(keyin/[\w/]+\.py):([\w.]+)`")


def defined_names(path: Path) -> set[str]:
    """``function`` and ``Class.method`` names defined at the top of a module."""
    names = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        if isinstance(node, ast.ClassDef):
            names.update(f"{node.name}.{item.name}" for item in node.body if isinstance(item, ast.FunctionDef))
    return names


def test_every_equation_names_an_existing_function():
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("## The paper's equations", 1)[1].split("\n## ", 1)[0]
    entries = ENTRY.findall(section)
    assert len(entries) >= 15
    missing = [f"{file}:{name}" for file, name in entries if name not in defined_names(ROOT / file)]
    assert not missing, f"docs/architecture.md names functions that do not exist: {missing}"
