# DICOM-RT output against an independent reader: on itkDicomRTTest's synthetic scan (CT, labels, dose), plastimatch
# makes the CT a DICOM series; itkDicomRTWriteTest writes an RTSTRUCT and an RTDOSE referencing it (and checks its
# own reader's round trip and the refusals); biomechreg rt-export does the same from the command line; plastimatch
# reads both files back, and itkDicomRTWriteTest compares what it read with the originals.
# Run with: cmake -DDRIVER=<test driver> -DCLI=<biomechreg> -DOUT=<scratch dir> -P itkDicomRTWritePlastimatch.cmake
include(${CMAKE_CURRENT_LIST_DIR}/plastimatchCommon.cmake)

run(${DRIVER} itkDicomRTTest make ${OUT})
run(${PLASTIMATCH} convert --input ${OUT}/ct.nrrd --output-dicom ${OUT}/series)
run(${DRIVER} itkDicomRTWriteTest write ${OUT} ${OUT}/series)
file(WRITE ${OUT}/scene.json [=[{"labels": [{"name": "air", "role": "outside", "value": 0},
  {"name": "Body", "role": "material", "value": 1, "youngs_modulus_kPa": 10, "poisson_ratio": 0.35},
  {"name": "prostate", "role": "material", "value": 2, "youngs_modulus_kPa": 60, "poisson_ratio": 0.4},
  {"name": "bladder", "role": "fixed", "value": 3}], "gauge": "Body"}]=])
run(${CLI} rt-export --reference-ct ${OUT}/series --labels ${OUT}/labels.nrrd --scene ${OUT}/scene.json
  --rtstruct-out ${OUT}/cli/rtss.dcm --dose ${OUT}/dose.nrrd --rtdose-out ${OUT}/cli/rtdose.dcm)
foreach(name rtss rtdose)
  file(READ ${OUT}/cli/${name}.dcm cli_bytes HEX)
  file(READ ${OUT}/ours/${name}.dcm library_bytes HEX)
  if(NOT cli_bytes STREQUAL library_bytes)
    message(FATAL_ERROR "rt-export's ${name}.dcm differs from the library's on the same inputs")
  endif()
endforeach()
execute_process(COMMAND ${CLI} rt-export --reference-ct ${OUT}/series --labels ${OUT}/labels.nrrd
  --rtstruct-out ${OUT}/cli/x.dcm RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "needs --labels FILE, --scene FILE")
  message(FATAL_ERROR "rt-export without --scene: exit ${rc} (2 expected), \"${err}\"")
endif()
# dicom3tools' IOD checker on the RTSTRUCT: no "Error" line (its warnings concern the CT's copied values). It asserts
# on 32-bit pixel data, plastimatch's RTDOSE included, so the RTDOSE is checked by reading only.
find_program(DCIODVFY dciodvfy)
if(NOT DCIODVFY)
  message(FATAL_ERROR "dciodvfy is not installed (scripts/setup.sh installs Debian's dicom3tools)")
endif()
execute_process(COMMAND ${DCIODVFY} ${OUT}/cli/rtss.dcm OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT "${out}${err}" MATCHES "RTStructureSet" OR "${out}${err}" MATCHES "Error")
  message(FATAL_ERROR "dciodvfy does not accept our RTSTRUCT:\n${out}${err}")
endif()
run(${PLASTIMATCH} convert --input ${OUT}/cli/rtss.dcm --referenced-ct ${OUT}/series --output-prefix ${OUT}/back)
run(${PLASTIMATCH} convert --input ${OUT}/cli/rtdose.dcm --output-dose-img ${OUT}/back_dose.nrrd)
run(${DRIVER} itkDicomRTWriteTest check ${OUT})
