# train-basis and register --wall-basis end to end: three pelvis phantoms of one patient (the same moving anatomy,
# bladders filled by 4, 8 and 6 mm), a basis trained on the first two daily scans, and the third registered with
# the walls moving in it. Checks: the moving anatomy is the same (the basis's premise), train-basis writes a basis
# file, register runs with it, fits the prostate inside its bounds and says that the interval is not calibrated
# for a trained basis; more modes than the basis has is a usage error (exit 2) naming --basis-modes, and a missing
# basis file a one-line error naming the file.
# Run with: cmake -DCLI=<biomechreg> -DOUT=<scratch dir> -P biomechregTrainBasis.cmake
file(REMOVE_RECURSE ${OUT})
foreach(filling "a 4 2" "b 8 4" "c 6 3")
  separate_arguments(filling)
  list(GET filling 0 name)
  list(GET filling 1 bladder)
  list(GET filling 2 rectum)
  execute_process(COMMAND ${CLI} phantom --scene pelvis --size 100,80,80 --spacing 2,2,2 --bladder-mm ${bladder}
    --rectum-mm ${rectum} --true-E-kPa 100 --out ${OUT}/${name} RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "phantom ${name} failed")
  endif()
endforeach()
file(SHA256 ${OUT}/a/moving_labels.nrrd moving_a)
file(SHA256 ${OUT}/c/moving_labels.nrrd moving_c)
if(NOT moving_a STREQUAL moving_c)
  message(FATAL_ERROR "the phantoms' moving anatomy differs between fillings: a basis of one patient needs one")
endif()

execute_process(COMMAND ${CLI} train-basis --moving-labels ${OUT}/a/moving_labels.nrrd
  --fixed-labels ${OUT}/a/fixed_labels.nrrd,${OUT}/b/fixed_labels.nrrd --scene ${OUT}/a/scene.json
  --out ${OUT}/basis.json RESULT_VARIABLE rc OUTPUT_VARIABLE trained ERROR_VARIABLE trained_err)
message(STATUS "${trained}${trained_err}")
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/basis.json)
  message(FATAL_ERROR "train-basis failed (${rc})")
endif()
file(READ ${OUT}/basis.json basis LIMIT 200)
if(NOT basis MATCHES "biomechreg-wall-motion-basis")
  message(SEND_ERROR "the basis file does not name its format")
endif()

set(pair --moving-ct ${OUT}/c/moving_ct.nrrd --moving-labels ${OUT}/c/moving_labels.nrrd
  --fixed-ct ${OUT}/c/fixed_ct.nrrd --fixed-labels ${OUT}/c/fixed_labels.nrrd --scene ${OUT}/c/scene.json)
execute_process(COMMAND ${CLI} register ${pair} --wall-basis ${OUT}/basis.json --outputs report --out ${OUT}/reg
  RESULT_VARIABLE rc OUTPUT_VARIABLE registered ERROR_VARIABLE registered_err)
message(STATUS "${registered}${registered_err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "register --wall-basis failed (${rc})")
endif()
# The fit (at 2 mm voxels the modulus is not stated, the fit still is; report.json holds it).
file(READ ${OUT}/reg/report.json report)
string(JSON modulus ERROR_VARIABLE no_modulus GET "${report}" youngs_modulus_kPa prostate)
message(STATUS "fit with the trained basis: ${modulus} kPa (truth 100)")
# The pelvis scene bounds the prostate's modulus to 20-600 kPa: an estimate on a bound is not a fit.
if(NOT modulus OR modulus LESS_EQUAL 20.1 OR modulus GREATER_EQUAL 599)
  message(SEND_ERROR "register --wall-basis fitted no prostate modulus inside its bounds (${modulus}${no_modulus})")
endif()
if(NOT registered MATCHES "trained basis")
  message(SEND_ERROR "register --wall-basis does not say that the interval is not calibrated for a trained basis")
endif()

execute_process(COMMAND ${CLI} register ${pair} --wall-basis ${OUT}/basis.json --basis-modes 5 --out ${OUT}/reg5
  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--basis-modes")
  message(SEND_ERROR "more modes than the basis has: exit ${rc} (expected 2), \"${err}\"")
endif()
execute_process(COMMAND ${CLI} register ${pair} --wall-basis ${OUT}/missing.json --out ${OUT}/reg_missing
  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "missing.json")
  message(SEND_ERROR "a missing basis file: exit ${rc}, \"${err}\"")
endif()
