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
#include "bmrNumerics.h"

#include "bmrError.h"
#include "bmrRuntimeSetting.h"

#include <string>

namespace bmr {
namespace {
/** OpenBLAS's thread count (both null without OpenBLAS). */
const RuntimeIntSetting &
OpenBlas()
{
  static const RuntimeIntSetting functions =
    FindRuntimeIntSetting("openblas_get_num_threads", "openblas_set_num_threads");
  return functions;
}
} // namespace

NumericsState
ConfigureNumerics(const NumericsConfiguration & configuration)
{
  if (configuration.blasThreads < 0)
  {
    Fail("ConfigureNumerics",
         "blasThreads must be 0 (leave the BLAS as it is) or positive, got " +
           std::to_string(configuration.blasThreads));
  }
  if (OpenBlas().set && configuration.blasThreads > 0)
  {
    OpenBlas().set(configuration.blasThreads);
  }
  return NumericsState{ OpenBlas().set != nullptr, BlasThreads() };
}

int
BlasThreads()
{
  return OpenBlas().get ? OpenBlas().get() : -1;
}
} // namespace bmr
