# biomechreg markers on a small pelvis phantom (100 x 80 x 40 voxels of 2 x 2 x 4 mm, a coarse truth mesh):
# - from the tracked seeds (0.5 mm noise per axis): every output is written, report.json holds the leave-one-out
#   TRE, IoU and D of fem, rigid, tps and none, and the FEM prostate overlaps the true treatment prostate better
#   than the unmoved planning prostate (the phantom moves it by several mm; a field that did not carry it fails);
# - from the exact seeds with no prior (--regularization 0), the FEM interpolates the three markers: 9 equations,
#   over 100 load parameters, fitted to < 0.01 mm (the LM's tolerance is far below);
# - bad input: an unpaired marker id (exit 1, one line naming it, no output directory), a non-positive box margin
#   (exit 2).
# Run with: cmake -DCLI=<biomechreg> -DOUT=<scratch dir> -P biomechregMarkersCheck.cmake
file(REMOVE_RECURSE ${OUT})
set(P ${OUT}/phantom)
execute_process(COMMAND ${CLI} phantom --scene pelvis --size 100,80,40 --spacing 2,2,4 --truth-mesh-scale 2
  --bladder-mm 8 --rectum-mm 5 --out ${P} RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "phantom failed: ${err}")
endif()
set(common --planning-ct ${P}/moving_ct.nrrd --planning-labels ${P}/moving_labels.nrrd --scene ${P}/scene.json
  --modulus prostate=60 --planning-markers ${P}/landmarks_moving.csv)

function(run name rc_expected)
  execute_process(COMMAND ${CLI} markers ${common} ${ARGN} --out ${OUT}/${name}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL rc_expected)
    message(FATAL_ERROR "markers ${name}: exit code ${rc}, expected ${rc_expected}\n${out}${err}")
  endif()
  set(err "${err}" PARENT_SCOPE)
endfunction()

# The largest value of the JSON array at methods.<method>.<key> of a report.
function(largest report method key var)
  string(JSON n LENGTH "${report}" methods ${method} ${key})
  set(best 0)
  math(EXPR last "${n} - 1")
  foreach(i RANGE ${last})
    string(JSON v GET "${report}" methods ${method} ${key} ${i})
    if(v GREATER best)
      set(best ${v})
    endif()
  endforeach()
  set(${var} ${best} PARENT_SCOPE)
endfunction()

run(tracked 0 --treatment-markers ${P}/landmarks_tracked.csv --treatment-labels ${P}/fixed_labels.nrrd)
foreach(f field.nrrd warped_ct.nrrd warped_labels.nrrd warped_labels_rigid.nrrd warped_labels_tps.nrrd report.json)
  if(NOT EXISTS ${OUT}/tracked/${f})
    message(SEND_ERROR "tracked: ${f} was not written")
  endif()
endforeach()
file(READ ${OUT}/tracked/report.json report)
foreach(m fem rigid tps none)
  string(JSON loo GET "${report}" methods ${m} leave_one_out_rms_mm)
  string(JSON iou GET "${report}" methods ${m} intersection_over_union)
  string(JSON d GET "${report}" methods ${m} mean_surface_distance_mm)
  message(STATUS "${m}: leave-one-out RMS ${loo} mm, IoU ${iou}, D ${d} mm")
  set(iou_${m} ${iou})
endforeach()
if(NOT iou_fem GREATER iou_none)
  message(SEND_ERROR "the FEM prostate (IoU ${iou_fem}) is no closer to the truth than the unmoved one (${iou_none})")
endif()

run(exact 0 --treatment-markers ${P}/landmarks_fixed.csv --regularization 0 --leave-one-out off)
file(READ ${OUT}/exact/report.json report)
largest("${report}" fem fit_residual_mm fit)
message(STATUS "exact markers, no prior: FEM fit max ${fit} mm")
if(fit GREATER 0.01)
  message(SEND_ERROR "the FEM does not interpolate three exact markers: max residual ${fit} mm")
endif()

file(READ ${P}/landmarks_fixed.csv markers)
string(REPLACE "seed1," "other," markers "${markers}")
file(WRITE ${OUT}/renamed.csv "${markers}")
run(unpaired 1 --treatment-markers ${OUT}/renamed.csv)
if(NOT err MATCHES "seed1" OR EXISTS ${OUT}/unpaired)
  message(SEND_ERROR "unpaired id: the error does not name seed1, or an output directory was left: ${err}")
endif()
string(STRIP "${err}" err)
string(FIND "${err}" "\n" newline)
if(NOT newline EQUAL -1)
  message(SEND_ERROR "unpaired id: the error is more than one line: ${err}")
endif()
run(margin 2 --treatment-markers ${P}/landmarks_fixed.csv --box-margin-mm 0)
