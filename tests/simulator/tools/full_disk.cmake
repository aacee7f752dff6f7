# Every tool on a full disk (ctest: tools_full_disk): exit status 1, a "no space left on the
# device" message naming the file, no file left under its final name and no temporary left
# beside it. The disk is a small tmpfs mounted for the test; without the right to mount one (not
# root, no tmpfs) the test prints "SKIPPED" and ctest reports it skipped.
# Inputs: -DGENERATE= -DVOXELIZE= -DSIMULATE= -DEXPORT= -DRENDER= (the tools) -DSPECS=<data/specs>
#         -DSCENES=<data/scenes> -DWORK=<dir>
cmake_minimum_required(VERSION 3.20)

# A tmpfs left mounted by an aborted earlier run would stop compression_block.cmake's clean-up.
execute_process(COMMAND umount "${WORK}/full" OUTPUT_QUIET ERROR_QUIET)
include("${CMAKE_CURRENT_LIST_DIR}/../compression_block.cmake")
set(full "${WORK}/full")
file(MAKE_DIRECTORY "${full}")
execute_process(COMMAND mount -t tmpfs -o size=1m tmpfs "${full}" RESULT_VARIABLE rc
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message("SKIPPED: cannot mount a tmpfs to fill (${err})")
  return()
endif()

set(failures "")
# expect(MESSAGE CONDITION...): records a failure unless if(CONDITION) holds (the tmpfs is
# unmounted before the test fails).
function(expect message)
  if(NOT (${ARGN}))
    set(failures "${failures}\nFAILED: ${message}" PARENT_SCOPE)
  endif()
endfunction()

# Fills the tmpfs to the last byte.
function(fill)
  execute_process(COMMAND dd if=/dev/zero of=${full}/filler bs=4096 OUTPUT_QUIET ERROR_QUIET)
endfunction()

# run_full(NAME PATHS... COMMAND cmd...): runs cmd, expects exit 1, a disk-full message and none
# of PATHS (final names) nor any temporary in the tmpfs.
function(run_full name)
  cmake_parse_arguments(A "" "" "PATHS;COMMAND" ${ARGN})
  execute_process(COMMAND ${A_COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect("${name}: exit status 1 on a full disk (got ${rc}; stderr: ${err})" rc EQUAL 1)
  string(FIND "${err}" "no space left on the device" pos)
  expect("${name}: says the disk is full (stderr: ${err})" pos GREATER -1)
  string(FIND "${err}" "18446744073709551615" pos)
  expect("${name}: no raw HDF5 byte counts (stderr: ${err})" pos EQUAL -1)
  foreach(p ${A_PATHS})
    expect("${name}: nothing left under the final name ${p}" NOT EXISTS "${p}")
  endforeach()
  file(GLOB_RECURSE tmps "${full}/*.tmp-*")
  list(LENGTH tmps left)
  expect("${name}: no temporary left (${tmps})" left EQUAL 0)
  set(failures "${failures}" PARENT_SCOPE)
endfunction()

# Inputs written off the tmpfs: a voxelized model with a skin surface and a short run on it.
execute_process(COMMAND "${VOXELIZE}" "${SPECS}/concentric_spheres.yaml" -o "${WORK}/spheres.h5" -q
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("sinew-voxelize writes the input model (${err})" rc EQUAL 0)
file(WRITE "${WORK}/spheres.yaml" "model: spheres.h5\neffects: [elasticity, gravity]\n"
     "duration: 0.002\noutput: {interval: 0.001, fields: [surfaces]}\n")
execute_process(COMMAND "${SIMULATE}" "${WORK}/spheres.yaml" -o "${WORK}/spheres_run" -q
                --threads 2 RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("sinew-simulate writes the input results (${err})" rc EQUAL 0)
set(results "${WORK}/spheres_run/results.h5")

# 1. Model writers: the model is larger than the disk.
run_full(sinew-generate PATHS "${full}/box.h5" COMMAND "${GENERATE}" box --dims 40 40 40
         --voxel-size 0.002 --material soft:3000:0.45:1000 -o "${full}/box.h5" -q)
fill()
run_full(sinew-voxelize PATHS "${full}/spheres.h5" COMMAND "${VOXELIZE}"
         "${SPECS}/concentric_spheres.yaml" -o "${full}/spheres.h5" -q)

# 2. Renders and exports, each on a disk full to the last byte.
run_full("sinew-render PNG" PATHS "${full}/last.png" COMMAND "${RENDER}" "${results}" -o
         "${full}/last.png")
run_full("sinew-render contact sheet" PATHS "${full}/sheet.png" COMMAND "${RENDER}" "${results}"
         --contact-sheet "${full}/sheet.png")
run_full("sinew-export glb" PATHS "${full}/a.glb" COMMAND "${EXPORT}" "${results}" --glb
         "${full}/a.glb")
run_full("sinew-export pc2" PATHS "${full}/a.pc2" "${full}/rest.obj" COMMAND "${EXPORT}"
         "${results}" --pc2 "${full}/a.pc2" --rest-obj "${full}/rest.obj")
run_full("sinew-export OBJ sequence" PATHS "${full}/objs/frame_0000.obj" COMMAND "${EXPORT}"
         "${results}" --obj-sequence "${full}/objs")

# 3. A run that fills the disk part way: the summary must not be left saying "running".
file(REMOVE "${full}/filler")
execute_process(COMMAND mount -o remount,size=160k "${full}")
run_full(sinew-simulate COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${full}/run" -q
         --threads 2)
if(EXISTS "${full}/run/run_summary.json")
  file(READ "${full}/run/run_summary.json" summary)
  string(JSON status GET "${summary}" status)
  expect("sinew-simulate: the summary left is not 'running' (${status})"
         NOT status STREQUAL "running")
endif()

execute_process(COMMAND umount "${full}")
if(failures)
  message(FATAL_ERROR "${failures}")
endif()
