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
#ifndef bmrStopwatch_h
#define bmrStopwatch_h

#include <chrono>
#include <cstdio>
#include <string>

namespace bmr {

/** The clock of every wall time the module reports (monotonic). */
using SteadyClock = std::chrono::steady_clock;

/** Wall time [s] since \a start. */
inline double
SecondsSince(SteadyClock::time_point start)
{
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

/** \a seconds with two decimals, as the stage lines print them. */
inline std::string
SecondsText(double seconds)
{
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", seconds);
  return text;
}

} // namespace bmr

#endif
