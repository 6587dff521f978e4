# One-command entry points for a fresh machine (see README).
PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
STAMP   = $(VENV)/.installed
# an interpreter pyenv holds but has not activated (PYTHON=python3.12 on these machines): its own path
PY     := $(shell $(PYTHON) -c 'import sys; print(sys.executable)' 2>/dev/null || \
            (v=$$(pyenv versions --bare 2>/dev/null | grep -E "^$(subst python,,$(PYTHON))(\.|$$)" | tail -n 1); \
             [ -n "$$v" ] && echo "$$(pyenv prefix $$v)/bin/python"))
# the real ros2 command line and launch system (wheels of their Jazzy sources), for the workspace tests
ROS2_TOOLS ?= $(wildcard ../shared/ros2-tools)

.PHONY: setup run test test-core test-py312 ros2-tools bench report calibrate-setup profile-setup cluster-setup \
        mutation-setup mutation clean

setup: $(STAMP)

$(STAMP): pyproject.toml requirements.lock
	@[ -n "$(PY)" ] || { echo "make: no interpreter $(PYTHON) (give PYTHON=python3.11 or python3.12)"; exit 2; }
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --disable-pip-version-check -q -r requirements.lock
	$(BIN)/pip install --disable-pip-version-check -q --no-deps --no-build-isolation -e .
	touch $(STAMP)

run: setup
	$(BIN)/homeo-launch sim --iterations 5000 --seed 0 --save-q out/q-seed0.json
	$(BIN)/homeo-sim run --iterations 5000 --seeds 20

# two workers (pytest-xdist): the graph tests mostly wait on discovery and timeouts; each worker has
# its own ROS domains and data directory (tests/rosgraph.py, tests/conftest.py)
WORKERS ?= 2

test: setup ros2-tools profile-setup calibrate-setup cluster-setup
	$(BIN)/python -m pytest -q -n $(WORKERS) --dist loadgroup

# the core, the graph's equivalence with the in-process runner, and the launch tests (ros2 launch in a
# colcon workspace): what .ci/run runs on the second Python
CORE_TESTS = tests/test_golden.py tests/test_graph_stages.py tests/test_determinism.py tests/test_scenario.py \
             tests/test_objectq.py tests/test_reward.py tests/test_motivation.py tests/test_world_conformance.py \
             tests/test_ros2_workspace.py tests/test_example_world.py
test-core: setup ros2-tools
	$(BIN)/python -m pytest -q -n $(WORKERS) --dist loadgroup $(CORE_TESTS)

test-py312:
	$(MAKE) test-core PYTHON=python3.12 VENV=.venv312

ros2-tools: $(VENV)/.ros2-tools

$(VENV)/.ros2-tools: $(STAMP) tools/requirements-ros2.lock
	@if [ -z "$(ROS2_TOOLS)" ]; then echo "make: no ros2-tools (../shared/ros2-tools): the ROS 2 workspace tests will skip"; \
	else $(ROS2_TOOLS)/install.sh $(VENV) && \
	  $(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-ros2.lock && touch $@; fi

bench: setup
	$(BIN)/homeo-sim bench
	$(BIN)/homeo-launch bench

report: setup
	$(BIN)/homeo-sim report --out out/report --seeds 10

# the searches' tool dependency (tools/calibrate.py --joint, tools/error_search.py; docs/FIDELITY.md), not the
# runtime's; `make test` installs it so that their tests run
calibrate-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-calibrate.lock

# the profiler of `homeo-launch bench --profile` (a tool dependency: py-spy; its test runs with `make test`)
profile-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-profile.lock

# the mutation tester of `make mutation` (a tool dependency: mutmut; not part of `make test`)
mutation-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-mutation.lock

# a benchmark, not a test: the core's mutation score per module (tools/mutation.py; results kept in out/mutation/,
# a rerun tests only what changed). MUTATION_JOBS mutmut children, MUTATION_BUDGET wall seconds per module.
MUTATION_JOBS ?= 1
MUTATION_BUDGET ?= 1800
mutation: mutation-setup
	$(BIN)/python tools/mutation.py --jobs $(MUTATION_JOBS) --budget $(MUTATION_BUDGET) $(MODULES)

# the cluster extra (--cluster ADDRESS: Ray); `make test` installs it so that the cluster tests run
cluster-setup: setup
	$(BIN)/pip install --disable-pip-version-check -q --no-deps -r tools/requirements-cluster.lock

clean:
	rm -rf $(VENV) .venv312 build install log src/*.egg-info
