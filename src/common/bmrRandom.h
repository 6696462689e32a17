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
#ifndef bmrRandom_h
#define bmrRandom_h

// Random numbers that are the same on every platform (private to src/).
#include <cstdint>
#include <random>

namespace bmr {

/** A uniform number in [lo, hi) from \a rng's raw integers: std::mt19937_64's sequence is fixed by the standard,
 * its distributions are not, so the same seed gives the same number on every platform. */
inline double
Uniform(std::mt19937_64 & rng, double lo, double hi)
{
  return lo + (hi - lo) * (double(rng() >> 11) / double(std::uint64_t(1) << 53));
}

} // namespace bmr

#endif
