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
#ifndef itkDemonsBaselineRegistrationFilter_hxx
#define itkDemonsBaselineRegistrationFilter_hxx

#include "itkDemonsBaselineRegistrationFilter.h"
#include "itkCastImageFilter.h"
#include "itkDiffeomorphicDemonsRegistrationFilter.h"
#include "itkFastSymmetricForcesDemonsRegistrationFilter.h"
#include "itkHistogramMatchingImageFilter.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageRegionIterator.h"
#include "itkMultiResolutionPDEDeformableRegistration.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace itk {

template<typename TImage, typename TDisplacementField, typename TLabelImage>
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::DemonsBaselineRegistrationFilter()
{
  this->AddRequiredInputName("MovingImage");
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetFixedImage(const ImageType * image)
{
  this->SetInput(image);
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
auto
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::GetFixedImage() const -> const ImageType *
{
  return this->GetInput();
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetMovingImage(const ImageType * image)
{
  this->SetInput("MovingImage", const_cast<ImageType *>(image));
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
auto
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::GetMovingImage() const -> const ImageType *
{
  return itkDynamicCastInDebugMode<const ImageType *>(this->ProcessObject::GetInput("MovingImage"));
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetFixedLabelImage(
  const LabelImageType * labels)
{
  this->SetInput("FixedLabelImage", const_cast<LabelImageType *>(labels));
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetMovingLabelImage(
  const LabelImageType * labels)
{
  this->SetInput("MovingLabelImage", const_cast<LabelImageType *>(labels));
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetNumberOfLevels(unsigned int levels)
{
  if (levels != m_NumberOfLevels)
  {
    m_NumberOfLevels = levels;
    m_NumberOfIterations.assign(levels, 50);
    this->Modified();
  }
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::SetNumberOfIterations(
  const std::vector<unsigned int> & iterations)
{
  if (iterations != m_NumberOfIterations)
  {
    m_NumberOfIterations = iterations;
    this->Modified();
  }
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  if (m_NumberOfLevels < 1 || m_NumberOfIterations.size() != m_NumberOfLevels)
  {
    itkExceptionMacro("NumberOfLevels (" << m_NumberOfLevels << ") must be >= 1 and NumberOfIterations hold one count "
                                         << "per level (it holds " << m_NumberOfIterations.size() << ")");
  }
  if (!(m_StandardDeviation > 0.0) || !(m_MaximumUpdateStepLength > 0.0))
  {
    itkExceptionMacro("StandardDeviation (" << m_StandardDeviation << " voxels) and MaximumUpdateStepLength ("
                                            << m_MaximumUpdateStepLength << " voxels) must be > 0");
  }
  if (m_HistogramMatching && (m_HistogramLevels < 2 || m_MatchPoints < 1))
  {
    itkExceptionMacro("HistogramLevels must be >= 2 and MatchPoints >= 1");
  }
  if (!m_FlattenLabels.empty() &&
      (!this->ProcessObject::GetInput("FixedLabelImage") || !this->ProcessObject::GetInput("MovingLabelImage")))
  {
    itkExceptionMacro("FlattenLabels needs both the fixed and the moving label image");
  }
  for (const ImageType * image : { this->GetFixedImage(), this->GetMovingImage() })
  {
    ImageRegionConstIterator<ImageType> it(image, image->GetLargestPossibleRegion());
    for (; !it.IsAtEnd(); ++it)
    {
      if (!std::isfinite(static_cast<double>(it.Get())))
      {
        itkExceptionMacro(<< (image == this->GetFixedImage() ? "fixed" : "moving") << " image: voxel " << it.GetIndex()
                          << " is not finite");
      }
    }
  }
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::GenerateOutputInformation()
{
  DisplacementFieldType * output = this->GetOutput();
  const ImageType *       fixed = this->GetFixedImage();
  if (!output || !fixed)
  {
    return;
  }
  output->SetLargestPossibleRegion(fixed->GetLargestPossibleRegion());
  output->SetSpacing(fixed->GetSpacing());
  output->SetOrigin(fixed->GetOrigin());
  output->SetDirection(fixed->GetDirection());
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::GenerateInputRequestedRegion()
{
  for (const auto & name : this->GetInputNames())
  {
    if (auto * input = dynamic_cast<ImageBase<ImageDimension> *>(this->ProcessObject::GetInput(name)))
    {
      input->SetRequestedRegionToLargestPossibleRegion();
    }
  }
}

namespace DemonsBaselineDetail {
/** Replaces every voxel of the given labels by the label's mean intensity in \a image (same grid). */
template<typename TFloatImage, typename TLabelImage>
void
FlattenLabels(TFloatImage * image, const TLabelImage * labels, const std::vector<typename TLabelImage::PixelType> & set)
{
  if (image->GetLargestPossibleRegion() != labels->GetLargestPossibleRegion())
  {
    itkGenericExceptionMacro("DemonsBaselineRegistrationFilter: a label image does not have the size of its image");
  }
  std::map<typename TLabelImage::PixelType, std::pair<double, std::size_t>> sums;
  for (const auto l : set)
  {
    sums[l] = { 0.0, 0 };
  }
  ImageRegionIterator<TFloatImage>      it(image, image->GetLargestPossibleRegion());
  ImageRegionConstIterator<TLabelImage> lt(labels, labels->GetLargestPossibleRegion());
  for (; !it.IsAtEnd(); ++it, ++lt)
  {
    const auto s = sums.find(lt.Get());
    if (s != sums.end())
    {
      s->second.first += it.Get();
      ++s->second.second;
    }
  }
  for (it.GoToBegin(), lt.GoToBegin(); !it.IsAtEnd(); ++it, ++lt)
  {
    const auto s = sums.find(lt.Get());
    if (s != sums.end())
    {
      it.Set(static_cast<typename TFloatImage::PixelType>(s->second.first / double(s->second.second)));
    }
  }
}
} // namespace DemonsBaselineDetail

template<typename TImage, typename TDisplacementField, typename TLabelImage>
auto
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::PreparedImages() const
  -> std::array<typename FloatImageType::Pointer, 2>
{
  using CastType = CastImageFilter<ImageType, FloatImageType>;
  std::array<typename FloatImageType::Pointer, 2> images;
  const ImageType *                               inputs[2] = { this->GetFixedImage(), this->GetMovingImage() };
  const char *                                    labelNames[2] = { "FixedLabelImage", "MovingLabelImage" };
  for (int i = 0; i < 2; ++i)
  {
    auto cast = CastType::New();
    cast->SetInput(inputs[i]);
    cast->Update();
    images[i] = cast->GetOutput();
    images[i]->DisconnectPipeline();
    if (!m_FlattenLabels.empty())
    {
      DemonsBaselineDetail::FlattenLabels(
        images[i].GetPointer(),
        itkDynamicCastInDebugMode<const LabelImageType *>(this->ProcessObject::GetInput(labelNames[i])),
        m_FlattenLabels);
    }
  }
  if (m_HistogramMatching)
  {
    using MatchingType = HistogramMatchingImageFilter<FloatImageType, FloatImageType>;
    auto matching = MatchingType::New();
    matching->SetSourceImage(images[1]);
    matching->SetReferenceImage(images[0]);
    matching->SetNumberOfHistogramLevels(m_HistogramLevels);
    matching->SetNumberOfMatchPoints(m_MatchPoints);
    matching->ThresholdAtMeanIntensityOn();
    matching->Update();
    images[1] = matching->GetOutput();
  }
  return images;
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::GenerateData()
{
  using MultiResolutionType =
    MultiResolutionPDEDeformableRegistration<FloatImageType, FloatImageType, DisplacementFieldType, float>;
  using DiffeomorphicType =
    DiffeomorphicDemonsRegistrationFilter<FloatImageType, FloatImageType, DisplacementFieldType>;
  using SymmetricType =
    FastSymmetricForcesDemonsRegistrationFilter<FloatImageType, FloatImageType, DisplacementFieldType>;

  const auto images = this->PreparedImages();
  const auto moving = images[1];

  typename MultiResolutionType::RegistrationType::Pointer demons;
  typename DiffeomorphicType::Pointer                     diffeomorphic;
  typename SymmetricType::Pointer                         symmetric;
  if (m_Variant == VariantEnum::Diffeomorphic)
  {
    diffeomorphic = DiffeomorphicType::New();
    diffeomorphic->SetUseGradientType(DiffeomorphicType::GradientType::Symmetric);
    diffeomorphic->SetMaximumUpdateStepLength(m_MaximumUpdateStepLength);
    demons = diffeomorphic;
  }
  else
  {
    symmetric = SymmetricType::New();
    symmetric->SetUseGradientType(SymmetricType::GradientType::Symmetric);
    symmetric->SetMaximumUpdateStepLength(m_MaximumUpdateStepLength);
    demons = symmetric;
  }
  demons->SmoothDisplacementFieldOn();
  demons->SetStandardDeviations(m_StandardDeviation);
  demons->SmoothUpdateFieldOff();
  demons->SetNumberOfWorkUnits(this->GetNumberOfWorkUnits());

  auto multiResolution = MultiResolutionType::New();
  multiResolution->SetRegistrationFilter(demons);
  multiResolution->SetFixedImage(images[0]);
  multiResolution->SetMovingImage(moving);
  multiResolution->SetNumberOfLevels(m_NumberOfLevels);
  multiResolution->SetNumberOfIterations(const_cast<unsigned int *>(m_NumberOfIterations.data()));
  // Progress by work done: an iteration on a level costs its voxels, 1/8 of the next finer level's.
  const auto levelCost = [this](unsigned int level) { return std::pow(0.125, double(m_NumberOfLevels - 1 - level)); };
  double     total = 0.0, done = 0.0;
  for (unsigned int level = 0; level < m_NumberOfLevels; ++level)
  {
    total += m_NumberOfIterations[level] * levelCost(level);
  }
  this->UpdateProgress(0.0f);
  demons->AddObserver(IterationEvent(), [&](const EventObject &) {
    done += levelCost(multiResolution->GetCurrentLevel());
    this->UpdateProgress(static_cast<float>(std::min(1.0, done / total)));
  });
  multiResolution->Update();
  m_FinalMetric = diffeomorphic ? diffeomorphic->GetMetric() : symmetric->GetMetric();

  this->GraftOutput(multiResolution->GetOutput());
}

template<typename TImage, typename TDisplacementField, typename TLabelImage>
void
DemonsBaselineRegistrationFilter<TImage, TDisplacementField, TLabelImage>::PrintSelf(std::ostream & os,
                                                                                     Indent         indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Variant: " << (m_Variant == VariantEnum::Diffeomorphic ? "Diffeomorphic" : "FastSymmetricForces")
     << std::endl;
  os << indent << "NumberOfLevels: " << m_NumberOfLevels << std::endl;
  os << indent << "NumberOfIterations:";
  for (unsigned int n : m_NumberOfIterations)
  {
    os << " " << n;
  }
  os << std::endl;
  os << indent << "StandardDeviation: " << m_StandardDeviation << " voxels" << std::endl;
  os << indent << "MaximumUpdateStepLength: " << m_MaximumUpdateStepLength << " voxels" << std::endl;
  os << indent << "HistogramMatching: " << m_HistogramMatching << std::endl;
  os << indent << "HistogramLevels: " << m_HistogramLevels << std::endl;
  os << indent << "MatchPoints: " << m_MatchPoints << std::endl;
  os << indent << "FlattenLabels:";
  for (const auto l : m_FlattenLabels)
  {
    os << " " << static_cast<typename NumericTraits<LabelType>::PrintType>(l);
  }
  os << std::endl;
  os << indent << "FinalMetric: " << m_FinalMetric << std::endl;
}

} // namespace itk

#endif
