# phantom --truth-geometry anatomy: the truth is meshed from the analytic anatomy (truth.json says so), which gives
# another truth mesh than the label map's voxels (the mesher's own test checks that its surfaces lie on the analytic
# ones); it is the default, unrefined for the spheres (the same mesh as the explicit choice). --truth-refine-size-mm
# refines the truth around the core (more elements, recorded in truth.json).
# Run with: cmake -DCLI=<biomechreg> -DOUT=<scratch dir> -P biomechregTruthGeometryCheck.cmake
file(REMOVE_RECURSE ${OUT})
foreach(geometry voxels anatomy)
  execute_process(COMMAND ${CLI} phantom --scene spheres --size 40,40,40 --spacing 2,2,2 --seed 5
    --truth-mesh-scale 1.5 --truth-geometry ${geometry} --out ${OUT}/${geometry} RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "phantom --truth-geometry ${geometry} failed")
  endif()
  file(READ ${OUT}/${geometry}/truth.json json)
  string(JSON recorded GET "${json}" truth_mesh geometry)
  string(JSON tetrahedra_${geometry} GET "${json}" truth_mesh tetrahedra)
  message(STATUS "--truth-geometry ${geometry}: truth.json says ${recorded}, ${tetrahedra_${geometry}} tetrahedra")
  if(NOT recorded STREQUAL geometry)
    message(SEND_ERROR "truth.json records the truth geometry as \"${recorded}\", not \"${geometry}\"")
  endif()
endforeach()
if(tetrahedra_voxels EQUAL tetrahedra_anatomy)
  message(SEND_ERROR "the anatomy's truth mesh has as many tetrahedra as the voxels' (${tetrahedra_voxels})")
endif()
execute_process(COMMAND ${CLI} phantom --scene spheres --size 40,40,40 --spacing 2,2,2 --seed 5 --truth-mesh-scale 1.5
  --out ${OUT}/default RESULT_VARIABLE rc OUTPUT_QUIET)
file(READ ${OUT}/default/truth.json json)
string(JSON recorded GET "${json}" truth_mesh geometry)
string(JSON tetrahedra_default GET "${json}" truth_mesh tetrahedra)
string(JSON refine_default GET "${json}" truth_mesh refine_near_size_mm)
if(NOT rc EQUAL 0 OR NOT recorded STREQUAL "anatomy" OR NOT tetrahedra_default EQUAL tetrahedra_anatomy
   OR NOT refine_default EQUAL 0)
  message(SEND_ERROR "the spheres' default truth is \"${recorded}\" with ${tetrahedra_default} tetrahedra and "
    "refinement ${refine_default} mm, not the unrefined anatomy (${tetrahedra_anatomy})")
endif()
execute_process(COMMAND ${CLI} phantom --scene spheres --size 40,40,40 --spacing 2,2,2 --seed 5 --truth-mesh-scale 1.5
  --truth-geometry anatomy --truth-refine-size-mm 2 --out ${OUT}/refined RESULT_VARIABLE rc OUTPUT_QUIET)
file(READ ${OUT}/refined/truth.json json)
string(JSON refined GET "${json}" truth_mesh tetrahedra)
string(JSON refine_size GET "${json}" truth_mesh refine_near_size_mm)
message(STATUS "--truth-refine-size-mm 2: ${refined} tetrahedra (${tetrahedra_anatomy} without)")
if(NOT rc EQUAL 0 OR NOT refined GREATER tetrahedra_anatomy OR NOT refine_size EQUAL 2)
  message(SEND_ERROR "the truth refined near the core has ${refined} tetrahedra, not more than ${tetrahedra_anatomy}")
endif()
