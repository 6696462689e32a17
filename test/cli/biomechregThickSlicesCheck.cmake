# biomechreg register on a pelvis phantom pair with clinical slices (1 x 1 x 3 mm, the fixed grid shifted by a
# sub-voxel offset; a coarse truth mesh for speed):
# - the run exits 0; the organs are not interpolated between slices by default (report.json: slice_interpolation
#   false), and are with --slice-interpolation on;
# - with both scans at 3 mm slices the interval is the 3 mm calibration's (method slice-calibration,
#   calibrated_slice_mm 3, the statement names it), no rescan is computed, and no warning says "not determined";
# - where no calibration holds (slices interpolated, which none measured) no modulus is stated: the statement says
#   "not determined", both ends are undetermined, the reason names the 3 mm voxels, and the run's warning says the
#   same thing (the warning and the statement must never disagree);
# - raised by --uncertainty-options voxel-limit-mm=3.5 (the advanced settings' group, read as
#   --uncertainty-voxel-limit-mm), the interval is stated and the warning then says that it is stated
#   beyond the geometry where coverage was shown;
# - a bladder that barely filled between the scans lies outside the calibration's volume changes: no modulus, the
#   reason names the bladder's volume change, and the run's warning says the same.
# Run with: cmake -DCLI=<biomechreg> -DOUT=<scratch dir> -P biomechregThickSlicesCheck.cmake
file(REMOVE_RECURSE ${OUT})
# A 1 x 1 x 3 mm pelvis pair of 80 kPa with the bladder's wall moved by BLADDER mm into OUT/NAME; sets inputs, the
# arguments that register it.
function(make_phantom name bladder)
  set(P ${OUT}/${name})
  execute_process(COMMAND ${CLI} phantom --scene pelvis --size 200,160,54 --spacing 1,1,3 --bladder-mm ${bladder}
    --rectum-mm 4 --true-E-kPa 80 --fixed-grid-shift-voxels 0.5 --truth-mesh-scale 1.5 --out ${P}
    RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "phantom (${bladder} mm filling) failed: ${err}")
  endif()
  set(inputs --moving-ct ${P}/moving_ct.nrrd --moving-labels ${P}/moving_labels.nrrd --fixed-ct ${P}/fixed_ct.nrrd
    --fixed-labels ${P}/fixed_labels.nrrd --scene ${P}/scene.json --outputs report PARENT_SCOPE)
endfunction()
make_phantom(phantom 8)

# Runs register with the inputs and ARGN into OUT/<name>; sets report (report.json) and output (what it printed).
function(register_into name)
  execute_process(COMMAND ${CLI} register ${inputs} ${ARGN} --out ${OUT}/${name}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "register ${ARGN} at 1 x 1 x 3 mm: exit code ${rc}")
  endif()
  file(READ ${OUT}/${name}/report.json json)
  set(report "${json}" PARENT_SCOPE)
  set(output "${out}${err}" PARENT_SCOPE)
endfunction()

register_into(reg)
string(JSON interpolated GET "${report}" slice_interpolation)
string(JSON method GET "${report}" youngs_modulus_interval prostate method)
string(JSON calibrated GET "${report}" youngs_modulus_interval prostate calibrated_slice_mm)
string(JSON statement GET "${report}" youngs_modulus_interval prostate statement)
string(JSON reason GET "${report}" youngs_modulus_interval prostate not_determined_reason)
string(JSON resamples LENGTH "${report}" youngs_modulus_interval prostate resamples_kPa)
if(interpolated)
  message(SEND_ERROR "report.json: slice_interpolation is ${interpolated} by default")
endif()
if(NOT method STREQUAL "slice-calibration" OR NOT calibrated EQUAL 3 OR NOT reason STREQUAL "" OR
   NOT resamples EQUAL 0 OR NOT statement MATCHES "calibrated on phantom pairs with 3 mm slices")
  message(SEND_ERROR "at 3 mm the 3 mm calibration is not stated: ${method}, ${calibrated} mm, '${statement}'")
endif()
if("${output}" MATCHES "not determined")
  message(SEND_ERROR "a calibrated statement beside a warning that says 'not determined'")
endif()

register_into(interpolated --slice-interpolation on)
string(JSON statement GET "${report}" youngs_modulus_interval prostate statement)
string(JSON reason GET "${report}" youngs_modulus_interval prostate not_determined_reason)
string(JSON lowerOk GET "${report}" youngs_modulus_interval prostate lower_end_determined)
string(JSON upperOk GET "${report}" youngs_modulus_interval prostate upper_end_determined)
if(NOT statement MATCHES "not determined: label voxels of up to 3 mm" OR lowerOk OR upperOk)
  message(SEND_ERROR "uncalibrated, a modulus was stated: '${statement}' (determined ${lowerOk}/${upperOk})")
endif()
string(FIND "${output}" "warning: ${reason}" at) # the reason holds brackets: a plain search, not a regex
if(at EQUAL -1)
  message(SEND_ERROR "the run's warning does not say what the statement says ('${reason}')")
endif()

register_into(raised --uncertainty-options voxel-limit-mm=3.5 --resamples 3 --slice-interpolation on)
string(JSON interpolated GET "${report}" slice_interpolation)
if(NOT interpolated)
  message(SEND_ERROR "report.json: slice_interpolation is ${interpolated} with --slice-interpolation on")
endif()
string(JSON reason GET "${report}" youngs_modulus_interval prostate not_determined_reason)
string(JSON resamples LENGTH "${report}" youngs_modulus_interval prostate resamples_kPa)
if(NOT reason STREQUAL "" OR NOT resamples EQUAL 3)
  message(SEND_ERROR "with the limit raised the interval is not stated from 3 rescans ('${reason}', ${resamples})")
endif()
if(NOT "${output}" MATCHES "warning: label voxels of up to 3 mm: the modulus's interval is stated although")
  message(SEND_ERROR "with the limit raised the run does not warn that coverage was not shown at 3 mm")
endif()
# A bladder that barely filled (1 mm of wall motion, about 11 mL) lies outside the 3 mm calibration's volume changes:
# no modulus, the reason names the bladder's volume change, and the run's warning says the same.
make_phantom(phantom_empty 1)
register_into(empty)
string(JSON statement GET "${report}" youngs_modulus_interval prostate statement)
string(JSON reason GET "${report}" youngs_modulus_interval prostate not_determined_reason)
string(JSON lowerOk GET "${report}" youngs_modulus_interval prostate lower_end_determined)
string(JSON upperOk GET "${report}" youngs_modulus_interval prostate upper_end_determined)
if(NOT reason MATCHES "bladder's volume change between the scans, and this pair's, [0-9.]+ mL, lies outside" OR
   lowerOk OR upperOk OR NOT statement MATCHES "not determined")
  message(SEND_ERROR "a 1 mm filling at 3 mm: a modulus was stated or the reason is not the filling: '${statement}'")
endif()
string(FIND "${output}" "warning: the modulus is not determined: ${reason}" at)
if(at EQUAL -1)
  message(SEND_ERROR "the run's warning does not say what the statement says ('${reason}')")
endif()
message(STATUS "ok: at 3 mm the calibrated interval, uncalibrated none unless asked, outside the calibrated "
  "fillings none, and the warnings agree")
