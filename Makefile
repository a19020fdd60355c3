# ForaNav: two commands do all set-up — `make demo` (the main job) and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup test demo bench paper-tests deploy clean camera-runtime docs

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

test: $(STAMP) camera-runtime
	$(BIN)/python -m pytest -q

# The camera's own runtime (Python 3.7 + numpy 1.16.6 + OpenCV 4.10) in .venv-camera/, built once from the
# machine's Python 3.7 (a stamp file inside makes a second run a no-op); tests/test_camera_runtime.py uses it.
camera-runtime: $(STAMP)
	$(BIN)/python -m host_tools.jevois_host.camera_runtime build

# docs/reference/*.md from the code (commands, flight app PARAMs, camera module parameters)
docs: $(STAMP)
	$(BIN)/python -m host_tools.docs_gen

demo: $(STAMP)
	$(BIN)/foranav demo

bench: $(STAMP)
	$(BIN)/foranav bench sim
	$(BIN)/foranav bench detector

paper-tests: $(STAMP)
	$(BIN)/foranav paper-tests --out runs/paper-tests

deploy: $(STAMP)
	@test -n "$(SD)" || { echo "usage: make deploy SD=/path/to/JEVOIS [DEPLOY_FLAGS=--headless]"; exit 2; }
	$(BIN)/foranav deploy --sd "$(SD)" $(DEPLOY_FLAGS)

clean:
	rm -rf $(VENV) .venv-camera runs .pytest_cache
