"""Planning (REFERENCE §7, docs/planning.md): a generic CEM, rollouts on the true simulator, the
low-level servo, the planning tasks and what keyin-plan runs on them; the learned keyframe planners
come with the trained pushing models."""
