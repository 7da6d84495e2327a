# contactqvi: two commands do everything on a fresh machine.
#   make demo   install what is missing, run the flagship under mpirun -n 2
#   make test   install what is missing, run the test suite serially (2 workers), with 2 ranks, a subset with 3 and 4
#   make container-check   build docker/Dockerfile (docker or podman), run the flagship and the tests inside
#   make paraview          install ParaView 5.13 from Debian, render the standard views of a fresh result
#   make paraview-dynamics the same over time: frames of a fresh drop test, and a state file for the GUI
VENV    ?= .venv
PY      := $(VENV)/bin/python
NP      ?= 2
OUT     ?= results

# OpenMPI refuses to run as root unless told to; set only when we are root.
ifeq ($(shell id -u),0)
MPIENV := OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
endif
# More ranks than cores: OpenMPI 4 reads OMPI_MCA_rmaps_base_oversubscribe, OpenMPI 5 (PRRTE) the PRTE_ variable.
MPIENV  += OMPI_MCA_rmaps_base_oversubscribe=1 PRTE_MCA_rmaps_default_mapping_policy=:oversubscribe OMPI_MCA_btl=self,sm
MPIRUN  := $(MPIENV) mpirun -n $(NP)

.PHONY: deps venv demo test test-serial test-mpi test-ranks benchmarks container-check paraview paraview-dynamics peers clean

deps:
	bash scripts/install-deps.sh

$(PY): scripts/packages.txt pyproject.toml
	$(MAKE) deps
	/usr/bin/python3 -m venv --system-site-packages $(VENV)
	$(PY) -m pip install --quiet --no-build-isolation --no-deps -e .
	@touch $(PY)

venv: $(PY)

demo: $(PY)
	$(MPIRUN) $(PY) demos/coulomb3d.py --output $(OUT)/coulomb3d

test: test-serial test-mpi test-ranks

# Every test serially, on WORKERS pytest-xdist processes (one per core); tests sharing a
# module-scoped fixture stay on one worker (tests/conftest.py).
WORKERS ?= 2
test-serial: $(PY)
	$(PY) -m pytest -q --color=no -p no:cacheprovider -n $(WORKERS) --dist loadgroup tests

# Every test on NP ranks except those marked serial (cannot run under mpirun), one_rank (serial
# arithmetic on every rank), parallel_twin (a twin runs its parallel code) or ranks(...) without
# NP: README, "Tests and benchmarks".
test-mpi: $(PY)
	$(MPIRUN) $(PY) -m mpi4py -m pytest -q --color=no -p no:cacheprovider tests

# 1 rank against 3 and 4 (ranks without contact facets, parallel output, a restart written on 1 rank
# continued on 3): a small, fast subset; the marker ranks(...) of a test says on which it runs.
RANK_TESTS ?= tests/test_ranks.py tests/test_output_parallel.py \
	tests/test_restart_paths.py::test_a_path_restarted_on_another_number_of_ranks \
	tests/test_dynamics.py::test_history_on_any_number_of_ranks \
	tests/test_current_geometry.py::test_newton_matrix_against_differences \
	tests/test_current_geometry.py::test_obstacle_newton_matrix_against_differences \
	tests/test_quadratic_mortar.py::test_quadratic_two_body_parallel_equals_serial \
	tests/test_quadratic_hexahedra.py::test_biquadratic_two_body_parallel_equals_serial \
	tests/test_convection.py::test_convected_follows_each_body_linear_field \
	tests/test_press_fit.py::test_push_out_slides_at_the_coulomb_force \
	tests/test_press_fit.py::test_a_uniform_table_is_the_number \
	tests/test_dynamics.py::test_restart_mid_tilt \
	tests/test_finite_strain.py::test_half_the_height_from_rest_in_one_step
test-ranks: $(PY)
	$(MPIENV) mpirun -n 3 $(PY) -m mpi4py -m pytest -q --color=no -p no:cacheprovider $(RANK_TESTS)
	$(MPIENV) mpirun -n 4 $(PY) -m mpi4py -m pytest -q --color=no -p no:cacheprovider $(RANK_TESTS)

# Paper tables at the levels that fit a laptop; README lists the larger runs (lev 9-10, scaling).
benchmarks: $(PY)
	$(PY) benchmarks/coulomb_tables.py --levels 3 4 5 6 7 --tables 2 3
	$(MPIRUN) $(PY) benchmarks/coulomb_tables.py --levels 8 --tables 2
	$(MPIRUN) $(PY) benchmarks/coulomb_tables.py --tables 4 --table4-lev 8
	$(PY) benchmarks/coulomb_peers.py --levels 7
	$(PY) benchmarks/stadler_tables.py
	$(PY) benchmarks/thermoforming_tables.py --table all

container-check:
	bash scripts/container-check.sh

# ParaView views (scripts/paraview/pv_views.py) of a fresh lev-4 d3/L2 result, to docs/images.
PV_OUT ?= $(OUT)/pv
PV_IMAGES ?= docs/images
paraview: $(PY)
	rm -rf $(PV_OUT)
	$(MPIRUN) $(PY) demos/coulomb3d.py --lev 4 --geometry d3 --load L2 --output $(PV_OUT)
	bash scripts/paraview/run.sh $(PV_OUT) $(PV_IMAGES)

# Views over time (scripts/paraview/pv_time.py) of a fresh drop test, to docs/images; the state
# file for ParaView's GUI beside its body.bp: paraview --state=$(PV_DYNAMICS_OUT)/paraview_time.pvsm
PV_DYNAMICS_OUT ?= $(OUT)/drop_test
paraview-dynamics: $(PY)
	rm -rf $(PV_DYNAMICS_OUT)
	$(PY) -m contactqvi run cases/drop_test.toml --output $(PV_DYNAMICS_OUT)
	bash scripts/paraview/run.sh $(PV_DYNAMICS_OUT) $(PV_IMAGES)
	$(PY) -m pytest -q --color=no -p no:cacheprovider -m paraview tests/test_paraview_script.py

# Peer codes for benchmarks/peers (GetFEM from Debian trixie, Kratos into build/kratos-venv); make test needs neither.
peers:
	bash scripts/install-peers.sh

clean:
	rm -rf $(OUT) .pytest_cache build *.egg-info
