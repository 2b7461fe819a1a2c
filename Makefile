# Set-up and routine jobs. `make demo` and `make test` do all set-up on a fresh
# Debian 12 machine with Python >= 3.11.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SAMPLE ?= tests/data/exif/87_OSError.jpg
OUT    ?= out

.PHONY: demo test bench check-python clean

demo: $(STAMP)
	$(PY) -m forensics_core analyze $(SAMPLE) --out $(OUT)
	@echo "outputs: $(OUT)/$(basename $(notdir $(SAMPLE)))/"

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) benchmarks/lens.py

check-python:
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "forensics needs Python >= 3.11; set PYTHON=python3.11 or newer")'
	@$(PYTHON) -c 'import venv, ensurepip' 2>/dev/null || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    apt-get update -qq && apt-get install -y -qq python3-venv; \
	  else echo "missing system package: python3-venv (sudo apt-get install python3-venv)"; exit 1; fi; }

$(PY): | check-python
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
