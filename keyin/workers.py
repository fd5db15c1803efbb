"""Worker processes that end with their parent: the initializer of keyin's process pools."""

from __future__ import annotations

import os
import threading
import time


def exit_with_parent(parent: int) -> None:
    """Worker initializer: end the worker within a second of its parent's death (e.g. kill -9),
    instead of waiting forever on a queue no one writes to."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True).start()
