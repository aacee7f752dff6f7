# ParaView opens the simulator's results (ctest: simulator_paraview_opens_results). Runs the
# box_compression scene on a generated 8 × 8 × 8 block and a short press of a small skin block with
# a visual surface, and reads each results.xdmf with pvpython's XDMF reader (paraview_check.py),
# which must log no error. Skipped when pvpython is not installed (the test's
# SKIP_REGULAR_EXPRESSION matches the message below): Debian's `paraview` and `python3-paraview`
# provide it; scripts/install-deps does not install them (they are large).
# Inputs: -DSIMULATE=... -DGENERATE=... -DSAMPLE=<sinew-sample-model> -DSCENES=<data/scenes>
#         -DCHECK=<paraview_check.py> -DWORK=<dir> -DPVPYTHON=<pvpython or PVPYTHON-NOTFOUND>
cmake_minimum_required(VERSION 3.20)
if(NOT PVPYTHON)
  message("pvpython not found: skipped (apt-get install paraview python3-paraview to run this test)")
  return()
endif()
include("${CMAKE_CURRENT_LIST_DIR}/results_runs.cmake")
# The box: 31 frames, 9³ nodes, 8³ hexahedra. The skin block: the reader loads the volume and the
# skin, 2023 + 673 points and 1536 + 1280 cells, 5 time steps (its surface frames once made the
# reader log "Cannot find DataItem element in geometry xml" on every read).
foreach(run "out;31;729;512" "skin_out;5;2696;2816")
  list(GET run 0 dir)
  list(SUBLIST run 1 3 counts)
  check_results(${dir} COMMAND "${PVPYTHON}" --force-offscreen-rendering "${CHECK}" ARGS ${counts})
  # No error or warning lines from the reader (ParaView logs them, "ERR| ... Cannot find DataItem
  # element in geometry xml" once, and reads on).
  if(check_output MATCHES "ERR\\||ERROR|Warning|Cannot find DataItem")
    message(FATAL_ERROR "FAILED: ParaView logged errors reading ${dir}/results.xdmf: ${check_output}")
  endif()
endforeach()
