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
#ifndef itkPipelineTypes_h
#define itkPipelineTypes_h

#include "bmrElasticityEstimator.h"
#include "itkImage.h"
#include "itkVector.h"

#include <cstdint>
#include <map>
#include <string>

namespace itk {

// What every pipeline shares: the image types, the observer and the stages' wall times.

/** The image types of the pipelines: CT [HU], label maps, displacement fields [mm, LPS].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
using BiomechanicalCTImageType = Image<float, 3>;
using BiomechanicalLabelImageType = Image<std::int32_t, 3>;
using BiomechanicalFieldType = Image<Vector<double, 3>, 3>;

/** Per organ (scene label name), a probability or partial-volume image of the fixed scan, in [0, 1].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
using BiomechanicalProbabilityImageType = Image<float, 3>;
using OrganProbabilityImages = std::map<std::string, BiomechanicalProbabilityImageType::Pointer>;

/** Receives what a pipeline is doing; every method does nothing by default.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
class BiomechanicalRegistration_EXPORT PipelineObserver
{
public:
  virtual ~PipelineObserver() = default;
  virtual void
  StageBegin(const std::string & /*stage*/)
  {}
  /** \a detail: a short result of the stage ("41043 tetrahedra, ..."), or empty. */
  virtual void
  StageEnd(const std::string & /*stage*/, double /*seconds*/, const std::string & /*detail*/)
  {}
  virtual void
  Warning(const std::string & /*message*/)
  {}
  /** After every inner solve of the estimation. */
  virtual void
  Iteration(const bmr::IterationRecord & /*record*/)
  {}
  /** Progress of the running stage: \a fraction of its work done, in [0, 1] (e.g. rescans finished of those
   * asked for), and what that is ("3 of 8 rescans"). Calls come one at a time, possibly from worker threads. */
  virtual void
  Progress(double /*fraction*/, const std::string & /*detail*/)
  {}
};

/** Wall time of one stage [s]. */
struct BiomechanicalRegistration_EXPORT PipelineStage
{
  std::string name;
  double      seconds{ 0.0 };
};

} // namespace itk

#endif
