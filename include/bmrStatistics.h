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
#include <cstdint>
#include <limits>
#include <ostream>
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

/** Ranks 1..n of \a values, ties given the average of the ranks they span ("fractional" ranking): the
 * values sorted ascending, a group of t equal values at sorted positions k+1, ..., k+t gets the rank
 * k + (t + 1) / 2. Throws when a value is not finite. */
BiomechanicalRegistration_EXPORT std::vector<double>
                                 AverageRanks(const std::vector<double> & values);

/** The correlation coefficient of CorrelationTest(). */
enum class CorrelationEnum : std::uint8_t
{
  /** r = sum (x_i - mean x)(y_i - mean y) / sqrt(sum (x_i - mean x)^2 sum (y_i - mean y)^2). */
  Pearson,
  /** rho = Pearson r of AverageRanks(x) and AverageRanks(y). */
  Spearman,
  /** tau-b = (n_c - n_d) / sqrt((n0 - n1)(n0 - n2)), n_c and n_d the concordant and discordant pairs,
   * n0 = n(n-1)/2, n1 = sum t_i(t_i-1)/2 over the groups of tied x and n2 likewise over the tied y. */
  KendallTauB
};
/** "pearson", "spearman" or "kendall_tau_b". */
BiomechanicalRegistration_EXPORT const char *
                                 ToString(CorrelationEnum value);
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, CorrelationEnum value);

/** \brief A correlation coefficient of paired samples with two two-sided p-values for "no association".
 *
 * Pearson and Spearman: t = r sqrt((n-2)/(1-r^2)) and pValueApproximate = 2 (1 - F_{n-2}(|t|)), F the
 * Student t distribution function (exact for Pearson r of bivariate normal samples; an approximation for
 * Spearman rho). When |r| = 1, t is infinite (with the sign of r) and pValueApproximate = 0.
 *
 * Kendall tau-b: z = (n_c - n_d) / sqrt(v) with the tie-corrected variance of n_c - n_d under independence
 * (Kendall 1970; SciPy's kendalltau, method 'asymptotic'),
 *   v = (v0 - vt - vu)/18 + v1/(2n(n-1)) + v2/(9n(n-1)(n-2)),
 *   v0 = n(n-1)(2n+5), vt = sum t(t-1)(2t+5), vu = sum u(u-1)(2u+5),
 *   v1 = [sum t(t-1)] [sum u(u-1)], v2 = [sum t(t-1)(t-2)] [sum u(u-1)(u-2)],
 * t and u the sizes of the groups of tied x and tied y; pValueApproximate = 2 (1 - Phi(|z|)).
 *
 * pValuePermutation: the fraction of all n! permutations of y (x fixed, the identity included) whose
 * coefficient c satisfies |c| >= |observed| (1 - 1e-12), the relative tolerance absorbing rounding between
 * permutations with equal exact coefficients. Exact under the null hypothesis that the pairing of x and y
 * is exchangeable; enumerated with std::next_permutation, so deterministic. NaN (permutationExact false)
 * when n > maxExactPermutationCount. */
struct BiomechanicalRegistration_EXPORT CorrelationTestResult
{
  CorrelationEnum method{ CorrelationEnum::Pearson };
  std::size_t     count{ 0 };
  double          coefficient{ 0 };       ///< r, rho or tau-b
  double          statistic{ 0 };         ///< t for Pearson and Spearman, z for Kendall
  double          pValueApproximate{ 1 }; ///< two-sided: Student t (n-2 dof) or normal (Kendall)
  double          pValuePermutation{ std::numeric_limits<double>::quiet_NaN() }; ///< two-sided, exact
  bool            permutationExact{ false };
};

/** Correlation of \a x and \a y by \a method, with its approximate and (for n <= \a maxExactPermutationCount)
 * exact permutation p-values; n! coefficients are computed, so keep \a maxExactPermutationCount near 10
 * (10! = 3628800; at most 20). Throws when the sizes differ, n < 3, a value is not finite or x or y is
 * constant (the correlation is then undefined). */
BiomechanicalRegistration_EXPORT CorrelationTestResult
CorrelationTest(const std::vector<double> & x,
                const std::vector<double> & y,
                CorrelationEnum             method,
                std::size_t                 maxExactPermutationCount = 10);

} // namespace bmr

#endif
