"""Where the tests find keyin's configs: inside the package, as an installed keyin does."""

from pathlib import Path

import keyin.conf

CONFIGS = Path(keyin.conf.__file__).parent

# keyin 0.1's scale=smoke also set method values "to exercise the paths"; they are overrides now.
OLD_SMOKE = ("backbone=ours", "backbone.norm=batch", "backbone.foreground_weight=3.0")
OLD_SMOKE_TWO_STAGES = (*OLD_SMOKE, "model.keyframes.teacher_keyframe_cost=25.0")
# keyin 0.1's `keyin-train scale=smoke` (model=keyin then was today's keyin_plus).
OLD_SMOKE_KEYIN = ("model=keyin_plus", *OLD_SMOKE_TWO_STAGES, "model.keyframes.teacher_weight=1.0",
                   "model.keyframes.discovery=offsets", "model.keyframes.teacher_leaves=false")
