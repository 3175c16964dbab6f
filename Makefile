# The two set-up commands of the README. Each creates its own virtual environment.
PYTHON ?= python3
DEMO_VENV := .venv
TEST_VENV := .venv-test

.PHONY: demo test bench bench-quick clean

$(DEMO_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(DEMO_VENV)
	$(DEMO_VENV)/bin/pip install --quiet --upgrade pip
	$(DEMO_VENV)/bin/pip install --quiet .
	touch $@

$(TEST_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(TEST_VENV)
	$(TEST_VENV)/bin/pip install --quiet --upgrade pip
	$(TEST_VENV)/bin/pip install --quiet -e ".[test]"
	touch $@

demo: $(DEMO_VENV)/.installed
	$(DEMO_VENV)/bin/usar-arm demo

test: $(TEST_VENV)/.installed
	$(TEST_VENV)/bin/python -m pytest -n 2 tests

clean:
	rm -rf $(DEMO_VENV) $(TEST_VENV) build *.egg-info
