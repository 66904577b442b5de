# `make demo` and `make test` work on a fresh machine: each creates .venv when missing and installs the project.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.clone2d-installed

.PHONY: demo test test-all bench browser-test lint clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -e ".[dev]"
	# The optional `extract` extra: mediapipe without its pins, plus the few packages it really needs.
	$(PY) -m pip install -q --disable-pip-version-check --no-deps mediapipe==0.10.14
	$(PY) -m pip install -q --disable-pip-version-check absl-py attrs flatbuffers "protobuf<5"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/clone demo

test: $(STAMP)
	$(PY) -m pytest -q

test-all: $(STAMP)
	$(PY) -m pytest -q -m ""

bench: $(STAMP)
	$(PY) -m bench.run

browser-test: $(STAMP)
	$(PY) -m pytest -q -m browser

lint: $(STAMP)
	$(VENV)/bin/ruff check pose_io retarget clone tests bench examples

clean:
	rm -rf $(VENV) build *.egg-info
