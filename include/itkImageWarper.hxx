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
#ifndef itkImageWarper_hxx
#define itkImageWarper_hxx

#include "itkImageWarper.h"
#include "itkBSplineInterpolateImageFunction.h"
#include "itkDisplacementFieldTransform.h"
#include "itkLabelImageGaussianInterpolateImageFunction.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkResampleImageFilter.h"

#include <type_traits>

namespace itk {

template<typename TImage, typename TDisplacementField>
ImageWarper<TImage, TDisplacementField>::ImageWarper()
  : m_Interpolation(std::is_integral<PixelType>::value ? InterpolationEnum::NearestNeighbor : InterpolationEnum::Linear)
{
  this->AddRequiredInputName("DisplacementField");
}

template<typename TImage, typename TDisplacementField>
void
ImageWarper<TImage, TDisplacementField>::SetDisplacementField(const DisplacementFieldType * field)
{
  this->SetInput("DisplacementField", const_cast<DisplacementFieldType *>(field));
}

template<typename TImage, typename TDisplacementField>
auto
ImageWarper<TImage, TDisplacementField>::GetDisplacementField() const -> const DisplacementFieldType *
{
  return itkDynamicCastInDebugMode<const DisplacementFieldType *>(this->ProcessObject::GetInput("DisplacementField"));
}

template<typename TImage, typename TDisplacementField>
void
ImageWarper<TImage, TDisplacementField>::GenerateOutputInformation()
{
  ImageType *                   output = this->GetOutput();
  const DisplacementFieldType * field = this->GetDisplacementField();
  if (!output || !field)
  {
    return;
  }
  output->CopyInformation(this->GetInput()); // pixel components
  output->SetLargestPossibleRegion(field->GetLargestPossibleRegion());
  output->SetSpacing(field->GetSpacing());
  output->SetOrigin(field->GetOrigin());
  output->SetDirection(field->GetDirection());
}

template<typename TImage, typename TDisplacementField>
void
ImageWarper<TImage, TDisplacementField>::GenerateInputRequestedRegion()
{
  // Any input voxel may be needed; the field must be complete for the transform.
  if (auto * input = const_cast<ImageType *>(this->GetInput()))
  {
    input->SetRequestedRegionToLargestPossibleRegion();
  }
  if (auto * field = const_cast<DisplacementFieldType *>(this->GetDisplacementField()))
  {
    field->SetRequestedRegionToLargestPossibleRegion();
  }
}

template<typename TImage, typename TDisplacementField>
void
ImageWarper<TImage, TDisplacementField>::GenerateData()
{
  using ScalarType = typename DisplacementFieldType::PixelType::ValueType;
  using TransformType = DisplacementFieldTransform<ScalarType, ImageType::ImageDimension>;
  using ResampleType = ResampleImageFilter<ImageType, ImageType, ScalarType>;

  // The transform keeps a pointer to the field; a shallow copy keeps the input unmodified.
  auto field = DisplacementFieldType::New();
  field->Graft(this->GetDisplacementField());
  auto transform = TransformType::New();
  transform->SetDisplacementField(field);

  auto resample = ResampleType::New();
  resample->SetInput(this->GetInput());
  resample->SetTransform(transform);
  resample->SetOutputParametersFromImage(this->GetDisplacementField());
  resample->SetDefaultPixelValue(m_DefaultPixelValue);
  switch (m_Interpolation)
  {
    case InterpolationEnum::Linear:
      resample->SetInterpolator(LinearInterpolateImageFunction<ImageType, ScalarType>::New());
      break;
    case InterpolationEnum::NearestNeighbor:
      resample->SetInterpolator(NearestNeighborInterpolateImageFunction<ImageType, ScalarType>::New());
      break;
    case InterpolationEnum::LabelGaussian: {
      auto   interpolator = LabelImageGaussianInterpolateImageFunction<ImageType, ScalarType>::New();
      double sigma[ImageType::ImageDimension];
      for (unsigned int i = 0; i < ImageType::ImageDimension; ++i)
      {
        sigma[i] = 0.5 * this->GetInput()->GetSpacing()[i];
      }
      interpolator->SetSigma(sigma);
      interpolator->SetAlpha(3.0);
      resample->SetInterpolator(interpolator);
      break;
    }
    case InterpolationEnum::BSpline:
      resample->SetInterpolator(BSplineInterpolateImageFunction<ImageType, ScalarType>::New());
      break;
  }
  resample->SetNumberOfWorkUnits(this->GetNumberOfWorkUnits());
  resample->GraftOutput(this->GetOutput());
  resample->Update();
  this->GraftOutput(resample->GetOutput());
}

template<typename TImage, typename TDisplacementField>
void
ImageWarper<TImage, TDisplacementField>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  const char * names[] = { "Linear", "NearestNeighbor", "LabelGaussian", "BSpline" };
  os << indent << "Interpolation: " << names[static_cast<int>(m_Interpolation)] << std::endl;
  os << indent
     << "DefaultPixelValue: " << static_cast<typename NumericTraits<PixelType>::PrintType>(m_DefaultPixelValue)
     << std::endl;
}

} // namespace itk

#endif
