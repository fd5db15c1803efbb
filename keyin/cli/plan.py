"""keyin-plan: hierarchical planning (paper Table 2); not built yet."""

from keyin.cli.pending import not_available


def main() -> None:
    not_available("keyin-plan", "Hierarchical planning with keyframes (paper Table 2)")


if __name__ == "__main__":
    main()
