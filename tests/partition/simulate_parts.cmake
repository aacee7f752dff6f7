# sinew-simulate-parts under mpirun against sinew-simulate --device cpu (ctest:
# partition_simulate_parts): the box compression scene (data/scenes/box_compression.yaml) on 2 and
# 3 parts gives probe files identical byte for byte (17 significant digits: the same bits) and a
# completed summary; a bad scene fails on every rank with the error named and a non-zero status;
# a checkpoint of 3 parts resumes on 2 with the same files; sinew-simulate --explain --parts P prints
# the partition.
# Inputs: -DSIMULATE=<sinew-simulate> -DPARTS=<sinew-simulate-parts> -DMPIEXEC=<mpirun>
#         -DGENERATE=<sinew-generate> -DSCENES=<data/scenes> -DWORK=<dir>
cmake_minimum_required(VERSION 3.20)

function(expect message)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "FAILED: ${message}")
  endif()
endfunction()

include("${CMAKE_CURRENT_LIST_DIR}/../simulator/compression_block.cmake")
set(mpirun "${MPIEXEC}" --oversubscribe --allow-run-as-root)

execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" -o "${WORK}/one" --quiet
                        --threads 1 --device cpu
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("sinew-simulate exits 0 (stderr: ${err})" rc EQUAL 0)
foreach(parts 2 3)
  execute_process(COMMAND ${mpirun} -n ${parts} "${PARTS}" "${WORK}/box_compression.yaml"
                          -o "${WORK}/parts${parts}" --quiet --threads 1
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect("sinew-simulate-parts on ${parts} ranks exits 0 (${out} ${err})" rc EQUAL 0)
  foreach(probe probe_lid_force.csv probe_bulge.csv)
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/one/${probe}"
                            "${WORK}/parts${parts}/${probe}" RESULT_VARIABLE same)
    expect("${probe} on ${parts} parts is the one-device file byte for byte" same EQUAL 0)
  endforeach()
  file(READ "${WORK}/parts${parts}/run_summary.json" summary)
  string(JSON status GET "${summary}" status)
  string(JSON device GET "${summary}" device)
  expect("summary status completed (got ${status})" status STREQUAL completed)
  string(FIND "${device}" "${parts} parts" pos)
  expect("the summary names the parts (got ${device})" pos GREATER -1)
endforeach()

# A checkpoint written on 3 parts resumes on 2 and ends on the one-device probe files.
execute_process(COMMAND ${mpirun} -n 3 "${PARTS}" "${WORK}/box_compression.yaml" -o "${WORK}/ckpt"
                        --quiet --threads 1 --checkpoint-every 400
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("a 3-part run with --checkpoint-every (${err})" rc EQUAL 0)
expect("it writes checkpoint.h5" EXISTS ${WORK}/ckpt/checkpoint.h5)
execute_process(COMMAND ${mpirun} -n 2 "${PARTS}" "${WORK}/box_compression.yaml" -o "${WORK}/ckpt"
                        --quiet --threads 1 --restart "${WORK}/ckpt/checkpoint.h5"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
expect("--restart on 2 parts resumes (${err})" rc EQUAL 0)
file(READ "${WORK}/ckpt/run_summary.json" summary)
string(JSON restart GET "${summary}" restart_step)
expect("resumed from step 800 (got ${restart})" restart EQUAL 800)
foreach(probe probe_lid_force.csv probe_bulge.csv)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/one/${probe}"
                          "${WORK}/ckpt/${probe}" RESULT_VARIABLE same)
  expect("${probe} after a 3 → 2 part restart is the one-device file" same EQUAL 0)
endforeach()

# A scene naming a model that does not exist: an error naming the key, non-zero on every rank.
file(WRITE "${WORK}/bad.yaml" "title: bad\nmodel: missing.h5\neffects: [elasticity]\nduration: 0.1\n")
execute_process(COMMAND ${mpirun} -n 2 "${PARTS}" "${WORK}/bad.yaml" -o "${WORK}/bad" --quiet
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("a bad scene exits non-zero" NOT rc EQUAL 0)
string(FIND "${out}${err}" "missing.h5" pos)
expect("the error names the missing model (${out}${err})" pos GREATER -1)

# sinew-simulate --explain --parts P prints the partition; too many parts name the field.
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" --explain --parts 3
                        --device cpu --threads 1
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("--explain --parts 3 exits 0 (${err})" rc EQUAL 0)
string(FIND "${out}" "Partition: 3 parts, slabs along lattice axis" pos)
expect("--explain --parts 3 prints the partition (${out})" pos GREATER -1)
string(FIND "${out}" "exchanged per step:" pos)
expect("--explain --parts 3 prints the bytes per step" pos GREATER -1)
execute_process(COMMAND "${SIMULATE}" "${WORK}/box_compression.yaml" --explain --parts 12
                        --device cpu --threads 1
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("--parts 12 on 9 node layers fails" NOT rc EQUAL 0)
string(FIND "${out}${err}" "only 9 node layers" pos)
expect("the error says why (${out}${err})" pos GREATER -1)
