# DICOM-RT input against an independent writer: the test driver makes a CT, its organ masks and a dose
# (NRRD), plastimatch (Debian's, installed by scripts/setup.sh) converts them into a CT series + RTSTRUCT and
# an RTDOSE, and itkDicomRTTest reads them back (Dice per organ, dose error) and checks the refusals.
# Run with: cmake -DDRIVER=<test driver> -DOUT=<scratch dir> -P itkDicomRTPlastimatch.cmake
include(${CMAKE_CURRENT_LIST_DIR}/plastimatchCommon.cmake)

run(${DRIVER} itkDicomRTTest make ${OUT})
# Structure names come from the masks' file names (Body, BLADDER, prostate).
run(${PLASTIMATCH} convert --input ${OUT}/ct.nrrd --input-prefix ${OUT}/masks --output-dicom ${OUT}/dicom)
run(${PLASTIMATCH} convert --input ${OUT}/ct.nrrd --input-dose-img ${OUT}/dose.nrrd --output-dicom ${OUT}/dicom_dose)
file(GLOB rtstruct ${OUT}/dicom/rtss_*.dcm)
file(GLOB rtdose ${OUT}/dicom_dose/dose_*.dcm)
list(LENGTH rtstruct structs)
list(LENGTH rtdose doses)
if(NOT structs EQUAL 1 OR NOT doses EQUAL 1)
  message(FATAL_ERROR "plastimatch wrote ${structs} RTSTRUCT and ${doses} RTDOSE files (one each expected)")
endif()

execute_process(COMMAND ${DRIVER} itkDicomRTTest check ${OUT} ${rtstruct} ${rtdose} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "itkDicomRTTest check failed")
endif()
