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
// The intensity-based baseline: ITK's multi-resolution Demons with organ flattening
// (itk::DemonsBaselineRegistrationFilter).
#include "itkDemonsPipeline.h"
#include "itkDemonsBaselineRegistrationFilter.h"

namespace itk {

BiomechanicalFieldType::Pointer
RunDemonsBaseline(const BiomechanicalCTImageType *    fixedCT,
                  const BiomechanicalCTImageType *    movingCT,
                  const BiomechanicalLabelImageType * fixedLabels,
                  const BiomechanicalLabelImageType * movingLabels,
                  const std::vector<std::int32_t> &   flatten,
                  const DemonsSettings &              settings,
                  PipelineObserver *                  observer)
{
  using FilterType =
    DemonsBaselineRegistrationFilter<BiomechanicalCTImageType, BiomechanicalFieldType, BiomechanicalLabelImageType>;
  auto demons = FilterType::New();
  demons->SetFixedImage(fixedCT);
  demons->SetMovingImage(movingCT);
  demons->SetVariant(settings.variant == "symmetric" ? FilterType::VariantEnum::FastSymmetricForces
                                                     : FilterType::VariantEnum::Diffeomorphic);
  demons->SetNumberOfLevels(settings.levels);
  demons->SetNumberOfIterations(std::vector<unsigned int>(settings.levels, settings.iterations));
  demons->SetStandardDeviation(settings.sigma);
  demons->SetHistogramMatching(settings.histogramMatching);
  if (!flatten.empty())
  {
    demons->SetFixedLabelImage(fixedLabels);
    demons->SetMovingLabelImage(movingLabels);
    demons->SetFlattenLabels(flatten);
  }
  if (observer != nullptr)
  {
    FilterType * filter = demons.GetPointer();
    demons->AddObserver(ProgressEvent(), [filter, observer](const EventObject &) {
      observer->Progress(filter->GetProgress(), std::to_string(filter->GetNumberOfLevels()) + " levels");
    });
  }
  demons->Update();
  return demons->GetOutput();
}

} // namespace itk
