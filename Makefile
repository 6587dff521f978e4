# One-command entry points for a fresh machine (see README).
PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
STAMP   = $(VENV)/.installed

.PHONY: setup run test bench report calibrate-setup profile-setup clean

setup: $(STAMP)

$(STAMP): pyproject.toml requirements.lock
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --disable-pip-version-check -q -r requirements.lock
	$(BIN)/pip install --disable-pip-version-check -q --no-deps --no-build-isolation -e .
	touch $(STAMP)

run: setup
	$(BIN)/homeo-launch sim --iterations 5000 --seed 0 --save-q out/q-seed0.json
	$(BIN)/homeo-sim run --iterations 5000 --seeds 20

test: setup profile-setup
	$(BIN)/python -m pytest -q

bench: setup
	$(BIN)/homeo-sim bench
	$(BIN)/homeo-launch bench

report: setup
	$(BIN)/homeo-sim report --out out/report --seeds 10

# the joint search's tool dependency (tools/calibrate.py --joint; docs/FIDELITY.md), not the runtime's
calibrate-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-calibrate.lock

# the profiler of `homeo-launch bench --profile` (a tool dependency: py-spy; its test runs with `make test`)
profile-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-profile.lock

clean:
	rm -rf $(VENV) build src/*.egg-info
