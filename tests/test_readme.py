"""The results page's tables are pasted from the committed reports, unchanged: every row of each report
named here stands in docs/results/README.md as it is in the report. README.md stays short and its
relative links lead somewhere."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = "docs/results/README.md"
# Reports whose tables docs/results/README.md shows (keyin 0.1's older tables, in docs/history/, predate this check).
REPORTS_IN_RESULTS = (
    "docs/results/untrained_table1/table1.md", "docs/results/brownian_table1/table1.md", "docs/results/pushing_table1/table1.md",
    "docs/results/pushing_table2/table2.md", "docs/results/metaworld_table1/table1.md",
)
README_MAX_LINES = 150


def table_rows(markdown: str) -> list[str]:
    """The data rows of the Markdown tables in ``markdown`` (header and rule lines left out)."""
    lines = [line.strip() for line in markdown.splitlines() if line.strip().startswith("|")]
    return [line for line in lines if not line.startswith("|---") and not line.startswith("| dataset |")]


@pytest.mark.parametrize("report", REPORTS_IN_RESULTS)
def test_every_row_of_the_report_stands_in_the_results_page_unchanged(report):
    results = set(table_rows((ROOT / RESULTS).read_text(encoding="utf-8")))
    rows = table_rows((ROOT / report).read_text(encoding="utf-8"))
    assert rows, f"{report} has no table"
    missing = [row for row in rows if row not in results]
    assert not missing, f"{RESULTS} lacks or changed these rows of {report}:\n" + "\n".join(missing)


def test_only_the_data_rows_of_a_table_are_compared():
    markdown = "text | not a row\n| dataset | method |\n|---|---|\n| brownian | random | 0.166 |\n"
    assert table_rows(markdown) == ["| brownian | random | 0.166 |"]


def test_the_readme_is_short():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines, more than {README_MAX_LINES}"


def test_every_relative_link_in_the_readme_points_to_a_file():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = [t.split("#")[0] for t in re.findall(r"\]\(([^)\s]+)\)", text)]
    relative = [t for t in targets if t and not re.match(r"[a-z]+:", t)]
    assert relative, "README.md links no file"
    missing = [t for t in relative if not (ROOT / t).exists()]
    assert not missing, "README.md links files that do not exist: " + ", ".join(missing)
