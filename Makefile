# mi_brdfs — two commands do everything, set-up included:
#   make render   renders the showcase scene to out/showcase.exr + out/showcase.png
#   make test     runs the test suite
# Both are idempotent: the set-up (system libraries, .venv) runs only when something is missing
# or pyproject.toml changed. The targets that regenerate files (render, bench, validate, audit,
# figures) pass --force: mi-brdfs replaces no file it was not told to.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.mi_brdfs-installed
OUT    := out
SPP    ?= 64
RES    ?= 256
PYTEST_ARGS ?=
# The documents whose quoted figures make validate and make bench fill in from their reports
QUOTING := $(foreach f,README.md $(wildcard docs/*.md),--readme $(f))

.PHONY: all setup system render test test-slow test-full bench validate audit figures docs gallery screenshots clean distclean

all: test

# System libraries drjit needs (libLLVM >= 17, libatomic); installs them where it can.
system:
	@sh tools/setup-system.sh

$(STAMP): pyproject.toml
	@sh tools/setup-system.sh
	@test -x $(PY) || $(PYTHON) -m venv $(VENV) || { \
	  echo "make: could not create $(VENV); install python3-venv (apt-get install python3-venv)"; exit 1; }
	$(PY) -m pip install --disable-pip-version-check -q --upgrade pip
	$(PY) -m pip install --disable-pip-version-check -q -e '.[test,plots,sweep,explore]'
	@touch $@

setup: $(STAMP)

render: $(STAMP)
	@mkdir -p $(OUT)
	$(VENV)/bin/mi-brdfs render showcase -o $(OUT)/showcase.exr --spp $(SPP) -D res=$(RES) --force

# pytest exits 5 when it collected no test: that is a broken suite, not a pass. Two worker
# processes (pytest-xdist), one per core of a 2-core machine; PYTEST_ARGS="-n 8" uses more.
test: $(STAMP)
	@$(PY) -m pytest -n 2 -m "not slow" $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "make test: pytest collected no tests (exit 5)"; exit 1; fi; \
	exit $$rc

# The tests marked slow (tests/tiers.py lists them and says what the quick tier keeps of each;
# the matrix's every cell in every llvm variant): CI runs them after `make test`
test-slow: $(STAMP)
	@$(PY) -m pytest -n 2 -m slow $(PYTEST_ARGS)

# Both tiers in one run
test-full: $(STAMP)
	@$(PY) -m pytest -n 2 $(PYTEST_ARGS)

bench: $(STAMP)
	$(VENV)/bin/mi-brdfs bench --out validation --force $(QUOTING)

# The validation campaign: validation/REPORT.md and validation/figures/ (about 20 min on 2 cores)
validate: $(STAMP)
	$(VENV)/bin/mi-brdfs validate --out validation --force $(QUOTING)

# The audit of every BSDF Mitsuba ships: validation/MITSUBA_AUDIT.md and validation/audit/
# (about 15 min on 2 cores; resumable: results are cached in validation/audit/.cache)
audit: $(STAMP)
	$(VENV)/bin/mi-brdfs audit --out validation --force

# The README's figures
figures: $(STAMP)
	@mkdir -p $(OUT)
	$(VENV)/bin/mi-brdfs render showcase -o $(OUT)/showcase-hq.exr --spp 256 -D res=320 -q --force
	cp $(OUT)/showcase-hq.png docs/showcase.png
	$(VENV)/bin/mi-brdfs render earth -o $(OUT)/earth-hq.exr --spp 512 -D res=256 -D width=768 -q --force
	cp $(OUT)/earth-hq.png docs/earth.png
	$(PY) tools/thinfilm_figure.py --res 128 --spp 48 --workers 2 --check-spp 512

# The plugin reference, docs/plugins/*.md, generated from the plugins' docstrings
docs: $(STAMP)
	$(PY) -m mi_brdfs.docgen

# The screenshots of docs/explore.md (docs/explore/*.png): the page of mi-brdfs explore in
# headless Chromium (Debian's chromium and chromium-driver, which the system step installs)
screenshots: $(STAMP)
	$(PY) tools/explore_screenshots.py

# A gallery of every plugin and form at a few parameter values (docs/gallery.png)
gallery: $(STAMP)
	$(PY) -m mi_brdfs.gallery --out docs/gallery.png

clean:
	rm -rf $(OUT) .pytest_cache
	find . -name __pycache__ -type d -prune -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV)

# Eradiate's rtls values, validation/eradiate/rtls.json (tests/plugins/test_rtls_eradiate.py
# compares against them): its Mitsuba fork in a virtual environment of its own, .venv-eradiate
# (it cannot share a process with the project's Mitsuba), at the versions the committed table
# was made with (the fork does not pin drjit)
ERADIATE_PINS := eradiate-mitsuba==0.5.0 drjit==1.2.0
.PHONY: eradiate-values
eradiate-values:
	@test -x .venv-eradiate/bin/python || $(PYTHON) -m venv .venv-eradiate
	.venv-eradiate/bin/python -m pip install --disable-pip-version-check -q $(ERADIATE_PINS)
	.venv-eradiate/bin/python validation/eradiate/values.py

# The audit of Eradiate's fork (Mitsuba's built-ins as the fork ships them, and Eradiate's
# plugins): validation/audit/eradiate.md, validation/audit/eradiate/ (findings.json, the
# reproducers, the resumable cache .cache). Sets up .venv-eradiate with ERADIATE_PINS, NumPy and
# this package without its dependencies (the fork is its Mitsuba)
.PHONY: audit-eradiate
audit-eradiate:
	@test -x .venv-eradiate/bin/python || $(PYTHON) -m venv .venv-eradiate
	.venv-eradiate/bin/python -m pip install --disable-pip-version-check -q $(ERADIATE_PINS) numpy
	.venv-eradiate/bin/python -m pip install --disable-pip-version-check -q --no-deps -e .
	.venv-eradiate/bin/mi-brdfs audit --out validation --force
