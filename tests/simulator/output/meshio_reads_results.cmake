# meshio reads the simulator's results (ctest: simulator_meshio_reads_results). Runs the
# box_compression scene on a generated 8 × 8 × 8 block and a short press of a small skin block
# (results_runs.cmake) and reads each results.xdmf with meshio's XDMF time-series reader, and the
# skin's results_surface_skin.xdmf, comparing with results.h5 through h5py (meshio_check.py).
# Skipped when no Python with meshio and h5py is found (the test's SKIP_REGULAR_EXPRESSION matches
# the message below): scripts/install-deps installs Debian's python3-meshio and python3-h5py.
# Inputs: -DSIMULATE=... -DGENERATE=... -DSAMPLE=<sinew-sample-model> -DSCENES=<data/scenes>
#         -DCHECK=<meshio_check.py> -DWORK=<dir> -DPYTHONS=<python3 candidates, |-separated>
cmake_minimum_required(VERSION 3.20)
set(python "")
string(REPLACE "|" ";" candidates "${PYTHONS}")
foreach(candidate IN LISTS candidates)
  execute_process(COMMAND "${candidate}" -c "import meshio, h5py" RESULT_VARIABLE rc
                  OUTPUT_QUIET ERROR_QUIET)
  if(rc EQUAL 0)
    set(python "${candidate}")
    break()
  endif()
endforeach()
if(NOT python)
  message("meshio not found: skipped (apt-get install python3-meshio to run this test)")
  return()
endif()
include("${CMAKE_CURRENT_LIST_DIR}/results_runs.cmake")
# The box: 31 frames, 9³ nodes, 8³ hexahedra, no surface. The skin block: 5 frames, 2023 nodes,
# 1536 hexahedra and results_surface_skin.xdmf.
foreach(run "out;31;729;512;0" "skin_out;5;2023;1536;1")
  list(GET run 0 dir)
  list(SUBLIST run 1 4 counts)
  check_results(${dir} COMMAND "${python}" "${CHECK}" ARGS ${counts})
endforeach()
