"""Planning (paper §4.2, App. 10; docs/planning.md): a generic CEM, rollouts on the true simulator, the
low-level servo, the planning tasks, the high-level planners (KEYIN's and Jumpy's latent CEM, TAP)
and what keyin-plan runs on them."""
