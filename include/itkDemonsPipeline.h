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
#ifndef itkDemonsPipeline_h
#define itkDemonsPipeline_h

#include "itkPipelineTypes.h"

#include <cstdint>
#include <string>
#include <vector>

namespace itk {

// The Demons baseline as one call: RunDemonsBaseline().

/** Settings of the Demons baseline (itk::DemonsBaselineRegistrationFilter); the defaults are biomechreg's.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT DemonsSettings
{
  std::string  variant{ "diffeomorphic" }; ///< or "symmetric" (fast symmetric forces)
  unsigned int levels{ 3 };
  unsigned int iterations{ 50 }; ///< per level
  double       sigma{ 1.5 };     ///< field smoothing [voxels]
  bool         histogramMatching{ true };
};

/** Demons of the moving CT onto the fixed CT; returns the fixed -> moving field [mm]. The label images are used
 * only when \a flatten names organs to flatten (each replaced by its mean in its own image). The \a observer
 * (may be null) hears the progress over the levels.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT BiomechanicalFieldType::Pointer
                                 RunDemonsBaseline(const BiomechanicalCTImageType *    fixedCT,
                                                   const BiomechanicalCTImageType *    movingCT,
                                                   const BiomechanicalLabelImageType * fixedLabels,
                                                   const BiomechanicalLabelImageType * movingLabels,
                                                   const std::vector<std::int32_t> &   flatten,
                                                   const DemonsSettings &              settings,
                                                   PipelineObserver *                  observer = nullptr);

} // namespace itk

#endif
