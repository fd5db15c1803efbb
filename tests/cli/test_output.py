"""A run prints what a user acts on: Lightning's install tips and its own internal deprecation are
dropped, while every other warning, the user's data and config included, still shows."""

import logging
import warnings

from keyin.cli.app import CHATTY_LIBRARIES, LightningTips, quiet_expected_library_output, show_library_info
from tests.cli.runner import run


def record(message: str) -> logging.LogRecord:
    return logging.LogRecord("lightning.pytorch.utilities.rank_zero", logging.INFO, __file__, 1, message, None, None)


def test_lightning_tips_are_dropped_and_its_other_lines_kept():
    tips = LightningTips()
    assert not tips.filter(record("💡 Tip: For seamless cloud logging and experiment tracking, try installing litlogger"))
    assert tips.filter(record("GPU available: False, used: False"))


def test_only_lightnings_pytree_deprecation_is_silenced():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        quiet_expected_library_output()
        warnings.warn("`isinstance(treespec, LeafSpec)` is deprecated, use `isinstance(treespec, TreeSpec)`")
        warnings.warn("data/brownian/test-00000.h5 holds frames in 0/1, not 0-255")
    assert [str(w.message) for w in caught] == ["data/brownian/test-00000.h5 holds frames in 0/1, not 0-255"]


def test_installing_the_filters_twice_adds_them_once():
    quiet_expected_library_output()
    quiet_expected_library_output()
    filters = logging.getLogger("lightning.pytorch.utilities.rank_zero").filters
    assert sum(isinstance(existing, LightningTips) for existing in filters) == 1


def test_library_info_lines_are_hidden_unless_verbose(tmp_path):
    """absl's and OpenGL's INFO lines ("MUJOCO_GL=egl, attempting to import ...") are hidden by
    default and shown with verbose=true; their warnings always show."""
    for verbose, shown in (("false", False), ("true", True)):
        result = run("generate", "dataset=brownian", "splits={test: 2}", "progress=false", f"verbose={verbose}",
                     f"hydra.run.dir=run_{verbose}", cwd=tmp_path)
        assert result.returncode == 0, result.stderr
        for name in CHATTY_LIBRARIES:
            library = logging.getLogger(name)
            assert library.isEnabledFor(logging.WARNING)
            assert library.level == (logging.NOTSET if shown else logging.WARNING)
    show_library_info(False)
