# Runs one biomechreg command and checks both its exit code (0) and its output (stdout must match EXPECT,
# a regular expression naming what the command reports), so that a run that exits 0 without doing its job
# fails. Run with: cmake -DCLI=<biomechreg> -DARGS="a;b;c" -DEXPECT=<regex> -P biomechregRun.cmake
execute_process(COMMAND ${CLI} ${ARGS} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "biomechreg ${ARGS}: exit code ${rc}: ${err}")
endif()
if(NOT out MATCHES "${EXPECT}")
  message(FATAL_ERROR "biomechreg: the output does not match '${EXPECT}'")
endif()
message(STATUS "ok: output matches '${EXPECT}'")
