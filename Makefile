# `make demo` and `make test` work on a fresh machine: each creates .venv when missing and installs the project.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.clone2d-installed

.PHONY: demo test test-all bench browser-test lint clean

# The optional `extract` extra: the few packages mediapipe really needs first, then mediapipe itself last, with
# --no-deps (its own pins pull jax and a second OpenCV) and --no-warn-conflicts (else pip's resolver prints a red
# error line about exactly those skipped pins on every fresh install).
$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -e ".[dev,fast]"
	$(PY) -m pip install -q --disable-pip-version-check absl-py attrs flatbuffers "protobuf<5"
	$(PY) -m pip install -q --disable-pip-version-check --no-deps --no-warn-conflicts mediapipe==0.10.14
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
