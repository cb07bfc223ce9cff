# The two commands of the README. Each one creates .venv if it is missing and installs the
# package with what it needs; nothing but Python 3.11, pip (and make) is required.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: report test test-slow install clean bench docs

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): $(PY) pyproject.toml
	$(PY) -m pip install --quiet -e '.[engines,test,parquet,dask]'
	@touch $(STAMP)

install: $(STAMP)

report: $(STAMP)
	$(PY) -m rockbench report --out reports

test: $(STAMP)
	$(PY) -m pytest -q -n 2

# the slow tests (exhaustive maps, committed maps re-run, full reports): about an hour on 2 cores
test-slow: $(STAMP)
	$(PY) -m pytest -q -n 2 -m slow --run-slow

docs: $(STAMP)
	$(PY) tools/render_docs.py

bench: $(STAMP)
	$(PY) benchmarks/run.py
	$(PY) benchmarks/loop_overhead.py
	$(PY) benchmarks/compiled_analytic.py
	$(PY) benchmarks/analytic_floor.py
	$(PY) benchmarks/adaptive_map.py --axes both
	$(PY) benchmarks/map_cell.py
	$(PY) benchmarks/startup.py

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info
