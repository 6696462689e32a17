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
#ifndef itkImageWarper_h
#define itkImageWarper_h

#include <cstdint>
#include <ostream>
#include "itkImageToImageFilter.h"
#include "itkVector.h"

namespace itk {

/** \class ImageWarperEnums
 * \brief The enums of ImageWarper (ITK 5 style: outside the class template, with operator<<).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationField
 */
class ImageWarperEnums
{
public:
  /** How the input is sampled at x + d(x). */
  enum class Interpolation : std::uint8_t
  {
    Linear,
    NearestNeighbor,
    LabelGaussian,
    BSpline,
  };
};
/** Prints the enumerator's full name. */
inline std::ostream &
operator<<(std::ostream & out, const ImageWarperEnums::Interpolation value)
{
  switch (value)
  {
    case ImageWarperEnums::Interpolation::Linear:
      return out << "itk::ImageWarperEnums::Interpolation::Linear";
    case ImageWarperEnums::Interpolation::NearestNeighbor:
      return out << "itk::ImageWarperEnums::Interpolation::NearestNeighbor";
    case ImageWarperEnums::Interpolation::LabelGaussian:
      return out << "itk::ImageWarperEnums::Interpolation::LabelGaussian";
    case ImageWarperEnums::Interpolation::BSpline:
      return out << "itk::ImageWarperEnums::Interpolation::BSpline";
  }
  return out << "INVALID VALUE FOR itk::ImageWarperEnums::Interpolation";
}

/** \class ImageWarper
 * \brief Warps an image through a displacement field: a composite of
 * ResampleImageFilter and DisplacementFieldTransform.
 *
 * out(x) = in(x + d(x)) for every voxel center x of the field's grid, with d
 * the fixed -> moving field (ITK's convention, as PhysicsDeformationFieldSource
 * produces it). Interpolation: Linear for CT, NearestNeighbor (default for
 * integer pixel types) or LabelGaussian (ITK's label-preserving Gaussian
 * voting) for label maps, BSpline (cubic) for smooth intensities. Points
 * mapped outside the input take DefaultPixelValue (e.g. -1000 HU for CT, 0
 * for labels). Units: mm.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationField
 */
template<typename TImage, typename TDisplacementField = Image<Vector<double, 3>, 3>>
class ITK_TEMPLATE_EXPORT ImageWarper : public ImageToImageFilter<TImage, TImage>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(ImageWarper);

  using Self = ImageWarper;
  using Superclass = ImageToImageFilter<TImage, TImage>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  using ImageType = TImage;
  using PixelType = typename ImageType::PixelType;
  using DisplacementFieldType = TDisplacementField;

  itkNewMacro(Self);
  itkTypeMacro(ImageWarper, ImageToImageFilter);

  using InterpolationEnum = ImageWarperEnums::Interpolation;

  /** The fixed -> moving displacement field; its grid is the output grid. */
  void
  SetDisplacementField(const DisplacementFieldType * field);
  const DisplacementFieldType *
  GetDisplacementField() const;

  itkSetEnumMacro(Interpolation, InterpolationEnum);
  itkGetEnumMacro(Interpolation, InterpolationEnum);
  itkSetMacro(DefaultPixelValue, PixelType);
  itkGetConstMacro(DefaultPixelValue, PixelType);

protected:
  ImageWarper();
  ~ImageWarper() override = default;

  void
  GenerateOutputInformation() override;
  void
  GenerateInputRequestedRegion() override;
  /** The input and the field need not share a grid: the field defines the output grid and the input is
   * sampled at x + d(x) in physical space wherever it lies (ImageToImageFilter would demand one grid). */
  void
  VerifyInputInformation() ITKv5_CONST override
  {}
  void
  GenerateData() override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  InterpolationEnum m_Interpolation;
  PixelType         m_DefaultPixelValue{};
};

/** \a image warped through the fixed -> moving \a field with one call: nearest neighbor for a label map
 * (\a labels true), linear otherwise; points mapped outside take \a outside.
 * \ingroup BiomechanicalRegistration */
template<typename TImage, typename TDisplacementField>
typename TImage::Pointer
WarpImage(const TImage * image, const TDisplacementField * field, bool labels, typename TImage::PixelType outside)
{
  using WarperType = ImageWarper<TImage, TDisplacementField>;
  auto warper = WarperType::New();
  warper->SetInput(image);
  warper->SetDisplacementField(field);
  warper->SetInterpolation(labels ? WarperType::InterpolationEnum::NearestNeighbor
                                  : WarperType::InterpolationEnum::Linear);
  warper->SetDefaultPixelValue(outside);
  warper->Update();
  return warper->GetOutput();
}

} // namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkImageWarper.hxx"
#endif

#endif
