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
#ifndef itkLabelImageToTetrahedralMeshFilter_hxx
#define itkLabelImageToTetrahedralMeshFilter_hxx

#include "itkLabelImageToTetrahedralMeshFilter.h"
#include "bmrDistanceLabels.h"
#include "bmrSimulation.h"
#include "itkImageRegionConstIterator.h"

#include <limits>

namespace itk {

template<typename TInputImage>
LabelImageToTetrahedralMeshFilter<TInputImage>::LabelImageToTetrahedralMeshFilter()
{
  this->SetNumberOfRequiredInputs(1);
  this->SetNumberOfRequiredOutputs(1);
  this->SetNthOutput(0, this->MakeOutput(0));
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::SetInput(const InputImageType * image)
{
  this->SetNthInput(0, const_cast<InputImageType *>(image));
}

template<typename TInputImage>
auto
LabelImageToTetrahedralMeshFilter<TInputImage>::GetInput() const -> const InputImageType *
{
  return itkDynamicCastInDebugMode<const InputImageType *>(this->GetPrimaryInput());
}

template<typename TInputImage>
auto
LabelImageToTetrahedralMeshFilter<TInputImage>::GetOutput() -> OutputMeshType *
{
  return itkDynamicCastInDebugMode<OutputMeshType *>(this->GetPrimaryOutput());
}

template<typename TInputImage>
ProcessObject::DataObjectPointer
LabelImageToTetrahedralMeshFilter<TInputImage>::MakeOutput(DataObjectPointerArraySizeType)
{
  return OutputMeshType::New().GetPointer();
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::SetMeshingParameters(const bmr::MeshingParameters & parameters)
{
  m_MeshingParameters = parameters;
  this->Modified();
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::SetExcludedLabels(const LabelListType & labels)
{
  if (labels != m_ExcludedLabels)
  {
    m_ExcludedLabels = labels;
    this->Modified();
  }
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::SetScene(const bmr::Scene & scene)
{
  scene.Validate();
  m_Scene = scene;
  m_UseScene = true;
  this->Modified();
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::ClearScene()
{
  if (m_UseScene)
  {
    m_UseScene = false;
    this->Modified();
  }
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::GenerateInputRequestedRegion()
{
  Superclass::GenerateInputRequestedRegion();
  auto * input = const_cast<InputImageType *>(this->GetInput());
  if (input)
  {
    input->SetRequestedRegionToLargestPossibleRegion();
  }
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  const InputImageType * input = this->GetInput();
  if (input->GetLargestPossibleRegion().GetNumberOfPixels() == 0)
  {
    itkExceptionMacro("the input label image is empty");
  }
  bmr::GridGeometry grid = GridGeometryOf(input);
  grid.Validate("input label image");
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::GenerateData()
{
  const InputImageType *    input = this->GetInput();
  const auto                region = input->GetLargestPossibleRegion();
  std::vector<std::int32_t> labels(region.GetNumberOfPixels());
  std::size_t               k = 0;
  for (ImageRegionConstIterator<InputImageType> it(input, region); !it.IsAtEnd(); ++it, ++k)
  {
    const auto v = it.Get();
    if (static_cast<double>(v) != static_cast<double>(static_cast<std::int32_t>(v)))
    {
      itkExceptionMacro("the input label image holds " << static_cast<double>(v) << ", which is not an int32 label");
    }
    labels[k] = static_cast<std::int32_t>(v);
  }
  const bmr::GridGeometry grid = GridGeometryOf(input);
  this->UpdateProgress(0.05f);
  bmr::TetrahedralMesh mesh;
  if (m_UseScene)
  {
    mesh = bmr::MeshSceneLabels(labels.data(), grid, m_Scene);
  }
  else
  {
    const bmr::TetrahedralMesh full =
      m_MeshingParameters.labelSurfaces == bmr::MeshingParameters::LabelSurfaces::Distance
        ? bmr::MeshImplicitLabelsOnGrid(bmr::DistanceLabelFunction(labels, grid), grid, labels, m_MeshingParameters)
        : bmr::MeshLabelVolume(labels.data(), grid, m_MeshingParameters);
    mesh = bmr::ExtractSubmesh(full, m_ExcludedLabels);
  }
  m_MeshQuality = bmr::ComputeMeshQuality(mesh);
  this->GetOutput()->Set(mesh);
  this->UpdateProgress(1.0f);
}

template<typename TInputImage>
void
LabelImageToTetrahedralMeshFilter<TInputImage>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  const bmr::MeshingParameters & p = m_MeshingParameters;
  os << indent << "CellSize [mm]: " << p.cellSize << std::endl;
  os << indent << "FacetSize [mm]: " << p.facetSize << std::endl;
  os << indent << "FacetDistance [mm]: " << p.facetDistance << std::endl;
  os << indent << "FacetAngle [deg]: " << p.facetAngle << std::endl;
  os << indent << "CellRadiusEdgeRatio: " << p.cellRadiusEdgeRatio << std::endl;
  os << indent << "LabelSurfaces: "
     << (p.labelSurfaces == bmr::MeshingParameters::LabelSurfaces::Distance ? "Distance" : "Voxels") << std::endl;
  for (const auto & nameAndSizes : p.SizesPerLabel())
  {
    os << indent << nameAndSizes.first << ':';
    for (const auto & kv : *nameAndSizes.second)
    {
      os << ' ' << kv.first << ':' << kv.second;
    }
    os << std::endl;
  }
  os << indent << "Optimize: " << p.optimize << " (sliver bound " << p.sliverBound << " deg)" << std::endl;
  os << indent << "RandomSeed: " << p.randomSeed << std::endl;
  os << indent << "ExcludedLabels:";
  for (auto l : m_ExcludedLabels)
  {
    os << ' ' << l;
  }
  os << std::endl;
  os << indent << "UseScene: " << m_UseScene << (m_UseScene ? " (" + m_Scene.name + ")" : std::string()) << std::endl;
  os << indent << "MeshQuality: minimum dihedral angle " << m_MeshQuality.minimumDihedralAngleDegrees
     << " deg, minimum radius ratio " << m_MeshQuality.minimumRadiusRatio << std::endl;
}

} // namespace itk

#endif
