"""The results page's tables are pasted from the committed reports, unchanged: every row of each report
named here stands in docs/results/README.md as it is in the report. README.md stays short, its
relative links lead somewhere, and its Table 1 figures are those of the reports its columns link."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = "docs/results/README.md"
# Reports whose tables docs/results/README.md shows (keyin 0.1's older tables, in docs/history/, predate this check).
REPORTS_IN_RESULTS = (
    "docs/results/untrained_table1/table1.md", "docs/results/brownian_table1/table1.md", "docs/results/pushing_table1/table1.md",
    "docs/results/pushing_table2/table2.md", "docs/results/metaworld_table1/table1.md",
    "docs/results/metaworld_v2_table1/table1.md",
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


def report_f1(report: str) -> dict[str, tuple[str, str, int]]:
    """A Table 1 report's interior F1 per method: (mean, std, seeds) as the report prints them."""
    lines = [line for line in (ROOT / report).read_text(encoding="utf-8").splitlines() if line.startswith("|")]
    header = [cell.strip() for cell in lines[0].strip("|").split("|")]
    method, f1, seeds = header.index("method"), header.index("F1 interior"), header.index("seeds")
    found = {}
    for line in table_rows("\n".join(lines)):
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        mean, std = cells[f1].split(" ± ")
        found[cells[method]] = (mean, std, int(cells[seeds]))
    return found


def readme_method(label: str) -> str:
    """A README row's method: the last `name` in its label, else its first word (``Jumpy`` → jumpy)."""
    named = re.findall(r"`([a-z0-9_]+(?: · [a-z0-9_= ]+)?)`", label)  # a row's changed choices after a ·
    return named[-1] if named else label.split()[0].lower()


def test_the_readme_table1_figures_are_those_of_the_linked_reports():
    text = (ROOT / "README.md").read_text(encoding="utf-8").split("\n| method | [Brownian F1]", 1)
    assert len(text) == 2, "README.md has no results table (a header row starting '| method | [Brownian F1]')"
    lines = ("| method | [Brownian F1]" + text[1]).split("\n\n", 1)[0].splitlines()  # the table alone
    links = [re.search(r"\]\(([^)]+)\)", cell) for cell in lines[0].strip("|").split("|")]
    columns = {i: link.group(1) for i, link in enumerate(links) if link and link.group(1).endswith("table1.md")}
    assert len(columns) >= 3, "README.md's results table links fewer than three Table 1 reports"
    reports = {i: report_f1(report) for i, report in columns.items()}
    checked = 0
    for line in lines[2:]:
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        method = readme_method(cells[0])
        for i, report in columns.items():
            figure = re.match(r"\**([0-9.]+)\**(?: ± ([0-9.]+))?", cells[i])
            if not figure:
                continue
            assert method in reports[i], f"README.md's {method!r} has a figure in {report}'s column but no row there"
            mean, std, seeds = reports[i][method]
            where = f"README.md's {method!r} in the column of {report}"
            assert figure.group(1) == mean, f"{where}: {figure.group(1)}, the report says {mean}"
            if figure.group(2) is None:
                assert seeds == 1 and "(seed 0)" in cells[i], f"{where}: one figure without ± but {seeds} seeds"
            else:
                assert figure.group(2) == std, f"{where}: ± {figure.group(2)}, the report says ± {std}"
            checked += 1
    assert checked >= 20, f"only {checked} README.md figures were compared with the reports"


def test_the_readme_method_of_a_row_label():
    assert readme_method("KEYIN + ours, `map` (`keyin_plus`)") == "keyin_plus"
    assert readme_method("Constant (every 5 frames)") == "constant"
    assert readme_method("the paper's loss (`keyin_paper · backbone=ours scale=cpu`)") == "keyin_paper · backbone=ours scale=cpu"


def test_what_the_readme_says_the_keyin_paper_rows_ran_is_what_their_job_configs_hold():
    """README's Methods and Results describe Table 1's rows of the paper's KEYIN as its loss at CPU sizes on our frame
    model (2-2.5k + 1.5k steps, all of stage 1 frozen, soft δ), named so; every committed job config of those rows agrees."""
    import yaml

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    methods = next(line for line in text.splitlines() if line.startswith("| `keyin` (rows say `keyin_paper`)"))
    assert "`scale=cpu` on `backbone=ours`, all of stage 1 frozen, soft δ" in methods
    assert "| the paper's loss, CPU sizes, our frame model, 2-2.5k + 1.5k steps (`keyin_paper · backbone=ours scale=cpu`) |" in text
    configs = sorted(ROOT.glob("docs/results/*_table1/jobs/keyin_paper_seed*/config.yaml"))
    assert len(configs) >= 9  # Brownian, pushing and Meta-World, 3 seeds each
    for path in configs:
        config = yaml.safe_load(path.read_text())
        keyframes, scale = config["model"]["keyframes"], config["scale"]
        assert config["backbone"]["name"] == "ours" and scale["lstm_hidden"] == 128 and scale["inter_latent"] == 0, path
        assert keyframes.get("frozen", "stage1") == "stage1" and keyframes.get("delta_input", "soft") == "soft", path
        assert keyframes["teacher_weight"] == 0 and not keyframes["offset_evidence"], path
        assert scale["stage2_steps"] == 1500 and scale["stage1_steps"] in (2000, 2500), path
