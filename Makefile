# The two set-up commands of the README. Each creates its own virtual environment, then compiles
# the numba kernels once (cached on disk beside the package) so that no command pays for it.
# -P: the installed package, not the source tree in the current folder (the demo venv's copy is
# the one `usar-arm` runs; warming the tree's instead left the demo's first plan compiling, 7 s).
PYTHON ?= python3
DEMO_VENV := .venv
TEST_VENV := .venv-test
DOCS_VENV := .venv-docs
WARM_UP := from usar_arm.planning.compiled import warm_up; warm_up(); \
	from usar_arm.workspace.kernels import warm_up; warm_up()

.PHONY: demo test test-all test-slow lint typecheck docs bench bench-quick load soak clean \
	ros-setup ros1-system ros1-setup

$(DEMO_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(DEMO_VENV)
	$(DEMO_VENV)/bin/pip install --quiet --upgrade pip
	$(DEMO_VENV)/bin/pip install --quiet .
	$(DEMO_VENV)/bin/python -P -c "$(WARM_UP)"
	touch $@

$(TEST_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(TEST_VENV)
	$(TEST_VENV)/bin/pip install --quiet --upgrade pip
	$(TEST_VENV)/bin/pip install --quiet -e ".[test,viz,ray,ros]"
	$(TEST_VENV)/bin/python -P -c "$(WARM_UP)"
	$(TEST_VENV)/bin/usar-arm ros --setup
	touch $@

# The ROS 2 message packages the package index lacks (tf2_msgs, control_msgs), built once into
# ~/.cache/usar-arm/ros-interfaces for the test venv (about 40 s on 2 cores; needs a C++
# compiler). `make test` does it; this target redoes it after the cache was cleared.
ros-setup: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/usar-arm ros --setup

# Debian's ROS 1 and the tools that judge the ROS 1 node (tests/ros1: robot_state_publisher,
# RViz under Xvfb, rosbag, view_frames): installed with apt-get where this runs as root (CI, a
# fresh Debian 12: about 360 MB, once), else said in one line (the ROS 1 tests then skip).
ros1-system: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python tools/ros1_debian.py

# The ROS 1 environment (a venv of Debian's interpreter, control_msgs generated; seconds).
ros1-setup: ros1-system
	$(TEST_VENV)/bin/usar-arm ros --ros1 --setup

demo: $(DEMO_VENV)/.installed
	$(DEMO_VENV)/bin/usar-arm demo

# The default suite: unit, integration and end-to-end tests against the embedded simulator
# (everything not marked slow), on both cores. The consumer tests (tests/consumers, about 100 s
# run alone) drive Tesseract in its own venv, bench/.venvs/tesseract (created here once, about
# 2 minutes and 320 MB; never a dependency of the package).
test: $(TEST_VENV)/.installed ros1-system
	$(PYTHON) bench/peers/venvs.py --only tesseract
	$(TEST_VENV)/bin/python -m pytest -n 2 -m "not slow and not realtime" tests

# The long campaigns and slow end-to-end runs (marked slow): the 10-minute soak, the 64-client
# load, the 1,000-plan invariants, the 1,000,000-configuration collision agreement, fuzzing, the
# kill campaign, the demo, the examples and the quick benchmark (which needs the peers' venvs in
# bench/.venvs). Three workers: the "simulator-load" group (soak, load) is mostly asleep. Then the
# realtime tests (the demo's 100 Hz rate and 10 mrad tracking) alone, on an otherwise idle machine.
test-slow: $(TEST_VENV)/.installed
	$(PYTHON) bench/peers/venvs.py
	$(TEST_VENV)/bin/python -m pytest -n 3 --dist loadgroup -m "slow and not realtime" tests
	$(TEST_VENV)/bin/python -m pytest -n 0 -m realtime tests

test-all: test test-slow

# ruff on everything, mypy (standard mode, every function annotated) on the package.
lint: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/ruff check usar_arm tests bench tools fuzz examples
	$(TEST_VENV)/bin/mypy usar_arm

typecheck: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/mypy usar_arm

# The documentation site (mkdocs.yml) into build/site, with --strict: a broken link or anchor, or
# a public name without a docstring (tools/docs_hooks.py), fails it. Its own venv: mkdocstrings
# reads the package's source with griffe and imports nothing, so the package goes in without its
# dependencies (no Pinocchio, OMPL or MuJoCo to download for the docs).
DOCS_PACKAGES := "mkdocs>=1.6,<2" "mkdocs-material>=9.5,<10" "mkdocstrings[python]>=0.27"

$(DOCS_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(DOCS_VENV)
	$(DOCS_VENV)/bin/pip install --quiet --upgrade pip
	$(DOCS_VENV)/bin/pip install --quiet $(DOCS_PACKAGES)
	$(DOCS_VENV)/bin/pip install --quiet --no-deps -e .
	touch $@

docs: $(DOCS_VENV)/.installed
	NO_MKDOCS_2_WARNING=1 $(DOCS_VENV)/bin/mkdocs build --strict --site-dir build/site

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

# The simulator alone under 64 clients for 60 s (48 arms streaming ACT at 100 Hz, 16 P3ATs driving
# at 20 Hz in the rooms world), and a 10-minute soak (tools/README.md); run them on an otherwise
# idle machine: they measure wall-clock rates.
load: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python tools/load_sim.py --clients 64 --platforms 16 --rate 100 \
		--seconds 60 --json bench/results/load.json

soak: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python tools/soak_sim.py --minutes 10 --json bench/results/soak.json

clean:
	rm -rf $(DEMO_VENV) $(TEST_VENV) $(DOCS_VENV) build *.egg-info
