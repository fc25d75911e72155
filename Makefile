# The two commands of the README, each doing its own set-up:
#   make book   build the book, executing every chapter at the smoke profile (_build/html),
#               and its downloads (_build/html/downloads: wheel, pins, chapters for Colab)
#   make test   ruff, every notebook and the unit tests (nbmake; the chapters first, so the
#               longest items start early on the workers; tests marked with one xdist_group
#               run on one worker, where they share compiled programs)
#   make grid   start the background queue of long runs: a worker per core at idle priority
#               in a worktree of HEAD (python -m sgb grid status|land|stop; sgb/grid.py)
#   make reproduce EXPERIMENT=... ARGS=...   one experiment, in the same environment (results
#               in $SGB_RESULTS, else ./sgb-results; ARGS=--maintainer-write-committed writes
#               the committed results/ instead)

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.stamp
JOBS ?= 2

# Recipes run with the virtualenv first on PATH; chapters run at the smoke profile.
export PATH := $(CURDIR)/$(BIN):$(PATH)
export VIRTUAL_ENV := $(CURDIR)/$(VENV)
export SGB_PROFILE := smoke

.PHONY: venv test book grid reproduce clean distclean

venv: $(STAMP)

$(STAMP): requirements.txt pyproject.toml
	$(PYTHON) -c 'import sys; sys.exit(not (3, 11) <= sys.version_info[:2] <= (3, 13))' \
	    || { echo "the book needs Python 3.11, 3.12 or 3.13: make PYTHON=python3.13 ..."; exit 1; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --disable-pip-version-check -q -r requirements.txt
	$(BIN)/python -m pip install --disable-pip-version-check -q --no-deps -e '.[book,test]'
	touch $@

test: venv
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m pytest -n $(JOBS) --dist loadgroup --nbmake --nbmake-timeout=900 book tests

# The smoke build compiles as fast as the tests do (conftest.FAST_COMPILE_FLAGS).
# Then the downloads of "Run it yourself": the wheel, the pins, and every chapter with the
# numbers, figure numbers, citations and captions of the build written in (sgb.colab; the
# build fails if any role text is left).
book: venv
	XLA_FLAGS="$$($(BIN)/python -c 'import conftest, os; print(os.environ["XLA_FLAGS"])')" \
	    $(BIN)/jupyter-book build . -W --keep-going
	rm -rf _build/html/downloads
	$(BIN)/python -m pip wheel -q --no-deps --disable-pip-version-check -w _build/html/downloads .
	cp requirements.txt _build/html/downloads/
	$(BIN)/python -m sgb.colab _build _build/html/downloads

grid: venv
	$(BIN)/python -m sgb grid start

# make reproduce EXPERIMENT=fig3 ARGS="--profile cpu --env ant"   (python -m sgb reproduce --help)
reproduce: venv
	$(BIN)/python -m sgb reproduce $(EXPERIMENT) $(ARGS)

clean:
	rm -rf _build .pytest_cache .ruff_cache *.egg-info
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -prune -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV)
