# The two commands of the README. Each one creates .venv if it is missing and installs the
# package with what it needs; nothing but Python 3.11, pip (and make) is required.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: report test test-slow install clean bench docs export-readers test-export-readers

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

# The readers of the fragility exports, each in its own venv (docs/fragility-export.md): pelicun
# 3.10 pins SciPy < 1.16 and pandas < 3, so it cannot share .venv; openquake.engine's GDAL
# requirement builds from source and needs a system GDAL of its version (3.13), so the engine is
# installed without it (its NRML readers do not use GDAL) and its other requirements from PyPI.
OQ_VERSION      := 3.26.2
PELICUN_VERSION := 3.10.0
OQ_DEPS := "numpy>=2.2.6" "scipy>=1.7" "pandas>=2.2.3" "h5py>=3.13" "django>=4.2,<5" psutil \
           requests "pyzmq~=26.0.3" "h3>=4.4" "decorator~=5.1.1" "pillow~=12.2.0" \
           "toml~=0.10.2" "numba~=0.61.2" "alpha_shapes~=1.1.0" "docutils~=0.19.0" \
           "django_cors_headers~=4.3.1" "pyproj~=3.7.2" "geopandas~=1.1.4" "fiona~=1.10.1"

.venv-pelicun/.installed:
	$(PYTHON) -m venv .venv-pelicun
	.venv-pelicun/bin/python -m pip install --quiet "pelicun==$(PELICUN_VERSION)"
	@touch $@

.venv-openquake/.installed:
	$(PYTHON) -m venv .venv-openquake
	.venv-openquake/bin/python -m pip install --quiet --no-deps "openquake.engine==$(OQ_VERSION)"
	.venv-openquake/bin/python -m pip install --quiet $(OQ_DEPS)
	@touch $@

export-readers: .venv-pelicun/.installed .venv-openquake/.installed

# the exports loaded by both tools' own readers (tests/test_fragility_export.py; about 40 s once
# built, a few minutes on the first run after a build)
test-export-readers: $(STAMP) export-readers
	ROCKBENCH_OPENQUAKE_PYTHON=.venv-openquake/bin/python \
	ROCKBENCH_PELICUN_PYTHON=.venv-pelicun/bin/python \
	$(PY) -m pytest -q tests/test_fragility_export.py

clean:
	rm -rf $(VENV) .venv-pelicun .venv-openquake .pytest_cache build *.egg-info
