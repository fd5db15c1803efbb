"""Entry points whose capability has not landed yet say so clearly and exit with status 2."""

from __future__ import annotations

import sys


def not_available(command: str, issue: str) -> None:
    print(
        f"error: {command} is not available yet: it arrives with the issue \"{issue}\". "
        f"Nothing was run.",
        file=sys.stderr,
    )
    sys.exit(2)
