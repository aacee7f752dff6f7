# End-to-end test of the sinew-simulate command line (ctest: simulator_cli_end_to_end).
# Generates the model of data/scenes/box_compression.yaml with sinew-generate, then checks:
# a full run writes every output; --explain prints the plan and writes nothing; --device cuda
# runs or says why not; a scene with an unknown key and a missing checkpoint fail with clear messages and non-zero
# status; --checkpoint-every writes a checkpoint that --restart resumes from; SIGINT stops a run
# with a checkpoint and exit status 130.
# Inputs: -DSIMULATE=<sinew-simulate> -DGENERATE=<sinew-generate> -DSCENES=<data/scenes> -DWORK=<dir>
cmake_minimum_required(VERSION 3.20)

# expect(MESSAGE CONDITION...): fails the test with MESSAGE unless if(CONDITION) holds.
function(expect message)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "FAILED: ${message}")
  endif()
endfunction()

include("${CMAKE_CURRENT_LIST_DIR}/../compression_block.cmake")

# 1. A full run.
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/out" --quiet --threads 2
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("a full run exits 0 (stderr: ${err})" rc EQUAL 0)
foreach(f results.h5 results.xdmf run_summary.json probe_lid_force.csv probe_bulge.csv)
  expect("the run writes ${f}" EXISTS ${WORK}/out/${f})
endforeach()
file(READ "${WORK}/out/results.xdmf" xdmf)
string(FIND "${xdmf}" "TopologyType=\"Hexahedron\"" pos)
expect("the XDMF index has hexahedral grids" pos GREATER -1)
file(READ "${WORK}/out/run_summary.json" summary)
string(JSON status GET "${summary}" status)
string(JSON frames GET "${summary}" frames)
string(JSON steps GET "${summary}" steps_done)
expect("summary status is completed (got ${status})" status STREQUAL completed)
expect("31 frames: t = 0, 0.02, ..., 0.6 (got ${frames})" frames EQUAL 31)
file(STRINGS "${WORK}/out/probe_lid_force.csv" rows)
list(GET rows 0 header)
expect("reaction probe header" header STREQUAL "time,step,fx,fy,fz")

# 2. --explain alone prints the plan and writes nothing.
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/explain_only" --explain
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("--explain exits 0 (stderr: ${err})" rc EQUAL 0)
string(FIND "${out}" "Time step" pos)
expect("--explain prints the time step" pos GREATER -1)
string(FIND "${out}" "probe 'lid_force'" pos)
expect("--explain lists the probes" pos GREATER -1)
expect("--explain without --run writes nothing" NOT EXISTS ${WORK}/explain_only)

# 3. --device cuda: runs where a CUDA device is, otherwise fails and says why.
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/cuda" --device cuda
                        --quiet
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  expect("--device cuda writes results" EXISTS ${WORK}/cuda/results.h5)
else()
  expect("--device cuda without a device exits 1 (got ${rc})" rc EQUAL 1)
  string(FIND "${err}" "CUDA" pos)
  expect("--device cuda explains why (stderr: ${err})" pos GREATER -1)
endif()

# 4. A scene with an unknown key names the file and the key path.
file(READ "${WORK}/box_compression.yaml" text)
string(REPLACE "  probe_interval: 0.005" "  probe_interval: 0.005\n  every: 3" text "${text}")
file(WRITE "${WORK}/bad.yaml" "${text}")
execute_process(COMMAND "${SIMULATE}" "${WORK}/bad.yaml" -o "${WORK}/bad"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("an unknown key exits 1 (got ${rc})" rc EQUAL 1)
string(FIND "${err}" "bad.yaml: output.every: unknown key 'every'" pos)
expect("the error names file and key (stderr: ${err})" pos GREATER -1)

# 5. Checkpoints: --checkpoint-every writes one; --restart from it completes the same run.
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/ckpt" --quiet
                        --checkpoint-every 400
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("a run with --checkpoint-every (stderr: ${err})" rc EQUAL 0)
expect("--checkpoint-every writes checkpoint.h5" EXISTS ${WORK}/ckpt/checkpoint.h5)
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/ckpt" --quiet
                        --restart "${WORK}/ckpt/checkpoint.h5"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("--restart resumes (stderr: ${err})" rc EQUAL 0)
file(READ "${WORK}/ckpt/run_summary.json" summary)
string(JSON restart GET "${summary}" restart_step)
string(JSON frames_restart GET "${summary}" frames)
expect("resumed from the last checkpoint, step 800 (got ${restart})" restart EQUAL 800)
expect("the resumed run has every frame" frames_restart EQUAL frames)
file(READ "${WORK}/out/probe_bulge.csv" a)
file(READ "${WORK}/ckpt/probe_bulge.csv" b)
expect("the resumed run's probe CSV equals the uninterrupted run's" a STREQUAL b)
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/ckpt"
                        --restart "${WORK}/nowhere.h5"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("a missing checkpoint is an error" NOT rc EQUAL 0)
# 6. SIGINT stops a long run at a step boundary with a checkpoint, exit 130, and valid outputs.
find_program(TIMEOUT timeout)
if(TIMEOUT)
  string(REPLACE "duration: 0.6" "duration: 600" text "${text}")
  string(REPLACE "  every: 3\n" "" text "${text}")
  file(WRITE "${WORK}/long.yaml" "${text}")
  execute_process(COMMAND "${TIMEOUT}" --preserve-status -s INT 1 "${SIMULATE}" "${WORK}/long.yaml"
                          -o "${WORK}/long" --quiet
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  expect("SIGINT exits 130 (got ${rc}, stderr: ${err})" rc EQUAL 130)
  expect("an interruption writes a checkpoint" EXISTS ${WORK}/long/checkpoint.h5)
  file(READ "${WORK}/long/run_summary.json" summary)
  string(JSON status GET "${summary}" status)
  string(JSON steps GET "${summary}" steps_done)
  expect("an interrupted run says so (got ${status})" status STREQUAL interrupted)
  expect("it got somewhere before the interruption" steps GREATER 0)
  string(FIND "${err}" "--restart" pos)
  expect("the message says how to resume (stderr: ${err})" pos GREATER -1)
endif()
message(STATUS "sinew-simulate end-to-end: all checks passed")
