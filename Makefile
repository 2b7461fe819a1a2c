# Set-up and routine jobs. `make demo` and `make test` do all set-up on a fresh
# Debian 12 machine with Python >= 3.11.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SAMPLES ?= tests/data/calibration/left01.jpg tests/data/exif/87_OSError.jpg
OUT    ?= out

# WeasyPrint needs Pango (and HarfBuzz' subsetter, and a font); the tests use
# poppler's pdfsig, pdftoppm, pdftotext, pdfinfo and pdfdetach, and openssl.
SYSTEM_PACKAGES := libpango-1.0-0 libpangoft2-1.0-0 libharfbuzz-subset0 fonts-dejavu-core poppler-utils openssl libimage-exiftool-perl

VALIDATION ?= out/validation
REAL ?= ../shared/data/real

.PHONY: demo test validate validate-real validate-lens-splices validate-innocent-processing validate-realistic calibrate bench bytecode check-python system-packages clean

demo: bytecode
	$(PY) -m forensics_core analyze $(SAMPLES) --out $(OUT) --case-id DEMO-1 --exhibit-id 1
	@for photo in $(SAMPLES); do \
	  $(PY) -m forensics_core verify $(OUT)/$$(basename $${photo%.*}) --evidence $$photo || exit 1; done
	@echo "outputs: $(foreach p,$(SAMPLES),$(OUT)/$(basename $(notdir $(p)))/) (findings.json, report.html, report.pdf, manifest.json, manifest.json.p7s)"

# The tests share nothing (temporary folders, ports chosen by the system), so
# they run in one process per core, at most 4 (each may hold several hundred
# MB while it analyses a large photo): on 2 cores 7.5 min instead of 11.5.
test: bytecode
	$(PY) -m pytest -n auto --maxprocesses 4

# The built-in synthetic suite; its record becomes the one shipped with the
# release, which every report states unless the examiner names another.
validate: bytecode
	$(PY) -m forensics_core validate synthetic --out $(VALIDATION)
	cp $(VALIDATION)/validation.json forensics_core/validation/synthetic.json
	@echo "shipped record: forensics_core/validation/synthetic.json; page: $(VALIDATION)/validation.html"

# Every set under $(REAL) (each folder with a truth.csv) in one record, shipped
# beside the synthetic one; reports state it first. Without the corpus there is
# nothing to measure, which is not an error.
validate-real: $(if $(wildcard $(REAL)),bytecode)
	@if [ ! -d "$(REAL)" ]; then echo "the real corpus is absent ($(REAL)): nothing validated"; exit 0; fi; \
	$(PY) -m forensics_core validate "$(REAL)" --out $(OUT)/validation-real && \
	cp $(OUT)/validation-real/validation.json forensics_core/validation/real.json && \
	echo "shipped record: forensics_core/validation/real.json; page: $(OUT)/validation-real/validation.html"

# The lens-distortion paper's three kinds of splice (another camera's piece, a
# piece moved to another distance from the centre, a rescaled one) forged from
# the real corpus's building photos into $(OUT)/validation-lens-splices/cases,
# with a control per host; nothing is shipped. No corpus, nothing to build.
validate-lens-splices: $(if $(wildcard $(REAL)),bytecode)
	@if [ ! -d "$(REAL)" ]; then echo "the real corpus is absent ($(REAL)): no lens splices built"; exit 0; fi; \
	$(PY) -m forensics_core validate lens-splices --corpus "$(REAL)" --out $(OUT)/validation-lens-splices && \
	echo "page: $(OUT)/validation-lens-splices/validation.html; cases and recipes: $(OUT)/validation-lens-splices/cases/"

# Splices from another camera's photo, copy-moves and removals with
# object-like outlines, forged from the same building photos into
# $(OUT)/validation-realistic/cases beside controls saved the same way (360
# photos, about 20 min on 2 cores). Its record (no photo) is shipped and
# calibrated on beside the real one. No corpus, nothing to build.
validate-realistic: $(if $(wildcard $(REAL)),bytecode)
	@if [ ! -d "$(REAL)" ]; then echo "the real corpus is absent ($(REAL)): no forgeries built"; exit 0; fi; \
	$(PY) -m forensics_core validate realistic --corpus "$(REAL)" --out $(OUT)/validation-realistic && \
	cp $(OUT)/validation-realistic/validation.json forensics_core/validation/realistic.json && \
	echo "shipped record: forensics_core/validation/realistic.json; page: $(OUT)/validation-realistic/validation.html; cases and recipes: $(OUT)/validation-realistic/cases/"

# The same building photos only processed as editors and platforms do (lens
# correction, rotation, keystone, crop, resizing, levels, sharpening, noise
# reduction, platform re-encodes, PNG export), all authentic, made into
# $(OUT)/validation-innocent-processing/cases: the detectors' false alarms on
# innocent processing. Its record (figures, hashes and recipes, no photo) is
# shipped for the report's error-rate section. No corpus, nothing to build.
validate-innocent-processing: $(if $(wildcard $(REAL)),bytecode)
	@if [ ! -d "$(REAL)" ]; then echo "the real corpus is absent ($(REAL)): no processed photos built"; exit 0; fi; \
	$(PY) -m forensics_core validate innocent-processing --corpus "$(REAL)" --out $(OUT)/validation-innocent-processing && \
	cp $(OUT)/validation-innocent-processing/validation.json forensics_core/validation/innocent_processing.json && \
	echo "page: $(OUT)/validation-innocent-processing/validation.html; cases and recipes: $(OUT)/validation-innocent-processing/cases/"

# Likelihood-ratio calibrators fitted on the shipped real record and the
# realistic one made from the same corpus (refresh them first with
# validate-real and validate-realistic), folds grouped by source photo; only
# detectors informative on the real sets are fused. The same records give
# the same calibrators.
calibrate: bytecode
	$(PY) -m forensics_core calibrate forensics_core/validation/real.json forensics_core/validation/realistic.json \
	  --out forensics_core/calibration/real.json

bench: bytecode
	$(PY) benchmarks/lens.py
	$(PY) benchmarks/report.py
	$(PY) benchmarks/end_to_end.py
	$(PY) benchmarks/report_stages.py

check-python:
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "forensics needs Python >= 3.11; set PYTHON=python3.11 or newer")'
	@$(PYTHON) -c 'import venv, ensurepip' 2>/dev/null || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    apt-get update -qq && apt-get install -y -qq python3-venv; \
	  else echo "missing system package: python3-venv (sudo apt-get install python3-venv)"; exit 1; fi; }

system-packages:
	@missing=""; \
	libs=$$( { ldconfig -p || /sbin/ldconfig -p; } 2>/dev/null ); \
	echo "$$libs" | grep -q 'libpango-1.0.so.0' || missing="$$missing pango"; \
	echo "$$libs" | grep -q 'libharfbuzz-subset.so.0' || missing="$$missing harfbuzz-subset"; \
	for tool in pdfsig pdftoppm pdftotext pdfinfo pdfdetach openssl fc-list exiftool; do \
	  command -v $$tool >/dev/null || missing="$$missing $$tool"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(SYSTEM_PACKAGES) >/dev/null; \
	  else echo "missing system packages (for$$missing): sudo apt-get install $(SYSTEM_PACKAGES)"; exit 1; fi; \
	fi

$(PY): | check-python
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY) system-packages
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

# An editable install leaves the project's own modules uncompiled, and where
# Python may not write bytecode (PYTHONDONTWRITEBYTECODE, a read-only clone)
# every command compiled them again: 0.14 s of a 2 s run. A wheel is compiled
# when installed; this does the same. Up-to-date files are skipped.
bytecode: $(STAMP)
	@$(PY) -m compileall -q forensics_core forensics_plugins >/dev/null

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
