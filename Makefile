# Set-up and entry points. Every target installs what is missing (Debian 12, root) and is quick when nothing is.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
APT_PKGS := python3-dolfinx python3-slepc4py python3-petsc4py python3-gmsh python3-mpi4py python3-scipy \
            python3-venv python3-pip libopenblas0-pthread openmpi-bin
STAMP := $(VENV)/.installed
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export MPLBACKEND := Agg
export PYVISTA_OFF_SCREEN := true

.PHONY: setup docs demo test test-fast test-fe test-mpi test-slow test-kernels bench contact-map speed-accuracy \
	speed-accuracy-disk disk-map clean

setup: $(STAMP)

/usr/lib/x86_64-linux-gnu/openblas-pthread/libblas.so.3:
	@echo "installing Debian packages: $(APT_PKGS)"
	apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q $(APT_PKGS)

$(STAMP): pyproject.toml /usr/lib/x86_64-linux-gnu/openblas-pthread/libblas.so.3
	@/usr/bin/python3 -c "import dolfinx, slepc4py, gmsh" 2>/dev/null || \
	  (apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q $(APT_PKGS))
	test -x $(PY) || /usr/bin/python3 -m venv --system-site-packages $(VENV)
	/usr/bin/python3 -c "import numpy; print('numpy==' + numpy.__version__)" > $(VENV)/constraints.txt
	$(PY) -m pip install -q -c $(VENV)/constraints.txt pyvista matplotlib tqdm "meshio>=5.3,<6" pytest pytest-xdist pdoc
	$(PY) -m pip install -q -c $(VENV)/constraints.txt --no-build-isolation --no-deps -e .
	$(PY) -c "import numpy, dolfinx; assert numpy.__version__ == '$$(/usr/bin/python3 -c 'import numpy; print(numpy.__version__)')'"
	# OpenBLAS 0.3.21 falls back to SSE3 kernels on CPUs it does not know (6x slower dgemm here): see blas_check.py
	env -u OPENBLAS_CORETYPE /usr/bin/python3 -S rotor37_rom/blas_check.py \
	  --pth "$$($(PY) -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/rotor37_openblas.pth"
	touch $(STAMP)

# Chromium for the report's browser test only (tests/cli/test_report_browser.py); where apt cannot install it, that test
# is skipped and says why
CHROMIUM := /usr/bin/chromium
$(CHROMIUM):
	-(apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium) \
	  || echo "chromium could not be installed: the browser test will be skipped"

# the paper's single-blade story in ~6 min on 2 cores (the GNL map 4): modes, clearance consumption, maps and NFRC
# with GNL off and on, stress at t_max; results/report/report.html
demo: $(STAMP)
	$(PY) demos/report.py

# a finer map without friction on the r = 55 model, GNL off and on (~30 min)
contact-map: $(STAMP)
	$(PY) demos/contact_map.py --r-c 25 --mu 0 --speeds 1200 1600 21 --revolutions 20

# the API reference from the docstrings (pdoc): results/api/index.html; pdoc's warnings (an annotation it cannot
# read) are errors, as in tests/test_api_reference.py
docs: $(STAMP)
	OPENBLAS_NUM_THREADS=1 $(PY) -W error::UserWarning -m pdoc -o results/api rotor37_rom forms geometry
	@echo "API reference: results/api/index.html"

# the suite on two workers side by side (pytest-xdist), one BLAS thread each (one per core): most tests are
# single-threaded Python, so this halves the wall time; whole files go to whichever worker is free (--dist loadfile:
# a file's module fixtures are built once), no hand-kept split; the summary and the 24 slowest tests in
# results/test.log
test: $(STAMP) $(CHROMIUM)
	@mkdir -p results && echo "tests on two workers: results/test.log"
	set -o pipefail; OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -q -ra --durations=24 -p no:cacheprovider -n 2 \
	  --dist loadfile tests 2>&1 | tee results/test.log

# the suite in parts: fast (no slow, no MPI: <= 3 min), FE, MPI, slow
test-fast: $(STAMP) $(CHROMIUM)
	$(PY) -m pytest -q -ra -m "not slow and not mpi" tests

test-fe: $(STAMP)
	$(PY) -m pytest -q -ra -m "fe" tests

test-mpi: $(STAMP)
	$(PY) -m pytest -q -ra -m "mpi" tests

test-slow: $(STAMP)
	$(PY) -m pytest -q -ra -m "slow" tests

# portability: the numerically sensitive tests under the native OpenBLAS kernels with 2 and 1 threads, and with
# the AMD Zen and Intel Haswell kernels forced (each run prints its kernels in the header); ~20 min
KERNEL_TESTS := -m "kernels or (not slow and not mpi)" tests
KERNELS := $(PY) -c "import numpy; from rotor37_rom.blas_check import openblas_core; print('OpenBLAS kernels:', openblas_core())"
test-kernels: $(STAMP)
	OPENBLAS_NUM_THREADS=2 $(KERNELS) && OPENBLAS_NUM_THREADS=2 $(PY) -m pytest -q -ra $(KERNEL_TESTS)
	OPENBLAS_NUM_THREADS=1 $(KERNELS) && OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -q -ra $(KERNEL_TESTS)
	OPENBLAS_CORETYPE=Zen $(KERNELS) && OPENBLAS_CORETYPE=Zen OPENBLAS_NUM_THREADS=2 $(PY) -m pytest -q -ra $(KERNEL_TESTS)
	OPENBLAS_CORETYPE=Haswell $(KERNELS) && OPENBLAS_CORETYPE=Haswell OPENBLAS_NUM_THREADS=2 $(PY) -m pytest -q -ra \
	  $(KERNEL_TESTS)

bench: $(STAMP)
	$(PY) benchmarks/bench_full_order.py
	$(PY) benchmarks/bench_contact_convergence.py
	$(PY) benchmarks/bench_contact_rom_size.py
	$(PY) benchmarks/bench_contact_rom_size.py --gnl --r-c 10 15 25 40
	$(PY) benchmarks/bench_contact_reference.py --r-c 10 25 40 80
	$(PY) benchmarks/bench_contact_reference.py --gnl --no-full-order --speeds 1280 1520 --r-md 0 20 50 --rom-cap 120 --rom-step 4e-7
	$(PY) benchmarks/bench_contact_ecsw.py
	$(PY) benchmarks/bench_integrator.py
	$(PY) benchmarks/bench_force_jacobians.py
	$(PY) benchmarks/bench_disk_stress_convergence.py

# the speed-accuracy study (docs/choosing-a-model.md): every scene's candidates, cost and error, the charts and the
# file choose_model reads (rotor37_rom/data/speed_accuracy.json); 52 min from scratch on 2 cores
speed-accuracy: $(STAMP)
	$(PY) benchmarks/speed_accuracy.py

# its bladed-disk scenes (the disk's frequencies at every nodal diameter, its short maps without and with GNL and
# the stress in them, its forced response without contact without and with GNL); about 4 h, the GNL map scene
# 2 h 15 min of it, the forced-response scenes 12 and ~55 min (AMD EPYC, 2 cores)
speed-accuracy-disk: $(STAMP)
	$(PY) benchmarks/speed_accuracy.py --scene disk

# the full-disk maps (issue #21): 90 speeds x 200 revolutions, 36 x 8 tip nodes, without GNL (2 h) and with GNL,
# point cubature 3e-3 in float32, its exact reference at 4 speeds (about 11 h; stopped, it resumes when run again), and
# the stress at the two maps' largest responses, GNL off and on (20 min)
disk-map: $(STAMP)
	OPENBLAS_NUM_THREADS=1 mpirun -n 2 $(PY) demos/contact_map.py --disk --direction cone --frequency-cap 60 \
		--speeds 1200 1650 90 --revolutions 200 --gnl off --stress --out results/disk_map200
	OPENBLAS_NUM_THREADS=1 mpirun -n 2 $(PY) benchmarks/bench_disk_map.py
	OPENBLAS_NUM_THREADS=1 $(PY) benchmarks/bench_disk_map.py --part stress

clean:
	rm -rf $(VENV) results .pytest_cache
