"""keyin's Hydra configs (conf/ at the top level, shipped as the package keyin.conf) so that an installed keyin finds them
(``pkg://keyin.conf``): one folder per config group, one root config per entry point."""
