"""keyin's code and configs cite what a reader can open: the paper (its sections, equations, algorithms,
appendices) or a file of this repository, never a note kept outside it; and a cited section of a doc
("docs/architecture.md, "Baselines"") begins a heading of that doc, or a paragraph's bold label."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = [path for folder in ("keyin", "conf") for path in sorted((ROOT / folder).rglob("*"))
           if path.suffix in (".py", ".yaml") and path.is_file()]
# docs/<name>.md, "Heading" · docs/<name>.md ("Heading") · docs/<name>.md, 'Heading' (inside f-strings)
DOC_SECTION = re.compile(r"(docs/[\w/]+\.md)(?:, | \()[\"']([^\"']+)[\"']")


def plain(text: str) -> str:
    """``text`` without Markdown's backticks and asterisks, with × read as x."""
    return text.replace("`", "").replace("*", "").replace("×", "x").strip()


def headings(doc: Path) -> set[str]:
    """The text of every Markdown heading of ``doc`` and of every paragraph's bold label (``**Label.**``)."""
    lines = doc.read_text(encoding="utf-8").splitlines()
    return {plain(line.lstrip("#")) for line in lines if line.startswith("#")} | {
        plain(line.split("**")[1]) for line in lines if line.startswith("**") and line.count("**") >= 2}


def words(text: str) -> str:
    """``text`` with a line break and a YAML or Python comment's ``#`` between its words read as one space."""
    return re.sub(r"\s*\n\s*#?\s*", " ", text).strip()


def test_the_product_is_read_somewhere():
    assert len(PRODUCT) > 100


@pytest.mark.parametrize("path", PRODUCT, ids=lambda path: str(path.relative_to(ROOT)))
def test_no_product_file_cites_the_outside_reference(path):
    lines = [f"{number}: {line.strip()}" for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if "REFERENCE" in line]
    assert not lines, (f"{path.relative_to(ROOT)} cites REFERENCE, which is not in this repository; cite the paper "
                       "(paper §3.2, eq. 4, Alg. 2, App. 10) or a doc here (docs/architecture.md, \"Conventions\"):\n"
                       + "\n".join(lines))


def test_every_cited_doc_section_begins_a_heading_of_that_doc():
    cited = {(doc, section, path) for path in PRODUCT
             for doc, section in DOC_SECTION.findall(path.read_text(encoding="utf-8"))}
    assert len(cited) >= 20, "fewer doc sections cited than expected: is the pattern still right?"
    missing = [f"{path.relative_to(ROOT)}: {doc}, \"{section}\"" for doc, section, path in sorted(cited)
               if not (ROOT / doc).is_file() or not any(heading.startswith(plain(words(section))) for heading in headings(ROOT / doc))]
    assert not missing, "cited sections that are no heading of their doc:\n" + "\n".join(missing)
