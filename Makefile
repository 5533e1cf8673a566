# Every target sets up .venv itself on a fresh machine (Python >= 3.11 on PATH as python3).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: test docs report report-quick bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest

# The documentation site under docs/_build/html (the gallery's examples run: a few minutes).
docs: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[docs]'
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

# The report's bifurcation ensemble runs both linear solvers: it adds PARDISO (x86_64).
report: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[fast]'
	$(BIN)/soilwater report

# A first look: every study coarser, into reports-quick/ (never over reports/).
report-quick: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[fast]'
	$(BIN)/soilwater report --quick

# The benchmark adds the optional PARDISO solver (x86_64; SuperLU elsewhere). OpenBLAS
# reads OPENBLAS_CORETYPE and OPENBLAS_L2_SIZE when NumPy loads it, so they are unset for
# this command only: the bench's dgemm and NumPy work run on this CPU's own kernels.
bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[fast]'
	env -u OPENBLAS_CORETYPE -u OPENBLAS_L2_SIZE $(BIN)/soilwater bench

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis
