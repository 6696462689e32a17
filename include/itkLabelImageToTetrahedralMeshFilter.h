/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef itkLabelImageToTetrahedralMeshFilter_h
#define itkLabelImageToTetrahedralMeshFilter_h

#include "bmrMesher.h"
#include "bmrScene.h"
#include "itkProcessObject.h"
#include "itkTetrahedralMeshObject.h"

namespace itk {

/** \class LabelImageToTetrahedralMeshFilter
 * \brief Meshes a label image into labeled 4-node tetrahedra with CGAL Mesh_3.
 *
 * Every non-zero label is meshed (CGAL's labeled image domain, the TetGen
 * equivalent), so that every organ surface is made of element faces and organ
 * interfaces share nodes. The mesh is built in physical space: spacing
 * (anisotropic voxels), origin and direction cosines (oblique volumes) of the
 * input are honoured. Elements of the excluded labels are then removed and
 * their walls kept as boundary faces carrying the excluded label, which is how
 * bone surfaces (u = 0) and hollow-organ walls (loads) are found later.
 *
 * When a scene is set (SetScene()), it decides everything: labels with the
 * roles fixed, hollow and outside are excluded, the region of interest is
 * cropped, the scene's mesh sizes are used, and every simulated label is
 * checked to be present in the output. Otherwise SetMeshingParameters() and
 * SetExcludedLabels() are used.
 *
 * Meshing is sequential with a fixed random seed: the same input gives the
 * same mesh. GetMeshQuality() reports the minimum dihedral angle and radius
 * ratio of the result.
 *
 * Input: a 3-D integer label image. Output: itk::TetrahedralMeshObject.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh
 */
template<typename TInputImage>
class ITK_TEMPLATE_EXPORT LabelImageToTetrahedralMeshFilter : public ProcessObject
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(LabelImageToTetrahedralMeshFilter);

  using Self = LabelImageToTetrahedralMeshFilter;
  using Superclass = ProcessObject;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  using InputImageType = TInputImage;
  using OutputMeshType = TetrahedralMeshObject;
  using LabelListType = std::vector<std::int32_t>;

  static_assert(TInputImage::ImageDimension == 3, "LabelImageToTetrahedralMeshFilter needs a 3-D label image");

  itkNewMacro(Self);
  itkTypeMacro(LabelImageToTetrahedralMeshFilter, ProcessObject);

  using Superclass::SetInput;
  void
  SetInput(const InputImageType * image);
  const InputImageType *
  GetInput() const;

  OutputMeshType *
  GetOutput();

  /** Mesh sizes and quality criteria [mm]; ignored when a scene is set. */
  void
  SetMeshingParameters(const bmr::MeshingParameters & parameters);
  const bmr::MeshingParameters &
  GetMeshingParameters() const
  {
    return m_MeshingParameters;
  }

  /** Labels meshed but removed from the output, their walls kept as boundary faces. */
  void
  SetExcludedLabels(const LabelListType & labels);
  const LabelListType &
  GetExcludedLabels() const
  {
    return m_ExcludedLabels;
  }

  /** A scene (roles, region of interest, mesh sizes) that overrides the two settings above. */
  void
  SetScene(const bmr::Scene & scene);
  void
  ClearScene();

  /** Quality of the last output mesh. */
  const bmr::MeshQuality &
  GetMeshQuality() const
  {
    return m_MeshQuality;
  }

protected:
  LabelImageToTetrahedralMeshFilter();
  ~LabelImageToTetrahedralMeshFilter() override = default;

  void
  GenerateData() override;
  void
  VerifyPreconditions() ITKv5_CONST override;
  void
                    GenerateInputRequestedRegion() override;
  DataObjectPointer MakeOutput(DataObjectPointerArraySizeType) override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  bmr::MeshingParameters m_MeshingParameters;
  LabelListType          m_ExcludedLabels;
  bool                   m_UseScene{ false };
  bmr::Scene             m_Scene;
  bmr::MeshQuality       m_MeshQuality;
};

} // namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkLabelImageToTetrahedralMeshFilter.hxx"
#endif

#endif
