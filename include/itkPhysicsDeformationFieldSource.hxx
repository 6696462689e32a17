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
#ifndef itkPhysicsDeformationFieldSource_hxx
#define itkPhysicsDeformationFieldSource_hxx

#include "itkPhysicsDeformationFieldSource.h"
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrTetrahedralMesh.h"
#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <memory>
#include <numeric>
#include <sstream>
#include <type_traits>

namespace itk {

template<typename TOutputImage>
PhysicsDeformationFieldSource<TOutputImage>::PhysicsDeformationFieldSource()
{
  // The mesh is the primary input (always required); the reference image defines the grid.
  this->SetPrimaryInputName("Mesh");
  this->AddRequiredInputName("ReferenceImage");
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::SetMesh(const MeshObjectType * mesh)
{
  this->SetInput("Mesh", const_cast<MeshObjectType *>(mesh));
}

template<typename TOutputImage>
auto
PhysicsDeformationFieldSource<TOutputImage>::GetMesh() const -> const MeshObjectType *
{
  return itkDynamicCastInDebugMode<const MeshObjectType *>(this->ProcessObject::GetInput("Mesh"));
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::SetReferenceImage(const ReferenceImageType * image)
{
  this->SetInput("ReferenceImage", const_cast<ReferenceImageType *>(image));
}

template<typename TOutputImage>
auto
PhysicsDeformationFieldSource<TOutputImage>::GetReferenceImage() const -> const ReferenceImageType *
{
  return itkDynamicCastInDebugMode<const ReferenceImageType *>(this->ProcessObject::GetInput("ReferenceImage"));
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  const bmr::TetrahedralMesh & mesh = this->GetMesh()->Get();
  if (mesh.GetNumberOfTetrahedra() == 0)
  {
    itkExceptionMacro("the input mesh has no element");
  }
  if (mesh.displacement.size() != mesh.points.size())
  {
    itkExceptionMacro("the input mesh carries no nodal displacement (3 values per node expected, got "
                      << mesh.displacement.size() << ")");
  }
  GridGeometryOf(this->GetReferenceImage()).Validate("reference image");
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::GenerateOutputInformation()
{
  OutputImageType *          output = this->GetOutput();
  const ReferenceImageType * reference = this->GetReferenceImage();
  if (!output || !reference)
  {
    return;
  }
  output->SetLargestPossibleRegion(reference->GetLargestPossibleRegion());
  output->SetSpacing(reference->GetSpacing());
  output->SetOrigin(reference->GetOrigin());
  output->SetDirection(reference->GetDirection());
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::WarnInvertedElements(const bmr::TetrahedralMesh & mesh, bool locate) const
{
  // So that a user sees which tissue the deformation crushes, and against which organ.
  const std::string where =
    locate ? " (" + bmr::InvertedElementsText(bmr::InvertedElementsByLabel(mesh, mesh.displacement), m_LabelNames) + ")"
           : std::string();
  itkWarningMacro(<< m_NumberOfInvertedElements << " elements are inverted by the deformation" << where
                  << "; the field is undefined inside them and holds there the fill of the voxels the mesh does not "
                     "cover");
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::GenerateData()
{
  OutputImageType * output = this->GetOutput();
  output->SetBufferedRegion(output->GetRequestedRegion());
  output->Allocate(); // not initialized here: each work unit clears its own region (parallel first touch)
  bmr::AdviseHugePages(output->GetBufferPointer(),
                       output->GetPixelContainer()->Size() * sizeof(typename TOutputImage::PixelType));

  const bmr::TetrahedralMesh & mesh = this->GetMesh()->Get();
  const bmr::GridGeometry      grid = GridGeometryOf(output);
  const bmr::FieldKindEnum     kind =
    m_FieldDirection == FieldDirectionEnum::FixedToMoving ? bmr::FieldKindEnum::PullBack : bmr::FieldKindEnum::Push;
  const bmr::DisplacementFieldRasterizer rasterizer(mesh, mesh.displacement, grid, kind);
  m_NumberOfInvertedElements = rasterizer.GetNumberOfInvertedElements();
  if (m_NumberOfInvertedElements > 0)
  {
    this->WarnInvertedElements(mesh, kind == bmr::FieldKindEnum::PullBack);
  }

  // A field of double 3-vectors has the rasterizer's layout (3 doubles per voxel, index 0 fastest): it is
  // computed in place. Other pixel types go through a buffer of doubles.
  using ValueType = typename PixelType::ValueType;
  constexpr bool            inPlace = std::is_same<ValueType, double>::value && sizeof(PixelType) == 3 * sizeof(double);
  const std::size_t         nvox = grid.GetNumberOfVoxels();
  std::unique_ptr<double[]> buffer(inPlace ? nullptr : new double[3 * nvox]);
  double *                  field = inPlace ? reinterpret_cast<double *>(output->GetBufferPointer()) : buffer.get();
  std::unique_ptr<unsigned char[]> inside(new unsigned char[nvox]);
  // Slabs along the last index: the rasterizer's ownership rule makes the result independent of the split.
  const auto          largest = output->GetLargestPossibleRegion();
  const auto          start = largest.GetIndex();
  MultiThreaderBase * threader = this->GetMultiThreader();
  threader->SetNumberOfWorkUnits(this->GetNumberOfWorkUnits());
  threader->ParallelizeImageRegion<3>(
    largest,
    [&](const ImageRegion<3> & region) {
      std::array<std::size_t, 3> s, n;
      for (unsigned int i = 0; i < 3; ++i)
      {
        s[i] = static_cast<std::size_t>(region.GetIndex(i) - start[i]);
        n[i] = region.GetSize(i);
      }
      // The rasterizer writes the covered voxels only: the others start at 0.
      for (std::size_t k = s[2]; k < s[2] + n[2]; ++k)
      {
        for (std::size_t j = s[1]; j < s[1] + n[1]; ++j)
        {
          const std::size_t row = s[0] + grid.size[0] * (j + grid.size[1] * k);
          std::fill(field + 3 * row, field + 3 * (row + n[0]), 0.0);
          std::fill(inside.get() + row, inside.get() + row + n[0], static_cast<unsigned char>(0));
        }
      }
      rasterizer.RasterizeRegion(s, n, field, inside.get());
    },
    nullptr);
  this->UpdateProgress(0.6f);
  m_NumberOfCoveredVoxels = std::accumulate(inside.get(), inside.get() + nvox, SizeValueType{ 0 });
  if (m_FillOutside)
  {
    bmr::FillOutsideHarmonic(grid, field, inside.get(), m_FillCoarsening, threader);
  }
  this->UpdateProgress(0.9f);
  if constexpr (!inPlace)
  {
    this->CopyToOutput(field, grid);
  }
  this->UpdateProgress(1.0f);
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::CopyToOutput(const double * field, const bmr::GridGeometry & grid)
{
  using ValueType = typename PixelType::ValueType;
  OutputImageType * output = this->GetOutput();
  this->GetMultiThreader()->ParallelizeArray(
    0,
    grid.size[2],
    [&](SizeValueType k) {
      PixelType *       out = output->GetBufferPointer() + k * grid.size[0] * grid.size[1];
      const double *    in = field + 3 * k * grid.size[0] * grid.size[1];
      const std::size_t planeSize = grid.size[0] * grid.size[1];
      for (std::size_t v = 0; v < planeSize; ++v)
      {
        for (unsigned int c = 0; c < 3; ++c)
        {
          out[v][c] = static_cast<ValueType>(in[3 * v + c]);
        }
      }
    },
    nullptr);
}

template<typename TOutputImage>
void
PhysicsDeformationFieldSource<TOutputImage>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "FieldDirection: "
     << (m_FieldDirection == FieldDirectionEnum::FixedToMoving ? "FixedToMoving" : "MovingToFixed") << std::endl;
  os << indent << "FillOutside: " << m_FillOutside << std::endl;
  os << indent << "FillCoarsening: " << m_FillCoarsening << std::endl;
  os << indent << "NumberOfCoveredVoxels: " << m_NumberOfCoveredVoxels << std::endl;
  os << indent << "NumberOfInvertedElements: " << m_NumberOfInvertedElements << std::endl;
  os << indent << "LabelNames:";
  for (const auto & [value, name] : m_LabelNames)
  {
    os << ' ' << value << '=' << name;
  }
  os << std::endl;
}

} // namespace itk

#endif
