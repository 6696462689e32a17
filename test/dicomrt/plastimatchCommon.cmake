# Shared by the DICOM-RT tests that use plastimatch as the independent writer: checks that plastimatch is
# installed, empties the scratch directory OUT and defines run(COMMAND...), which stops the test on a non-zero exit.
find_program(PLASTIMATCH plastimatch)
if(NOT PLASTIMATCH)
  message(FATAL_ERROR "plastimatch is not installed (scripts/setup.sh installs Debian's package)")
endif()
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${ARGN}: exit code ${rc}\n${out}\n${err}")
  endif()
endfunction()
