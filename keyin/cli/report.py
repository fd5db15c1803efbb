"""keyin-report: the paper's tables from a sweep; not built yet."""

from keyin.cli.pending import not_available


def main() -> None:
    not_available("keyin-report", "Table 1 baselines and keyin-report")


if __name__ == "__main__":
    main()
