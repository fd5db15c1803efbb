"""Where the tests find keyin's configs: inside the package, as an installed keyin does."""

from pathlib import Path

import keyin.conf

CONFIGS = Path(keyin.conf.__file__).parent
