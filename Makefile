# ForaNav: two commands do all set-up — `make demo` (the main job) and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup test demo bench paper-tests deploy clean

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q

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
	rm -rf $(VENV) runs .pytest_cache
