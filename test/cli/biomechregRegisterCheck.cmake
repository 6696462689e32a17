# Checks the outputs of `biomechreg register` on a pelvis phantom pair in DIR (DIR/reg):
# - the stated prostate modulus (the default rescan interval's centre) is within 10 % of the truth (truth.json), and
#   its 95 % interval contains the truth with both ends determined (100 kPa lies well inside [20, 600] kPa).
#   The fixed scan is made on a finer, independent mesh and voxelized at 1 mm, so the shape change that
#   carries the modulus is seen through the label staircase; benchmarks/run_calibration_benchmark.sh measures
#   the coverage over 30-500 kPa;
# - the RMS distance of the deformed prostate surface nodes to the fixed prostate surface is below half
#   a voxel (0.5 mm);
# - the accepted outer iterates (history.csv, stage "outer") never increase Phi*;
# - the interval's standard deviation of log E lies in [0.01, 0.3] (the calibration benchmark's spread at
#   30-150 kPa); outside it the resamples or their statistics are wrong;
# - every promised output exists, report.json names the gauge, and the interval says which wall law it assumes
#   (the default's: walls along their normals).
# Run with: cmake -DDIR=<phantom dir> -P biomechregRegisterCheck.cmake
file(READ ${DIR}/truth.json truth)
file(READ ${DIR}/reg/report.json report)
string(JSON trueE GET "${truth}" youngs_modulus_kPa prostate)
string(JSON statedE GET "${report}" youngs_modulus_interval prostate estimate_kPa)
string(JSON lo95 GET "${report}" youngs_modulus_interval prostate interval_95_kPa 0)
string(JSON hi95 GET "${report}" youngs_modulus_interval prostate interval_95_kPa 1)
string(JSON lowerOk GET "${report}" youngs_modulus_interval prostate lower_end_determined)
string(JSON upperOk GET "${report}" youngs_modulus_interval prostate upper_end_determined)
string(JSON rms GET "${report}" surface_distance_mm prostate rms)
string(JSON gauge GET "${report}" gauge label)
# if() compares floating-point numbers; math() is integer-only, and the true modulus is a whole number.
math(EXPR lower "${trueE} * 9 / 10")
math(EXPR upper "${trueE} * 11 / 10")
message(STATUS "prostate E: true ${trueE} kPa, stated ${statedE} kPa (accepted ${lower}..${upper}), 95 % ${lo95}..${hi95}")
if(statedE LESS lower OR statedE GREATER upper)
  message(SEND_ERROR "stated prostate modulus ${statedE} kPa is more than 10 % from the true ${trueE} kPa")
endif()
if(NOT lowerOk OR NOT upperOk OR trueE LESS lo95 OR trueE GREATER hi95)
  message(SEND_ERROR "the 95 % interval ${lo95}..${hi95} kPa (determined: ${lowerOk}/${upperOk}) misses ${trueE} kPa")
endif()
message(STATUS "prostate surface RMS ${rms} mm (limit 0.5 mm)")
if(NOT rms LESS 0.5)
  message(SEND_ERROR "prostate surface RMS ${rms} mm is not below half a voxel (0.5 mm)")
endif()
string(JSON sigma GET "${report}" youngs_modulus_interval prostate sigma_log_E)
message(STATUS "prostate sigma(log E) ${sigma} (accepted 0.01..0.3)")
if(NOT sigma GREATER 0.01 OR NOT sigma LESS 0.3)
  message(SEND_ERROR "report.json: sigma_log_E of the prostate is ${sigma}, expected 0.01..0.3")
endif()
if(NOT gauge STREQUAL "soft_tissue")
  message(SEND_ERROR "report.json: gauge is '${gauge}', expected soft_tissue")
endif()
string(JSON assumes GET "${report}" youngs_modulus_interval prostate assumes)
if(NOT assumes MATCHES "along their normals")
  message(SEND_ERROR "report.json: the interval's 'assumes' does not name the default wall law: '${assumes}'")
endif()

file(STRINGS ${DIR}/reg/history.csv lines REGEX "^outer,")
list(LENGTH lines n)
if(n LESS 2)
  message(SEND_ERROR "history.csv holds ${n} outer iterations, expected at least 2")
endif()
set(previous "")
foreach(line ${lines})
  string(REPLACE "," ";" fields "${line}")
  list(GET fields 3 phi) # stage, iteration, E_prostate_kPa, phi_mm2, ...
  if(NOT previous STREQUAL "")
    if(phi GREATER previous)
      message(SEND_ERROR "outer Phi* increased from ${previous} to ${phi}")
    endif()
  endif()
  set(previous ${phi})
endforeach()
message(STATUS "${n} outer iterations, Phi* non-increasing")

foreach(f field.nrrd forward_field.nrrd warped_ct.nrrd warped_labels.nrrd mesh.vtu history.csv sweep.csv report.json)
  if(NOT EXISTS ${DIR}/reg/${f})
    message(SEND_ERROR "missing output ${f}")
  endif()
endforeach()
