# ParaView opens the simulator's results (ctest: simulator_paraview_opens_results). Runs the
# box_compression scene on a generated 8 × 8 × 8 block and reads results.xdmf with pvpython's XDMF
# reader (paraview_check.py). Skipped when pvpython is not installed (the test's
# SKIP_REGULAR_EXPRESSION matches the message below): Debian's `paraview` package provides it;
# scripts/install-deps does not install it (it is large).
# Inputs: -DSIMULATE=... -DGENERATE=... -DSCENES=<data/scenes> -DCHECK=<paraview_check.py>
#         -DWORK=<dir> -DPVPYTHON=<pvpython or PVPYTHON-NOTFOUND>
cmake_minimum_required(VERSION 3.20)
if(NOT PVPYTHON)
  message("pvpython not found: skipped (apt-get install paraview to run this test)")
  return()
endif()
include("${CMAKE_CURRENT_LIST_DIR}/compression_block.cmake")
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/out" --quiet
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: sinew-simulate exited ${rc}: ${err}")
endif()
# 31 frames (t = 0, 0.02, ..., 0.6), 9³ nodes, 8³ hexahedra.
execute_process(COMMAND "${PVPYTHON}" --force-offscreen-rendering "${CHECK}"
                        "${WORK}/out/results.xdmf" 31 729 512
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: pvpython exited ${rc}: ${out} ${err}")
endif()
