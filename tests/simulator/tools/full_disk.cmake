# Every tool on a full disk (ctest: tools_full_disk): exit status 1, a "no space left on the
# device" message naming the file, no file left under its final name and no temporary left
# beside it. A run (sinew-simulate, sinew-sweep) that fills the disk part way may keep files of
# the frames before the failure, as an interrupted one does, but only whole ones: a results.h5
# left under its name opens (sinew-export reads every frame of it), an XDMF index names a
# results.h5 that is there, a probe CSV ends in a whole row. With 0 B, 4 KiB or 64 KiB free a run
# left a results.h5 that failed to open ("addr overflow": issue 33).
# The disk is a small tmpfs mounted for the test; without the right to mount one (not root, no
# tmpfs) the test prints "SKIPPED" and ctest reports it skipped.
# Inputs: -DGENERATE= -DVOXELIZE= -DSIMULATE= -DSWEEP= -DEXPORT= -DRENDER= (the tools)
#         -DSPECS=<data/specs> -DSCENES=<data/scenes> -DWORK=<dir>
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

# Fills the tmpfs to the last byte, then frees `free` bytes again (0 when not given).
function(fill)
  execute_process(COMMAND dd if=/dev/zero of=${full}/filler bs=4096 OUTPUT_QUIET ERROR_QUIET)
  if(ARGC GREATER 0 AND ARGV0 GREATER 0)
    execute_process(COMMAND truncate -s -${ARGV0} ${full}/filler)
  endif()
endfunction()

# expect_whole_run_files(NAME DIR): what a run that failed part way left in DIR is whole: a
# results.h5 opens and sinew-export reads all its frames, an XDMF index names a results.h5 that
# is there, a probe CSV ends in a newline, the summary does not say "running".
function(expect_whole_run_files name dir)
  if(EXISTS "${dir}/results.h5")
    execute_process(COMMAND "${EXPORT}" "${dir}/results.h5" --pc2 "${WORK}/check.pc2"
                    --rest-obj "${WORK}/check.obj" RESULT_VARIABLE rc ERROR_VARIABLE err)
    expect("${name}: the results.h5 left under its name opens (${err})" rc EQUAL 0)
  endif()
  file(GLOB indexes "${dir}/*.xdmf")
  if(indexes)
    expect("${name}: an XDMF index (${indexes}) names a results.h5 that is there"
           EXISTS "${dir}/results.h5")
  endif()
  file(GLOB csvs "${dir}/probe_*.csv")
  foreach(csv ${csvs})
    file(READ "${csv}" text)
    string(LENGTH "${text}" length)
    math(EXPR last "${length} - 1")
    if(length GREATER 0)
      string(SUBSTRING "${text}" ${last} 1 end)
    else()
      set(end "")
    endif()
    expect("${name}: ${csv} ends in a whole row" end STREQUAL "\n")
  endforeach()
  if(EXISTS "${dir}/run_summary.json")
    file(READ "${dir}/run_summary.json" summary)
    string(JSON status GET "${summary}" status)
    expect("${name}: the summary left is not 'running' (${status})" NOT status STREQUAL "running")
  endif()
  set(failures "${failures}" PARENT_SCOPE)
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

# 3. Runs that fill the disk part way, with 0 B, 4 KiB and 64 KiB free on the 1 MiB disk, then
# on a disk of 160 KiB: whatever is left under a final name is whole.
file(REMOVE "${full}/filler")
foreach(free 0 4096 65536)
  fill(${free})
  run_full("sinew-simulate, ${free} B free" COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml"
           -o "${full}/run" -q --threads 2)
  expect_whole_run_files("sinew-simulate, ${free} B free" "${full}/run")
  file(REMOVE_RECURSE "${full}/run")
  file(REMOVE "${full}/filler")
endforeach()
if(SWEEP)
  # sinew-sweep runs through the same runner; its run folder must hold only whole files too.
  file(WRITE "${WORK}/full_sweep.yaml" "version: 1\nscene: box_compression.yaml\n"
       "list: [{damping: 60}]\nrun: {device: cpu, threads: 2}\n")
  fill(65536)
  execute_process(COMMAND "${SWEEP}" "${WORK}/full_sweep.yaml" -o "${full}/sweep" -q
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect("sinew-sweep: a non-zero exit status on a full disk (got ${rc}; stderr: ${err})"
         NOT rc EQUAL 0)
  file(GLOB runs "${full}/sweep/run_*")
  foreach(run ${runs})
    expect_whole_run_files("sinew-sweep ${run}" "${run}")
  endforeach()
  file(GLOB_RECURSE tmps "${full}/*.tmp-*")
  expect("sinew-sweep: no temporary left (${tmps})" NOT tmps)
  file(REMOVE_RECURSE "${full}/sweep")
  file(REMOVE "${full}/filler")
endif()
execute_process(COMMAND mount -o remount,size=160k "${full}")
run_full(sinew-simulate COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${full}/run" -q
         --threads 2)
expect_whole_run_files("sinew-simulate, 160 KiB disk" "${full}/run")

execute_process(COMMAND umount "${full}")
if(failures)
  message(FATAL_ERROR "${failures}")
endif()
