# ITK module description of BiomechanicalRegistration. Read by ITK's module
# system (inside an ITK source tree or through ITKModuleExternal) and, in the
# standalone build, by the top-level CMakeLists.txt for its ITK components. ITKIOGDCM is a public dependency:
# the public itkBiomechanicalImageIO.h reads DICOM series through itk::GDCMImageIO; the GDCM library itself
# (ITKGDCM) is used only inside src/dicomrt.
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
    ITKIOGDCM
  PRIVATE_DEPENDS
    ITKGDCM
  COMPILE_DEPENDS
    ITKImageSources
  TEST_DEPENDS
    ITKTestKernel
    ITKIONRRD
    ITKIOMeta
    ITKIONIFTI
  DESCRIPTION
    "${DOCUMENTATION}"
  EXCLUDE_FROM_DEFAULT
)
