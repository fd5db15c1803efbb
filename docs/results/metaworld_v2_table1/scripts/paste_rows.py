"""Issue 46: put the rows of a collected Table 1 report into its section of docs/results/README.md (the
rows there must equal the report's: tests/test_readme.py).

    python docs/results/metaworld_v2_table1/scripts/paste_rows.py docs/results/metaworld_v2_table1/table1.md \
        "### Version 2: timing a fixed pattern cannot follow"
"""

import sys
from pathlib import Path

PAGE = Path("docs/results/README.md")


def main() -> None:
    report, heading = Path(sys.argv[1]), sys.argv[2]
    rows = [line for line in report.read_text().splitlines() if line.startswith("| ") and not line.startswith(("| dataset", "|---"))]
    lines = PAGE.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(heading))
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("#")), len(lines))
    table = [i for i in range(start, end) if lines[i].startswith("| ") and not lines[i].startswith(("| dataset", "|---"))]
    if not table:
        raise SystemExit(f"no table rows under {heading!r} in {PAGE}")
    lines[table[0] : table[-1] + 1] = rows
    PAGE.write_text("\n".join(lines) + "\n")
    print(f"{PAGE}: {len(rows)} rows under {heading!r}")


if __name__ == "__main__":
    main()
