# Determinism: the same inputs give bit-identical outputs with 1 and 2 threads (ITK's work units and
# OpenBLAS's environment, through ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS and OPENBLAS_NUM_THREADS; biomechreg runs the BLAS
# on one thread whatever the latter says: bmr::ConfigureNumerics), for the joint
# estimation (`register`: fields, warped images, the recovered modulus, the rescan interval, whose resamples
# run one at a time with 1 thread and two at once with 2, the default concurrency) and for the Demons baseline.
# Run with: cmake -DCLI=<biomechreg> -DDIR=<spheres phantom dir> -DOUT=<scratch dir> -P biomechregDeterminism.cmake
foreach(threads 1 2)
  set(ENV{ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS} ${threads})
  set(ENV{OPENBLAS_NUM_THREADS} ${threads})
  execute_process(COMMAND ${CLI} register --moving-ct ${DIR}/moving_ct.nrrd --moving-labels ${DIR}/moving_labels.nrrd
    --fixed-ct ${DIR}/fixed_ct.nrrd --fixed-labels ${DIR}/fixed_labels.nrrd --scene ${DIR}/scene.json
    --resamples 3 --outputs all --out ${OUT}/register_${threads} RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "register with ${threads} threads failed")
  endif()
  execute_process(COMMAND ${CLI} demons --moving-ct ${DIR}/moving_ct.nrrd --fixed-ct ${DIR}/fixed_ct.nrrd
    --demons-levels 2 --demons-iterations 20 --out ${OUT}/demons_${threads} RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "demons with ${threads} threads failed")
  endif()
endforeach()
foreach(f register/field.nrrd register/forward_field.nrrd register/warped_ct.nrrd register/warped_labels.nrrd
    register/mesh.vtu demons/field.nrrd demons/warped_ct.nrrd)
  string(REPLACE "/" "_1/" a ${f})
  string(REPLACE "/" "_2/" b ${f})
  file(SHA256 ${OUT}/${a} ha)
  file(SHA256 ${OUT}/${b} hb)
  if(NOT ha STREQUAL hb)
    message(SEND_ERROR "${f} differs between 1 and 2 threads")
  else()
    message(STATUS "${f}: identical with 1 and 2 threads")
  endif()
endforeach()
foreach(threads 1 2)
  file(READ ${OUT}/register_${threads}/report.json report)
  string(JSON E_${threads} GET "${report}" youngs_modulus_kPa inner)
endforeach()
message(STATUS "recovered inner modulus: ${E_1} kPa (1 thread), ${E_2} kPa (2 threads)")
if(NOT E_1 STREQUAL E_2)
  message(SEND_ERROR "the recovered modulus differs between 1 and 2 threads: ${E_1} vs ${E_2}")
endif()
file(READ ${OUT}/register_1/report.json report1)
file(READ ${OUT}/register_2/report.json report2)
string(JSON interval1 GET "${report1}" youngs_modulus_interval)
string(JSON interval2 GET "${report2}" youngs_modulus_interval)
if(NOT interval1 STREQUAL interval2)
  message(SEND_ERROR "the rescan interval differs between 1 and 2 threads:\n${interval1}\n${interval2}")
else()
  message(STATUS "rescan interval identical with 1 and 2 threads")
endif()
