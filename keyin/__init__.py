"""keyin: keyframe discovery and planning with keyframe-based stochastic video prediction."""

__version__ = "0.2.0"

# Models renamed since keyin 0.1, old name -> today's: 0.1's `keyin` (at scale=cpu, with our
# additions) is `keyin_plus`; `keyin` is now the paper's method. Read where a checkpoint or a
# metrics.json carries no keyin_version.
RENAMED_SINCE_0_1 = {"keyin": "keyin_plus"}

# The Hydra configs (conf/) ship inside the package as this module, so an installed keyin needs no source tree.
CONFIG_MODULE = "keyin.conf"

# The entry of the run config every keyin-train checkpoint stores (keyin.checkpoints.CONFIG_KEY) that names the run's
# config-group choices (``{"backbone": "ours", "scale": "cpu", ...}``; checkpoints written before 2026-12-07 have none):
# what the values alone do not name.
CHOICES_KEY = "choices"
