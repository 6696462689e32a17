# biomechreg --task-trace on the spheres phantom: register (with its interval, so that resamples nest their solves)
# writes the trace, and benchmarks/replay_task_trace.py replays it. Replayed on the recorded thread count it gives
# the recorded wall time back within 2 % (the same durations rearranged: a region, wait or background the replay
# misplaces shows as a difference), and 16 workers take no longer than one.
# Run with: cmake -DCLI=<biomechreg> -DDIR=<spheres phantom> -DOUT=<scratch> -DREPLAY=<replay_task_trace.py> -P ...
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${CLI} --threads 2 --task-trace ${OUT}/trace.csv register
  --moving-ct ${DIR}/moving_ct.nrrd --moving-labels ${DIR}/moving_labels.nrrd --fixed-ct ${DIR}/fixed_ct.nrrd
  --fixed-labels ${DIR}/fixed_labels.nrrd --scene ${DIR}/scene.json --outputs report --out ${OUT}/register
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "register --task-trace: exit code ${rc}\n${out}\n${err}")
endif()
if(NOT EXISTS ${OUT}/trace.csv)
  message(FATAL_ERROR "register --task-trace wrote no trace")
endif()
execute_process(COMMAND python3 ${REPLAY} ${OUT}/trace.csv 1 2 16
  RESULT_VARIABLE rc OUTPUT_VARIABLE replay ERROR_VARIABLE err)
message(STATUS "${replay}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "replay_task_trace.py: exit code ${rc}\n${err}")
endif()
string(REGEX MATCH "recorded: ([0-9.]+) s on 2 threads" _ "${replay}")
set(recorded ${CMAKE_MATCH_1})
string(REGEX MATCH "P =   1: ([0-9.]+) s" _ "${replay}")
set(one ${CMAKE_MATCH_1})
string(REGEX MATCH "P =   2: ([0-9.]+) s" _ "${replay}")
set(two ${CMAKE_MATCH_1})
string(REGEX MATCH "P =  16: ([0-9.]+) s" _ "${replay}")
set(sixteen ${CMAKE_MATCH_1})
if(NOT recorded OR NOT one OR NOT two OR NOT sixteen)
  message(FATAL_ERROR "the replay printed no recorded time on 2 threads or no prediction for 1, 2 and 16")
endif()
execute_process(COMMAND python3 -c "import sys; r,a,b,c=map(float,sys.argv[1:]); sys.exit(0 if abs(b-r)<=0.02*r and a>=c else 1)"
  ${recorded} ${one} ${two} ${sixteen} RESULT_VARIABLE bad)
if(NOT bad EQUAL 0)
  message(FATAL_ERROR "the replay on 2 workers (${two} s) is not within 2 % of the recorded ${recorded} s, or 16 "
    "workers take longer than one (1: ${one} s, 2: ${two} s, 16: ${sixteen} s)")
endif()
message(STATUS "ok: the trace replays to the recorded time on 2 workers (${two} of ${recorded} s); 1: ${one} s, 16: ${sixteen} s")
