"""Planning (REFERENCE §7, docs/planning.md): a generic CEM, rollouts on the true simulator and the
low-level servo; the high-level keyframe planners come with the trained pushing model."""
