"""keyin's Hydra configs, shipped inside the package so that an installed keyin finds them
(``pkg://keyin.conf``): one folder per config group, one root config per entry point."""
