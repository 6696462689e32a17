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

// The settings structs' own checks (UncertaintySettings::Validate, RegistrationSettings::Validate): one place for
// the ranges, which the library enforces and the CLI reports as usage errors.

#include "itkRegistrationPipeline.h"

#include "bmrError.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace itk {
namespace {
/** Fails naming \a where and \a setting unless \a value is finite and within [lo, hi] (an end excluded when its
 * flag says so). */
void
RequireRange(const char *        where,
             const char *        setting,
             double              value,
             double              lo,
             double              hi,
             bool                loOpen,
             bool                hiOpen,
             const std::string & meaning)
{
  const bool aboveLo = loOpen ? value > lo : value >= lo;
  const bool belowHi = hiOpen ? value < hi : value <= hi;
  if (std::isfinite(value) && aboveLo && belowHi)
  {
    return;
  }
  std::ostringstream os;
  os << setting << " must lie in " << (loOpen ? "(" : "[") << lo << ", " << hi << (hiOpen ? ")" : "]");
  if (!meaning.empty())
  {
    os << " (" << meaning << ")";
  }
  os << ", got " << value;
  bmr::FailInput(where, os.str());
}
} // namespace

void
UncertaintySettings::Validate() const
{
  const char * where = "UncertaintySettings";
  const double inf = std::numeric_limits<double>::infinity();
  if ((method == UncertaintyMethodEnum::Rescan || method == UncertaintyMethodEnum::Bootstrap) && resamples < 3)
  {
    bmr::FailInput(where,
                   "resamples must be at least 3 for rescans or the bootstrap, got " + std::to_string(resamples));
  }
  RequireRange(where, "meshJitter", meshJitter, 0.0, 0.9, false, true, "mesh sizes x U(1 - j, 1 + j)");
  const std::pair<const char *, double> scales[] = { { "shiftVoxels", shiftVoxels },
                                                     { "rotationDegrees", rotationDegrees },
                                                     { "tangentialWallFraction", tangentialWallFraction },
                                                     { "smoothingVoxels", smoothingVoxels },
                                                     { "stepTolerance", stepTolerance } };
  for (const auto & [name, value] : scales)
  {
    RequireRange(where, name, value, 0.0, inf, false, true, "0: not varied");
  }
  RequireRange(where,
               "simulationMeshScale",
               simulationMeshScale,
               0.25,
               2.0,
               false,
               false,
               "resimulation mesh sizes relative to the estimation's");
  RequireRange(where, "statedVoxelLimitMM", statedVoxelLimitMM, 0.0, inf, true, true, "mm");
}

void
RegistrationSettings::Validate() const
{
  const char * where = "RegistrationSettings";
  estimator.Validate();
  walls.Validate();
  uncertainty.Validate();
  RequireRange(where, "coarseFactor", coarseFactor, 0.0, 10.0, true, false, "1 or less: sweep on the fine mesh");
  RequireRange(where, "meshScale", meshScale, 0.25, 4.0, false, false, "mesh sizes relative to the scene's");
  if (estimator.limitElementInversion && walls.ReducedBasis())
  {
    bmr::FailInput(where,
                   "limitElementInversion needs one parameter per wall node: controlSpacing 0 and a wall "
                   "motion other than pressure");
  }
}
} // namespace itk
