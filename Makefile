# The two set-up commands of the README. Each creates its own virtual environment.
PYTHON ?= python3
DEMO_VENV := .venv
TEST_VENV := .venv-test

.PHONY: demo test bench bench-quick load soak clean

$(DEMO_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(DEMO_VENV)
	$(DEMO_VENV)/bin/pip install --quiet --upgrade pip
	$(DEMO_VENV)/bin/pip install --quiet .
	touch $@

$(TEST_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(TEST_VENV)
	$(TEST_VENV)/bin/pip install --quiet --upgrade pip
	$(TEST_VENV)/bin/pip install --quiet -e ".[test,viz,ray]"
	touch $@

demo: $(DEMO_VENV)/.installed
	$(DEMO_VENV)/bin/usar-arm demo

# Three workers on two cores: one of them runs the "simulator-load" group (the 10-minute soak, mostly
# asleep, then the 64-client load), the other two the rest.
# The peers' venvs (bench/.venvs) let the quick benchmark in the suite run them too; a peer that
# cannot be installed is reported as skipped by the benchmark, not a failure here.
test: $(TEST_VENV)/.installed
	$(PYTHON) bench/peers/venvs.py || echo "note: some benchmark peers could not be installed"
	$(TEST_VENV)/bin/python -m pytest -n 3 --dist loadgroup tests

# Benchmarks (bench/README-peers.md, bench/results/README.md). Each peer gets its own venv in
# bench/.venvs (created once by venvs.py; mplib needs numpy < 2); usar-arm runs in the test venv.
BENCH_QUICK_OUT ?= build/bench-quick

bench: $(TEST_VENV)/.installed
	$(PYTHON) bench/peers/venvs.py
	$(TEST_VENV)/bin/python bench/run.py --out bench/results

bench-quick: $(TEST_VENV)/.installed
	$(PYTHON) bench/peers/venvs.py
	$(TEST_VENV)/bin/python bench/run.py --quick --out $(BENCH_QUICK_OUT) \
		--problems $(BENCH_QUICK_OUT)/problems

# The simulator alone under 64 clients x 100 Hz for 60 s, and a 10-minute soak (tools/README.md);
# run them on an otherwise idle machine: they measure wall-clock rates.
load: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python tools/load_sim.py --clients 64 --rate 100 --seconds 60 \
		--json bench/results/load.json

soak: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python tools/soak_sim.py --minutes 10 --json bench/results/soak.json

clean:
	rm -rf $(DEMO_VENV) $(TEST_VENV) build *.egg-info
