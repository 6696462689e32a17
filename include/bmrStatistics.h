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
#ifndef bmrStatistics_h
#define bmrStatistics_h

#include "BiomechanicalRegistrationExport.h"

#include <cstddef>
#include <vector>

namespace bmr {

/** Mean, sample standard deviation (divisor n - 1; 0 for one value), minimum, median and maximum. */
struct BiomechanicalRegistration_EXPORT SummaryStatistics
{
  std::size_t count{ 0 };
  double      mean{ 0.0 };
  double      standardDeviation{ 0.0 };
  double      minimum{ 0.0 };
  double      median{ 0.0 };
  double      maximum{ 0.0 };
};

/** Summary of \a values; throws itk::ExceptionObject when it is empty or holds a non-finite value. */
BiomechanicalRegistration_EXPORT SummaryStatistics
Summarize(const std::vector<double> & values);

/** The \a q-th percentile (0 <= q <= 100) with linear interpolation between order statistics
 * (the "linear" definition of NumPy and R's type 7). Throws on an empty input. */
BiomechanicalRegistration_EXPORT double
Percentile(std::vector<double> values, double q);

/** \brief Two-tailed paired Student t-test of the differences d_i = a_i - b_i.
 *
 * t = mean(d) / (sd(d) / sqrt(n)) with n - 1 degrees of freedom, and
 * p = 2 (1 - F_{n-1}(|t|)), F the Student t distribution function. When every difference is equal,
 * sd(d) = 0: p is 1 if they are all zero and 0 otherwise. */
struct BiomechanicalRegistration_EXPORT PairedTTestResult
{
  std::size_t count{ 0 };
  double      meanDifference{ 0.0 };
  double      standardDeviation{ 0.0 }; ///< of the differences
  double      t{ 0.0 };
  double      degreesOfFreedom{ 0.0 };
  double      pValue{ 1.0 };
};

/** Paired t-test of \a a against \a b; throws when they differ in length or hold fewer than 2 pairs. */
BiomechanicalRegistration_EXPORT PairedTTestResult
PairedTTest(const std::vector<double> & a, const std::vector<double> & b);

} // namespace bmr

#endif
