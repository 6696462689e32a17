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
#ifndef itkPhysicsDeformationFieldSource_h
#define itkPhysicsDeformationFieldSource_h

#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include "itkImageSource.h"
#include "itkTetrahedralMeshObject.h"

namespace itk {

/** \class PhysicsDeformationFieldSourceEnums
 * \brief The enums of PhysicsDeformationFieldSource (ITK 5 style: outside the class template, with operator<<).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationField
 */
class PhysicsDeformationFieldSourceEnums
{
public:
  /** Which field: fixed -> moving (the exact pull-back, default) or moving -> fixed (the push). */
  enum class FieldDirection : std::uint8_t
  {
    FixedToMoving,
    MovingToFixed,
  };
};
/** Prints the enumerator's full name. */
inline std::ostream &
operator<<(std::ostream & out, const PhysicsDeformationFieldSourceEnums::FieldDirection value)
{
  switch (value)
  {
    case PhysicsDeformationFieldSourceEnums::FieldDirection::FixedToMoving:
      return out << "itk::PhysicsDeformationFieldSourceEnums::FieldDirection::FixedToMoving";
    case PhysicsDeformationFieldSourceEnums::FieldDirection::MovingToFixed:
      return out << "itk::PhysicsDeformationFieldSourceEnums::FieldDirection::MovingToFixed";
  }
  return out << "INVALID VALUE FOR itk::PhysicsDeformationFieldSourceEnums::FieldDirection";
}

/** \class PhysicsDeformationFieldSource
 * \brief Turns the nodal displacements of a finite-element simulation into a displacement field image.
 *
 * The simulation's map is phi(X) = X + u(X), with u piecewise linear on the
 * undeformed tetrahedra (moving space). The output grid is that of the
 * reference image. Two fields are available (SetFieldDirection()):
 *
 * - FixedToMoving (default, the pull-back): for every voxel center x of the
 *   grid, the deformed element containing x is found and
 *   \f$ d(x) = \sum_a \lambda_a(x) X_a - x \f$ with the barycentric coordinates
 *   \f$\lambda_a\f$ of x in the deformed element and \f\f$ its undeformed
 *   nodes: the exact inverse of the piecewise-linear map, ready for
 *   DisplacementFieldTransform + ResampleImageFilter (fixed grid, maps fixed
 *   points to moving points).
 * - MovingToFixed (the push): \f$ d(X) = \sum_a \lambda_a(X) u_a \f$ on a
 *   moving-space grid.
 *
 * Voxels the mesh does not cover (lumens, bone interiors, beyond the region of
 * interest) are filled continuously: the harmonic extension of the field
 * (Laplace's equation on a grid coarsened by FillCoarsening, zero on the image
 * border), so lumens follow their walls, bone interiors enclosed by u = 0
 * stay at 0, and the field decays to zero towards the border. SetFillOutside(false)
 * leaves them at zero instead.
 *
 * Threaded over z-slabs; a voxel on a shared face belongs to the element of
 * lowest index, so the output is identical for any number of threads. The fill
 * is threaded with the same guarantee (bmr::FillOutsideHarmonic). A field of
 * double 3-vectors is computed in place in the output buffer (other pixel
 * types through a buffer of doubles), whose pages are advised to be huge
 * (bmr::AdviseHugePages).
 * Units: mm (LPS). Input: an itk::TetrahedralMeshObject with nodal displacement.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationField
 */
template<typename TOutputImage>
class ITK_TEMPLATE_EXPORT PhysicsDeformationFieldSource : public ImageSource<TOutputImage>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(PhysicsDeformationFieldSource);

  using Self = PhysicsDeformationFieldSource;
  using Superclass = ImageSource<TOutputImage>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  using OutputImageType = TOutputImage;
  using PixelType = typename OutputImageType::PixelType;
  using ReferenceImageType = ImageBase<3>;
  using MeshObjectType = TetrahedralMeshObject;

  static_assert(TOutputImage::ImageDimension == 3 && PixelType::Dimension == 3,
                "PhysicsDeformationFieldSource produces 3-D fields of 3-vectors");

  itkNewMacro(Self);
  itkTypeMacro(PhysicsDeformationFieldSource, ImageSource);

  using FieldDirectionEnum = PhysicsDeformationFieldSourceEnums::FieldDirection;

  /** The simulated mesh; must carry a nodal displacement [mm]. */
  void
  SetMesh(const MeshObjectType * mesh);
  const MeshObjectType *
  GetMesh() const;

  /** The grid of the output field (its largest possible region, spacing, origin, direction). */
  void
  SetReferenceImage(const ReferenceImageType * image);
  const ReferenceImageType *
  GetReferenceImage() const;

  itkSetEnumMacro(FieldDirection, FieldDirectionEnum);
  itkGetEnumMacro(FieldDirection, FieldDirectionEnum);

  itkSetMacro(FillOutside, bool);
  itkGetConstMacro(FillOutside, bool);
  itkBooleanMacro(FillOutside);

  /** Coarsening factor of the grid on which the outside fill is solved (>= 1). */
  itkSetClampMacro(FillCoarsening, unsigned int, 1, 64);
  itkGetConstMacro(FillCoarsening, unsigned int);

  /** Number of voxels covered by the mesh in the last output. */
  itkGetConstMacro(NumberOfCoveredVoxels, SizeValueType);
  /** Elements inverted by the deformation (no unique pull-back there). */
  itkGetConstMacro(NumberOfInvertedElements, SizeValueType);

  /** The names of the mesh's labels (value -> name, a scene's), by which the inverted-element warning says where the
   * deformation crushes tissue; a label without one is named "label N". */
  void
  SetLabelNames(const std::map<std::int32_t, std::string> & names)
  {
    if (names != m_LabelNames)
    {
      m_LabelNames = names;
      this->Modified();
    }
  }
  const std::map<std::int32_t, std::string> &
  GetLabelNames() const
  {
    return m_LabelNames;
  }

protected:
  PhysicsDeformationFieldSource();
  ~PhysicsDeformationFieldSource() override = default;

  void
  GenerateOutputInformation() override;
  void
  GenerateData() override;
  /** The outside fill couples all voxels: the whole field is always produced. */
  void
  EnlargeOutputRequestedRegion(DataObject * output) override
  {
    output->SetRequestedRegionToLargestPossibleRegion();
  }
  void
  VerifyPreconditions() ITKv5_CONST override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  /** One warning: how many elements the deformation inverts and, with \a locate (the pull-back, whose count is of
   * the deformed mesh), where: their labels and what they lie against (bmr::InvertedElementsByLabel()). */
  void
  WarnInvertedElements(const bmr::TetrahedralMesh & mesh, bool locate) const;
  /** The output's voxels from \a field (3 doubles per voxel, index 0 fastest), plane by plane on the threader. */
  void
  CopyToOutput(const double * field, const bmr::GridGeometry & grid);

  FieldDirectionEnum                  m_FieldDirection{ FieldDirectionEnum::FixedToMoving };
  bool                                m_FillOutside{ true };
  unsigned int                        m_FillCoarsening{ 4 };
  SizeValueType                       m_NumberOfCoveredVoxels{ 0 };
  SizeValueType                       m_NumberOfInvertedElements{ 0 };
  std::map<std::int32_t, std::string> m_LabelNames;
};

} // namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkPhysicsDeformationFieldSource.hxx"
#endif

#endif
