# Two commands on a fresh machine: `make demo` and `make test`. Each creates .venv and installs
# keyin into it on first use. TORCH_SPEC picks the torch build installed first: the default is the
# CPU build (torch==2.13.0); on a GPU machine use e.g. `make test TORCH_SPEC=` to keep your own torch.
VENV ?= .venv
PYTHON ?= python3
TORCH_SPEC ?= torch==2.13.0
EXTRAS ?= dev,sim,track,launchers,tune
BIN = $(VENV)/bin
STAMP = $(VENV)/.keyin-installed

.PHONY: demo demo-keyin test test-slow install clean-venv

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	if [ -n "$(TORCH_SPEC)" ]; then $(BIN)/pip install "$(TORCH_SPEC)"; fi
	$(BIN)/pip install -e ".[$(EXTRAS)]"
	touch $(STAMP)

install: $(STAMP)

# The baselines and the pretrained KEYIN (docs/models.md) on the 1000 Brownian test clips, KEYIN's own
# argmax offsets (the paper's readout), then keyin-discover on the bundled example video (its turns as
# labels): runs/discover/<date>/<time>/brownian_example.gif/ holds keyframes.json and the pictures; last, a
# short table of the three scores beside the paper's (keyin-report --brief).
# (expanded when the recipe runs, after .venv exists)
SHIPPED = $(shell $(BIN)/python -c 'import keyin.pretrained as p; print(p.FOLDER)')
demo: $(STAMP)
	$(BIN)/keyin-generate dataset=brownian 'splits={test: 1000}'
	$(BIN)/keyin-eval model=random dataset=brownian hydra.run.dir=runs/demo/random
	$(BIN)/keyin-eval model=constant dataset=brownian hydra.run.dir=runs/demo/constant
	$(BIN)/keyin-eval ckpt=pretrained:brownian 'discovery=[offsets]' hydra.run.dir=runs/demo/keyin
	$(BIN)/keyin-discover ckpt=pretrained:brownian input=$(SHIPPED)/brownian_example.gif \
	  labels=$(SHIPPED)/brownian_example_labels.json fps=10
	$(BIN)/keyin-report runs/demo/random runs/demo/constant runs/demo/keyin --brief

# KEYIN with our additions (model=keyin_plus) on Brownian at scale=cpu, both stages, then its keyframe
# F1 on the 1000 test clips; the paper's KEYIN: keyin-train experiment=brownian_keyin model=keyin backbone=paper
# (about 40 minutes on 2 CPU cores; the last line printed is the metrics JSON).
demo-keyin: $(STAMP)
	$(BIN)/keyin-train experiment=brownian_keyin

test: $(STAMP)
	OMP_NUM_THREADS=1 $(BIN)/python -m pytest -q -n auto --dist loadfile --durations=30   # one worker per core, one torch thread per worker (two threads per worker on 2 cores took twice the time), a test file per worker; the 30 slowest tests (issue 44)

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

clean-venv:
	rm -rf $(VENV)
