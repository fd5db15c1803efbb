"""The names of KEYIN's discovery rules and keyframe prices, without torch: the commands check
``rule=`` and ``keyframe_cost=`` before they import a model (``--help`` answers at once)."""

KEYIN_RULES = ("offsets", "boundaries", "map", "map_pruned", "segmentation")
VARIANT_RULES = ("offsets", "boundaries", "map")  # scored beside a model's own rule when it has offset evidence
SEGMENT_COST_RULES = ("map", "map_pruned", "segmentation")  # the rules that read the segments' interpolation BCE
BOUNDARY_SCORE_RULES = ("boundaries", "map_pruned")  # the rules that read stage 2's boundary scores (offset_evidence)
KNEE = "knee"  # the label-free keyframe price: each clip's count at the knee of its cost curve
