# biomechreg dose on a small pelvis phantom (100 x 80 x 40 voxels of 2 x 2 x 4 mm, a coarse truth mesh: ~2 s):
# - the synthetic plan (--plan-margin 5): dvh.csv and dose_metrics.csv with their headers, and the prostate's D95
#   inside the band the plan's closed form allows;
# - the written dose.nrrd read back with --dose gives the same dose_metrics.csv, byte for byte (same grid, no
#   resampling, float stored as float);
# - the dose warped with the phantom's truth field (--field) onto the fixed labels;
# - bad inputs: exit 1, one line on stderr, no output directory.
# Run with: cmake -DCLI=<biomechreg> -DOUT=<scratch dir> -P biomechregDoseCheck.cmake
file(REMOVE_RECURSE ${OUT})
set(P ${OUT}/phantom)
execute_process(COMMAND ${CLI} phantom --scene pelvis --size 100,80,40 --spacing 2,2,4 --truth-mesh-scale 2
  --out ${P} RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "phantom failed: ${err}")
endif()

function(run_dose name)
  execute_process(COMMAND ${CLI} dose --scene ${P}/scene.json ${ARGN} --out ${OUT}/${name}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "dose ${name}: exit code ${rc}\n${out}${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

# The field of the metrics table in column COLUMN (a name of its header) of the row of STRUCTURE.
function(metric dir structure column var)
  file(STRINGS ${dir}/dose_metrics.csv lines)
  list(GET lines 0 header)
  string(REPLACE "," ";" header "${header}")
  list(FIND header ${column} index)
  foreach(line ${lines})
    string(REPLACE "," ";" fields "${line}")
    list(GET fields 0 name)
    if(name STREQUAL structure)
      list(GET fields ${index} value)
      set(${var} ${value} PARENT_SCOPE)
      return()
    endif()
  endforeach()
  message(FATAL_ERROR "${dir}/dose_metrics.csv has no row ${structure}")
endfunction()

# 1. The plan: PTV = prostate + 5 mm, Rx 78 Gy, penumbra 6 mm (sigma = 6 / (2 * 0.8416) = 3.565 mm).
run_dose(plan --labels ${P}/moving_labels.nrrd --plan-margin 5)
if(NOT out MATCHES "conformal plan \\.\\.\\. +[0-9.]+ s  PTV = prostate \\+ 5 mm, Rx 78 Gy, penumbra 6 mm")
  message(SEND_ERROR "the plan's stage line is missing:\n${out}")
endif()
foreach(f dvh.csv dose_metrics.csv dose.nrrd)
  if(NOT EXISTS ${OUT}/plan/${f})
    message(SEND_ERROR "dose wrote no ${f}")
  endif()
endforeach()
if(NOT EXISTS ${OUT}/plan/dvh.png AND NOT out MATCHES "warning: no dvh.png")
  message(SEND_ERROR "neither dvh.png nor a warning saying why not")
endif()
file(STRINGS ${OUT}/plan/dose_metrics.csv lines)
list(GET lines 0 header)
set(expected "organ,a,gEUD_Gy,Dmean_Gy,D95_Gy,D2_Gy,D98_Gy,Dmin_Gy,Dmax_Gy,V50Gy_pct,V60Gy_pct,V65Gy_pct,V70Gy_pct,V75Gy_pct,volume_cc,voxels,outside_dose_grid_pct")
if(NOT header STREQUAL expected)
  message(SEND_ERROR "dose_metrics.csv header:\n${header}\nexpected\n${expected}")
endif()
file(STRINGS ${OUT}/plan/dvh.csv lines LIMIT_COUNT 2)
list(GET lines 0 header)
if(NOT header MATCHES "^dose_Gy,bladder_cumulative_pct,.*prostate_cumulative_pct,.*anterior_rectal_wall_cumulative_pct,bladder_differential_pct,.*anterior_rectal_wall_differential_pct$")
  message(SEND_ERROR "dvh.csv header: ${header}")
endif()
# D95 of the prostate: every prostate voxel lies inside the prostate, where the dose is at least
# Rx Phi(m / sigma) = 78 Phi(1.4025) = 71.73 Gy; the coldest 5 % of an 18 mm prostate is its outer 0.3 mm, the
# outer voxel layer, whose centres lie at most half the largest spacing (2 mm) inside its faces:
# D95 <= Rx Phi((m + 2) / sigma) = 78 Phi(1.9635) = 76.07 Gy.
metric(${OUT}/plan prostate D95_Gy d95)
metric(${OUT}/plan prostate a a)
message(STATUS "prostate D95 ${d95} Gy (band 71.73-76.07 Gy), a ${a}")
if(NOT (d95 GREATER 71.73 AND d95 LESS 76.07))
  message(SEND_ERROR "prostate D95 ${d95} Gy outside [71.73, 76.07] Gy")
endif()
if(NOT a EQUAL -10)
  message(SEND_ERROR "the prostate's default gEUD parameter is ${a}, not -10")
endif()
metric(${OUT}/plan anterior_rectal_wall voxels wall)
if(NOT wall GREATER 0)
  message(SEND_ERROR "the anterior rectal wall is empty")
endif()

# 2. The written dose read back: the same table.
run_dose(readback --labels ${P}/moving_labels.nrrd --dose ${OUT}/plan/dose.nrrd --plot off)
file(READ ${OUT}/plan/dose_metrics.csv planned)
file(READ ${OUT}/readback/dose_metrics.csv read)
if(NOT planned STREQUAL read)
  message(SEND_ERROR "the plan's dose read back gives other metrics:\n${planned}\n${read}")
endif()

# 3. Warped with the truth field onto the fixed labels, --eud-a and --v-doses: the tissue carries its planned dose;
# the phantom moves the prostate by a few mm, less than the 5 mm margin, so its D95 stays above the 80 % level
# (0.8 Rx = 62.4 Gy, reached 3 mm outside the moving prostate).
run_dose(warped --labels ${P}/fixed_labels.nrrd --dose ${OUT}/plan/dose.nrrd --field ${P}/truth_field.nrrd
  --eud-a prostate=-20,rectum=12 --v-doses 70,74.1 --plot off)
metric(${OUT}/warped prostate D95_Gy d95)
metric(${OUT}/warped prostate a a)
metric(${OUT}/warped rectum a ar)
metric(${OUT}/warped prostate V74.1Gy_pct v741)
message(STATUS "warped: prostate D95 ${d95} Gy, V74.1Gy ${v741} %")
if(NOT (d95 GREATER 62.4 AND d95 LESS 78.001) OR NOT a EQUAL -20 OR NOT ar EQUAL 12)
  message(SEND_ERROR "warped dose: prostate D95 ${d95} Gy (expected 62.4-78), a ${a} and ${ar} (expected -20, 12)")
endif()

# 4. Bad inputs: one line on stderr, exit 1, nothing written.
function(expect_failure name regex)
  execute_process(COMMAND ${CLI} dose --scene ${P}/scene.json --labels ${P}/moving_labels.nrrd ${ARGN}
    --out ${OUT}/${name} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(REGEX MATCHALL "\n" newlines "${err}")
  list(LENGTH newlines count)
  if(NOT rc EQUAL 1 OR NOT count EQUAL 1 OR NOT err MATCHES "${regex}")
    message(SEND_ERROR "${name}: exit code ${rc} (expected 1), ${count} lines on stderr (expected 1):\n${err}")
  endif()
  if(EXISTS ${OUT}/${name})
    message(SEND_ERROR "${name}: a failed run left ${OUT}/${name}")
  endif()
endfunction()
expect_failure(missing "^biomechreg: error: cannot read dose image \"[^\"]*none.nrrd\"" --dose ${OUT}/none.nrrd)
expect_failure(negative "^biomechreg: error: dose image \"[^\"]*moving_ct.nrrd\": voxel \\[[0-9, ]+\\] holds -"
  --dose ${P}/moving_ct.nrrd)
expect_failure(target "no structure \"urethra\" for the plan's target" --plan-margin 5 --prostate urethra)
