# Set-up shared by cli_end_to_end.cmake and paraview_opens_results.cmake: an empty folder WORK
# holding a copy of data/scenes/box_compression.yaml and the model it names, compression_block.h5
# (an 8 × 8 × 8 block of 2.5 mm voxels written by sinew-generate). Fails the test when sinew-generate
# fails. Inputs: -DGENERATE=<sinew-generate> -DSCENES=<data/scenes> -DWORK=<dir>
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
file(COPY "${SCENES}/box_compression.yaml" DESTINATION "${WORK}")
execute_process(COMMAND "${GENERATE}" box --dims 8 8 8 --voxel-size 0.0025
                        --material soft:3000:0.45:1000 -o "${WORK}/compression_block.h5" -q
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: sinew-generate box exited ${rc}")
endif()
