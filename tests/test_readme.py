"""The README's tables are pasted from the committed reports, unchanged: every row of each report
named here stands in README.md as it is in the report."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# Reports whose tables README.md shows (keyin 0.1's older tables predate this check).
REPORTS_IN_README = (
    "docs/results/untrained_table1/table1.md", "docs/results/brownian_table1/table1.md", "docs/results/pushing_table1/table1.md",
    "docs/results/pushing_table2/table2.md",
)


def table_rows(markdown: str) -> list[str]:
    """The data rows of the Markdown tables in ``markdown`` (header and rule lines left out)."""
    lines = [line.strip() for line in markdown.splitlines() if line.strip().startswith("|")]
    return [line for line in lines if not line.startswith("|---") and not line.startswith("| dataset |")]


@pytest.mark.parametrize("report", REPORTS_IN_README)
def test_every_row_of_the_report_stands_in_the_readme_unchanged(report):
    readme = set(table_rows((ROOT / "README.md").read_text(encoding="utf-8")))
    rows = table_rows((ROOT / report).read_text(encoding="utf-8"))
    assert rows, f"{report} has no table"
    missing = [row for row in rows if row not in readme]
    assert not missing, f"README.md lacks or changed these rows of {report}:\n" + "\n".join(missing)


def test_only_the_data_rows_of_a_table_are_compared():
    markdown = "text | not a row\n| dataset | method |\n|---|---|\n| brownian | random | 0.166 |\n"
    assert table_rows(markdown) == ["| brownian | random | 0.166 |"]
