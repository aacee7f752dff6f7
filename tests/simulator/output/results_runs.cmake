# Set-up shared by meshio_reads_results.cmake and paraview_opens_results.cmake: two short runs whose
# results the reader tests open. Fails the test when a tool fails.
# - WORK/out: data/scenes/box_compression.yaml on compression_block.cmake's 8 × 8 × 8 block
#   (31 frames: t = 0, 0.02, ..., 0.6; 9³ nodes, 8³ hexahedra; no surface).
# - WORK/skin_out: a small skin block with a visual surface 'skin' (sinew-sample-model skin-block,
#   16 × 16 × 6 voxels: 2023 nodes, 1536 elements, the skin 673 vertices and 1280 triangles) under
#   data/scenes/skin_block_press.yaml cut to 2 ms with a frame every 0.5 ms (5 frames).
# Inputs: -DSIMULATE=... -DGENERATE=... -DSAMPLE=<sinew-sample-model> -DSCENES=<data/scenes>
#         -DWORK=<dir>
include("${CMAKE_CURRENT_LIST_DIR}/../compression_block.cmake")
execute_process(COMMAND "${SAMPLE}" skin-block --dims 16 16 6 --voxel-size 0.0019
                        -o "${WORK}/skin_block.h5" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: sinew-sample-model exited ${rc}")
endif()
file(READ "${SCENES}/skin_block_press.yaml" scene)
string(REPLACE "duration: 0.02" "duration: 0.002" scene "${scene}")
string(REPLACE "interval: 0.001" "interval: 0.0005" scene "${scene}")
file(WRITE "${WORK}/skin_press.yaml" "${scene}")
foreach(run "box_compression.yaml;out" "skin_press.yaml;skin_out")
  list(GET run 0 scene_file)
  list(GET run 1 out_dir)
  execute_process(COMMAND "${SIMULATE}" "${WORK}/${scene_file}" -o "${WORK}/${out_dir}" --quiet
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "FAILED: sinew-simulate ${scene_file} exited ${rc}: ${err}")
  endif()
endforeach()

# Runs a reader's check on one run's results: COMMAND <results.xdmf of WORK/dir> ARGS; fails the test
# when it exits non-zero, and leaves its stdout and stderr in check_output.
function(check_results dir)
  cmake_parse_arguments(R "" "" "COMMAND;ARGS" ${ARGN})
  execute_process(COMMAND ${R_COMMAND} "${WORK}/${dir}/results.xdmf" ${R_ARGS}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "FAILED: ${R_COMMAND} exited ${rc} on ${dir}: ${out} ${err}")
  endif()
  set(check_output "${out}${err}" PARENT_SCOPE)
endfunction()
