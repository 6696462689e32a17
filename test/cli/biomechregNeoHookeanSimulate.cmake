# simulate with "model": "neo_hookean" (issue 16): the spheres phantom's truth scene with its model switched.
# The outer surface's prescribed 1.5 mm inward motion must be reached (max |u| 1.5 mm, a displacement load),
# by Newton iterations reported on the FEM stage, with the field written. Inputs: CLI, DIR (phantom), OUT.
file(READ ${DIR}/truth_scene.json scene)
string(REPLACE "\"model\": \"linear\"" "\"model\": \"neo_hookean\"" scene "${scene}")
if(NOT scene MATCHES "\"model\": \"neo_hookean\"")
  message(FATAL_ERROR "the phantom's truth scene names no model: ${DIR}/truth_scene.json")
endif()
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
file(WRITE ${OUT}/scene_neo_hookean.json "${scene}")
execute_process(COMMAND ${CLI} simulate --moving-labels ${DIR}/moving_labels.nrrd --scene ${OUT}/scene_neo_hookean.json
                        --out ${OUT}/sim
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "simulate with the neo-Hookean model failed (exit ${rc})")
endif()
if(NOT out MATCHES "max \\|u\\| 1\\.5 mm, neo-Hookean: [1-9][0-9]* Newton iterations in [1-9][0-9]* load increments, [1-9][0-9]* factorizations")
  message(FATAL_ERROR "the FEM stage does not report the prescribed 1.5 mm reached by Newton iterations")
endif()
if(NOT EXISTS ${OUT}/sim/field.nrrd)
  message(FATAL_ERROR "no field written")
endif()
