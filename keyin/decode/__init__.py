"""Every rule that turns a model (or nothing) into keyframe positions.

A rule is called like every discoverer, ``rule(clips, future_length)`` with clips (B, L, C, H, W)
in [0, 1] and (B,) valid future frames, and returns per clip the future positions it marks,
inside the clip's valid frames: Random and Constant (:mod:`keyin.decode.baselines`), the paper's
argmax offsets (:mod:`keyin.decode.offsets`), surprise peaks (:mod:`keyin.decode.surprise`), and
KEYIN's rules on a trained model as objects that say what they read (:mod:`keyin.decode.registry`),
the rules on the exact segmentation under them and the stage-1 gate (:mod:`keyin.decode.rules` over
:mod:`keyin.decode.segmentation` and :mod:`keyin.decode.segment_costs`). Scoring them is :mod:`keyin.eval`'s job.
"""
