# psph: `make run` (default scene on 2 ranks + pictures) and `make test` (serial + 2-rank).
# Both bring the environment up through `make env`, which is idempotent and fast once done.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
NP ?= 2
# workers of the serial suite (pytest-xdist; one per core here): make test-serial TEST_WORKERS=1
TEST_WORKERS ?= 2
OUT ?= runs/terzaghi

# Open MPI refuses root and more ranks than cores unless told; users should not have to.
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
# Keep Open MPI from probing absent network fabrics (noisy warnings, slow start-up).
export OMPI_MCA_btl := self,vader,tcp
export OMPI_MCA_btl_vader_single_copy_mechanism := none
# Numba caches compiled kernels beside the sources; one thread per rank.
export NUMBA_NUM_THREADS := 1
export OMP_NUM_THREADS := 1

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
DEB_PKGS := openmpi-bin libopenmpi-dev libhdf5-openmpi-dev pkg-config
STAMP := $(VENV)/.psph-env-ok

.PHONY: env run test layers test-serial test-mpi bench bench-time-vs-error bench-stability bench-memory \
	bench-scaling bench-ranks bench-tpi-gravity bench-collapse-beta bench-field \
	bench-field-window bench-large bench-convergence bench-convergence-quick bench-smoke lint clean-env \
	docs docs-check

env: $(STAMP)

$(STAMP): pyproject.toml
	@if ! command -v mpicc >/dev/null || ! pkg-config --exists hdf5-openmpi 2>/dev/null; then \
	  echo "make env: installing $(DEB_PKGS)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $(DEB_PKGS) >/dev/null; \
	fi
	@[ -x $(VPY) ] || $(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade pip 'setuptools>=77' wheel
	$(VPY) -m pip install -q numpy cython pkgconfig mpi4py
	@$(VPY) -c "import h5py, sys; sys.exit(0 if h5py.get_config().mpi else 1)" 2>/dev/null || \
	  CC=mpicc HDF5_MPI=ON HDF5_PKGCONFIG_NAME=hdf5-openmpi \
	  $(VPY) -m pip install -q --force-reinstall --no-deps --no-binary=h5py --no-build-isolation h5py
	$(VPY) -m pip install -q -e '.[dev,docs]'
	$(VPY) -c "import h5py, mpi4py, numba; assert h5py.get_config().mpi, 'h5py lacks MPI'"
	@touch $@

run: env
	mpirun -n $(NP) $(VPY) -m psph run terzaghi --out $(OUT)
	$(VPY) -m psph plot $(OUT)

# Any built-in scene on NP ranks with its pictures: make scene-harmonic, scene-strip_footing
scene-%: env
	mpirun -n $(NP) $(VPY) -m psph run $* --out runs/$*
	$(VPY) -m psph plot runs/$*

# the import layers of pyproject.toml [tool.importlinter] first: seconds, before the suites
test: layers docs test-serial test-mpi docs-check

layers: env
	$(VENV)/bin/lint-imports

# a file's tests stay on one worker (--dist loadfile), so its module fixtures run once
test-serial: env
	$(VPY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile --durations=15

test-mpi: env
	mpirun -n 2 $(VPY) -m pytest -q --with-mpi -m mpi -p no:cacheprovider --durations=15 tests

bench: env
	mpirun -n 1 $(VPY) bench/performance/throughput.py
	mpirun -n 2 $(VPY) bench/performance/throughput.py
	$(VPY) bench/performance/throughput.py --plot

bench-time-vs-error: env
	$(VPY) bench/verification/time_vs_error.py

bench-stability: env
	$(VPY) bench/verification/stability.py

# peak memory and set-up time per rank, 0.5M-2M particles on 1, 2 and 4 ranks
bench-memory: env
	$(VPY) bench/performance/memory.py

# ~10M particles on 2 ranks: 100 steps, snapshot, checkpoint, restart; set-up on 1, 2, 4
bench-large: env
	$(VPY) bench/performance/large_run.py

# strong (20k, 100k, 400k) and weak scaling 1 -> 2 ranks
bench-scaling: env
	$(VPY) bench/performance/scaling.py

# TPI stability of a column at rest under gravity, over alpha and dt gamma_l / (rho k)
bench-tpi-gravity: env
	$(VPY) bench/verification/tpi_gravity.py

# the dilative saturated collapse with and without Eq. (47), side by side (Fig. 16)
bench-collapse-beta: env
	$(VPY) bench/verification/collapse_beta.py

# Section 4.5 clay slope on 2 ranks: the full 40 s (about 25 min) or a 0.5 s window
bench-field: env
	$(VPY) bench/performance/field.py

bench-field-window: env
	$(VPY) bench/performance/field.py --window 0.5

# run-out against dx and dt, local and regularised softening: the full matrix
# (hours on 2 cores; ARGS="--only REGEX" for a subset) or the CI-sized dry column (~3 min)
bench-convergence: env
	$(VPY) bench/verification/convergence.py $(ARGS)

bench-convergence-quick: env
	$(VPY) bench/verification/convergence.py --quick

# the same scenes on 1, 2, 3 and 4 ranks compared field by field
bench-ranks: env
	$(VPY) bench/verification/rank_invariance.py

# every bench script's smallest case (or --help) in a scratch directory: tests/test_bench_smoke.py
bench-smoke: env
	$(VPY) -m pytest -q -p no:cacheprovider tests/test_bench_smoke.py

# the documentation site (Sphinx + MyST) into docs/_build/html: any warning fails, internal
# links included; docs/reference/scene_keys.md is generated from the scene schema
docs: env
	$(VPY) -m sphinx -W --keep-going -n -q -b html docs docs/_build/html

# the tutorials' marked command blocks, run in scratch directories (docs/check_tutorials.py)
docs-check: env
	$(VPY) docs/check_tutorials.py

lint: env
	$(VENV)/bin/ruff check psph tests bench
	$(VENV)/bin/lint-imports

clean-env:
	rm -rf $(VENV)
