# The README's demo command after the build, exactly as `scripts/setup.sh demo` runs it (scripts/run_demo.sh):
# it must exit 0, report the recovered modulus, and leave the outputs the README's walk-through names.
# Run with: cmake -DSCRIPT=<scripts/run_demo.sh> -DBUILD=<build dir> -DDIR=<scratch dir> -P readmeDemoCheck.cmake
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})
execute_process(COMMAND bash ${SCRIPT} ${BUILD} WORKING_DIRECTORY ${DIR}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "scripts/run_demo.sh: exit code ${rc}: ${err}")
endif()
if(NOT out MATCHES "prostate Young's modulus: true 100.0 kPa, recovered [0-9.]+ kPa")
  message(FATAL_ERROR "the demo did not report the recovered modulus")
endif()
foreach(f fixed_labels.nrrd moving_labels.nrrd scene.json truth.json register/field.nrrd register/warped_ct.nrrd
    register/report.json register/history.csv register/sweep.csv register/sweep.png)
  if(NOT EXISTS ${DIR}/biomechreg-demo/${f})
    message(FATAL_ERROR "the demo did not write biomechreg-demo/${f}")
  endif()
endforeach()
message(STATUS "ok: the README's demo command exits 0 and writes its outputs and plot")
