# Two commands: `make demo` runs the main job, `make test` runs the suite (every lane; `make test-fast`: the unit
# lane only). Both set up .venv on first use (idempotent): pip install -r requirements.txt, the package itself
# (editable, `pip install -e .`: its manifest is at the repository root) and our ROS 2 interfaces built from the wheels.
SHELL := /bin/bash
PYTHON ?= python3
VENV := $(CURDIR)/.venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.requirements.stamp
# The ROS wheels' .pth bootstrapper re-executes Python once to set LD_LIBRARY_PATH;
# an inherited flag would make it skip that step.
unexport _ROS_WHEELS_BOOTSTRAP_COMPLETE
export PIP_DISABLE_PIP_VERSION_CHECK := 1

.PHONY: setup demo test test-fast docs-slow lint browser bench bench-deps interfaces clean

KERNELS := $(VENV)/.kernels.stamp
setup: $(STAMP) interfaces $(KERNELS) browser

$(STAMP): requirements.txt setup.py package.xml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@echo "[setup] installing pinned requirements into .venv (first run takes a few minutes)"
	@$(PY) -m pip install --progress-bar off -q -r requirements.txt
	@$(PY) -m pip install --progress-bar off -q --no-deps -e .
	@touch $(STAMP)

# numba compiles the planning kernels at first use and caches them on disk: done here once per source change, so
# no node start, request or test pays the ~1 min compile (maru_planner/planning/warm_up.py)
$(KERNELS): $(STAMP) $(shell find maru_planner -name '*.py')
	@echo "[setup] compiling the planning kernels (about two minutes after an install or a source change)"
	@$(PY) -m maru_planner.planning.warm_up
	@touch $@

# Debian's chromium for the browser tests (test/unit/web/); skipped with one line where it cannot be installed
browser:
	@sh scripts/install_browser.sh

interfaces: $(STAMP)
	@VENV=$(VENV) bash scripts/build_interfaces.sh

demo: setup
	@$(PY) -m maru_planner.ros.demo

# every lane (a lane's failure does not skip the others), its time printed; a lane's modules are spread over
# TEST_WORKERS processes (pytest-xdist, a module stays on one worker: its node fixtures), then its modules marked
# serial (bursts, storms and admission timings that load the machine on purpose) run alone; exit code 5 = none
LANES := unit ros hostile architecture docs
# one worker when the user exported ROS_DOMAIN_ID (the tests then share that domain), else two on free domains
TEST_WORKERS ?= $(if $(ROS_DOMAIN_ID),1,2)
test: setup
	@status=0; for lane in $(LANES); do \
		start=$$(date +%s); echo "[test] lane $$lane (test/$$lane)"; \
		$(PY) -m pytest -p no:cacheprovider -n $(TEST_WORKERS) --dist loadfile -m "not serial" test/$$lane; \
		code=$$?; [ $$code = 0 ] || [ $$code = 5 ] || status=1; \
		if grep -rqs "mark.serial" test/$$lane; then \
			$(PY) -m pytest -p no:cacheprovider -m serial test/$$lane || status=1; \
		fi; \
		echo "[test] lane $$lane: $$(( $$(date +%s) - start )) s"; \
	done; exit $$status

# the documentation's slow blocks too (ROS examples, benchmark runs): about ten minutes
docs-slow: setup
	@MARU_DOCS_SLOW=1 $(PY) -m pytest -p no:cacheprovider test/docs

# the unit lane: no rclpy node, colcon build or hostile-input sweep (test/ros/, test/hostile/, test/architecture/)
test-fast: setup
	@$(PY) -m pytest -p no:cacheprovider test/unit

lint: setup
	@$(VENV)/bin/ruff check maru_planner bench test scripts launch
	@$(VENV)/bin/ruff format --check maru_planner bench test scripts launch setup.py
	@$(VENV)/bin/mypy

bench-deps: setup
	@$(PY) -m pip install --progress-bar off -q -r bench/requirements.txt
	@$(PY) -m pip install --progress-bar off -q --no-deps -r bench/requirements-nodeps.txt

bench: bench-deps
	@for b in bench/*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

# what the build (setup, colcon, pip's egg-info), the demo and pytest write into the tree; .venv stays
clean:
	rm -rf build install log demo_output .pytest_cache .ruff_cache .mypy_cache .hypothesis bench/results/quick
	find . -path ./.venv -prune -o -name '*.egg-info' -type d -prune -exec rm -rf {} +
