# ITK module description of BiomechanicalRegistration. Read by ITK's module
# system (inside an ITK source tree or through ITKModuleExternal) and, in the
# standalone build, by the top-level CMakeLists.txt for its ITK components.
get_filename_component(MY_CURRENT_DIR "${CMAKE_CURRENT_LIST_FILE}" PATH)
file(READ "${MY_CURRENT_DIR}/README.md" DOCUMENTATION)

itk_module(BiomechanicalRegistration
  ENABLE_SHARED
  DEPENDS
    ITKCommon
    ITKImageFunction
    ITKImageGrid
    ITKTransform
    ITKDisplacementField
    ITKPath
    ITKDistanceMap
    ITKOptimizersv4
    ITKPDEDeformableRegistration
    ITKConnectedComponents
    ITKThresholding
    ITKImageIntensity
    ITKIOImageBase
  PRIVATE_DEPENDS
    ITKGDCM
  COMPILE_DEPENDS
    ITKImageSources
  TEST_DEPENDS
    ITKTestKernel
    ITKIONRRD
    ITKIOMeta
    ITKIONIFTI
    ITKIOGDCM
  DESCRIPTION
    "${DOCUMENTATION}"
  EXCLUDE_FROM_DEFAULT
)
