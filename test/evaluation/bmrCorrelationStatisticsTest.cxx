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
// Rank and correlation statistics (bmrStatistics.h):
// - the dissertation's Table 3.2 (mean prostate modulus against T-stage): Pearson r and Spearman rho with their
//   t-test p-values against the published 3-digit values, Kendall tau-b against a hand count of the pairs, and
//   the exact permutation p-values of all three against an independent enumeration;
// - average ranks and Spearman / Kendall with ties in both variables, derived by hand;
// - exact permutation p-values of tiny cases counted by hand;
// - Pearson against closed forms (|r| = 1 without NaN; r = 0.8 with the Student t CDF for 3 dof in closed form);
// - the refused inputs.
#include "bmrStatistics.h"
#include "bmrTestUtilities.h"
#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {
bool
Near(double a, double b, double tolerance, const std::string & what)
{
  if (!(std::abs(a - b) <= tolerance))
  {
    std::cerr << "FAIL: " << what << ": " << bmr::test::ToString(a) << " != " << bmr::test::ToString(b)
              << " (tolerance " << tolerance << ")" << std::endl;
    return false;
  }
  return true;
}

/** Two-sided p of Student's t with 8 degrees of freedom in closed form (even dof): with tan(theta) = |t| / sqrt(8),
 * p = 1 - sin(theta) (1 + cos^2/2 + 1*3/(2*4) cos^4 + 1*3*5/(2*4*6) cos^6). */
double
StudentTwoSidedP8(double t)
{
  const double theta = std::atan(std::abs(t) / std::sqrt(8.0));
  const double c2 = std::cos(theta) * std::cos(theta);
  return 1.0 - std::sin(theta) * (1.0 + c2 / 2.0 + 3.0 / 8.0 * c2 * c2 + 15.0 / 48.0 * c2 * c2 * c2);
}

/** Two-sided p of the standard normal, through std::erfc (independent of Boost.Math). */
double
NormalTwoSidedP(double z)
{
  return std::erfc(std::abs(z) / std::sqrt(2.0));
}

/** Kendall's pair counts by a naive double loop over the pairs i < j. */
struct PairCounts
{
  int concordant{ 0 };
  int discordant{ 0 };
  int tiedXOnly{ 0 };
  int tiedYOnly{ 0 };
  int tiedBoth{ 0 };
};
PairCounts
CountPairs(const std::vector<double> & x, const std::vector<double> & y)
{
  PairCounts c;
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    for (std::size_t j = i + 1; j < x.size(); ++j)
    {
      const double dx = x[i] - x[j];
      const double dy = y[i] - y[j];
      if (dx == 0.0 && dy == 0.0)
        ++c.tiedBoth;
      else if (dx == 0.0)
        ++c.tiedXOnly;
      else if (dy == 0.0)
        ++c.tiedYOnly;
      else if (dx * dy > 0.0)
        ++c.concordant;
      else
        ++c.discordant;
    }
  }
  return c;
}
} // namespace

int
bmrCorrelationStatisticsTest(int, char *[])
{
  using bmr::CorrelationEnum;
  using bmr::CorrelationTest;
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool ok = true;

  // 1. Table 3.2 of the dissertation: mean prostate modulus [kPa] of ten patients and their T-stages.
  // Published: Pearson r = 0.662 (p = 0.037), Spearman rho = 0.701 (p = 0.024).
  {
    const std::vector<double> x = { 48.60, 53.99, 71.97, 60.81, 38.06, 45.42, 40.67, 52.40, 51.47, 56.19 };
    const std::vector<double> y = { 1, 3, 3, 2, 1, 1, 2, 2, 1, 2 };
    const auto                pearson = CorrelationTest(x, y, CorrelationEnum::Pearson);
    const auto                spearman = CorrelationTest(x, y, CorrelationEnum::Spearman);
    const auto                kendall = CorrelationTest(x, y, CorrelationEnum::KendallTauB);
    std::cout << std::setprecision(10) << "Table 3.2: pearson r = " << pearson.coefficient
              << " t = " << pearson.statistic << " p = " << pearson.pValueApproximate
              << " p_perm = " << pearson.pValuePermutation << std::endl
              << "Table 3.2: spearman rho = " << spearman.coefficient << " t = " << spearman.statistic
              << " p = " << spearman.pValueApproximate << " p_perm = " << spearman.pValuePermutation << std::endl
              << "Table 3.2: kendall tau-b = " << kendall.coefficient << " z = " << kendall.statistic
              << " p = " << kendall.pValueApproximate << " p_perm = " << kendall.pValuePermutation << std::endl;
    ok &= Expect(pearson.method == CorrelationEnum::Pearson && pearson.count == 10, "Pearson result: method, count 10");

    // Pearson. The published r is rounded to 3 digits (+-5e-4), and so are the table's means, to 0.01 kPa: to first
    // order, rounding them moves r by at most 0.005 sum_i |dr/dx_i| = 3.2e-4 (dr/dx_i = 0.0156 at most). The table's
    // means give r = 0.661458, 5.4e-4 from 0.662, so the tolerance is 5e-4 + 3.2e-4 -> 8.5e-4; the p-value
    // (0.037256) is within the 3-digit rounding of 0.037, tolerance 5e-4.
    ok &= Near(pearson.coefficient, 0.662, 8.5e-4, "Table 3.2 Pearson r against the published 0.662");
    ok &= Near(pearson.pValueApproximate, 0.037, 5e-4, "Table 3.2 Pearson p against the published 0.037");
    // r of the table's values by the one-pass formula (n sum xy - sum x sum y) / sqrt(...), independent of the
    // two-pass one of CorrelationTest: they agree to rounding (sum x^2 / sum (x - mean)^2 = 32, so ~1e-14), 1e-12.
    {
      double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
      for (std::size_t i = 0; i < x.size(); ++i)
      {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        syy += y[i] * y[i];
        sxy += x[i] * y[i];
      }
      const double n = double(x.size());
      const double r = (n * sxy - sx * sy) / std::sqrt((n * sxx - sx * sx) * (n * syy - sy * sy));
      ok &= Near(pearson.coefficient, r, 1e-12, "Table 3.2 Pearson r against the one-pass formula");
      // An independent double-precision computation (Python, two-pass) gave r = 0.6614578841822429.
      ok &= Near(pearson.coefficient, 0.6614578841822429, 1e-12, "Table 3.2 Pearson r");
    }
    // t = r sqrt(8 / (1 - r^2)) (rounding only, 1e-12) and p against the closed form of 8 dof (Boost.Math and the
    // trigonometric series agree to ~1e-15, 1e-12).
    ok &= Near(pearson.statistic,
               pearson.coefficient * std::sqrt(8.0 / (1.0 - pearson.coefficient * pearson.coefficient)),
               1e-12,
               "Table 3.2 Pearson t");
    ok &= Near(
      pearson.pValueApproximate, StudentTwoSidedP8(pearson.statistic), 1e-12, "Table 3.2 Pearson p, 8 dof closed form");

    // Spearman. Average ranks by hand: x has no ties, ranks (4, 7, 10, 9, 1, 3, 2, 6, 5, 8); y has the tie groups
    // {1} x 4 -> ranks 1..4 -> 2.5, {2} x 4 -> 5..8 -> 6.5, {3} x 2 -> 9, 10 -> 9.5. Centred (mean 5.5):
    // sum (rx - 5.5)^2 = 82.5, sum (ry - 5.5)^2 = 4 * 9 + 4 * 1 + 2 * 16 = 72, sum of products = 54, so
    // rho = 54 / sqrt(82.5 * 72) = 54 / sqrt(5940) = 0.700649 (quarter-integer sums: exact up to the final
    // division and square root, 1e-15). Published 0.701 and p = 0.024: 3-digit rounding, 5e-4 (the ranks do not
    // change when the means are rounded to 0.01 kPa: the closest means are 0.93 kPa apart).
    const std::vector<double> ranksX = { 4, 7, 10, 9, 1, 3, 2, 6, 5, 8 };
    const std::vector<double> ranksY = { 2.5, 9.5, 9.5, 6.5, 2.5, 2.5, 6.5, 6.5, 2.5, 6.5 };
    ok &= Expect(bmr::AverageRanks(x) == ranksX, "Table 3.2 ranks of the moduli, exact");
    ok &= Expect(bmr::AverageRanks(y) == ranksY, "Table 3.2 average ranks of the T-stages, exact");
    ok &= Near(spearman.coefficient, 54.0 / std::sqrt(5940.0), 1e-15, "Table 3.2 Spearman rho by hand");
    ok &= Near(spearman.coefficient, 0.701, 5e-4, "Table 3.2 Spearman rho against the published 0.701");
    ok &= Near(spearman.pValueApproximate, 0.024, 5e-4, "Table 3.2 Spearman p against the published 0.024");
    ok &= Near(spearman.pValueApproximate,
               StudentTwoSidedP8(spearman.statistic),
               1e-12,
               "Table 3.2 Spearman p, 8 dof closed form");

    // Kendall tau-b by hand. In the order of increasing modulus (no ties in x) the T-stages read
    // 1 2 1 1 1 2 3 2 2 3; against the earlier ones, each stage is concordant (c) / discordant (d) / tied (=):
    //   2: 1c; 1: 1d 1=; 1: 1d 2=; 1: 1d 3=; 2: 4c 1=; 3: 6c; 2: 4c 1d 2=; 2: 4c 1d 3=; 3: 8c 1=
    // n_c = 27, n_d = 5, 13 pairs tied in y only (6 + 6 + 1 within the groups of 4, 4 and 2), none in x: 45 pairs.
    // tau-b = (27 - 5) / sqrt((45 - 0)(45 - 13)) = 22 / sqrt(1440) = 0.579751.
    // Variance: v0 = 10 * 9 * 25 = 2250, vt = 0, vu = 2 * (4 * 3 * 13) + 2 * 1 * 9 = 330, v1 = v2 = 0 (no ties in x):
    // v = 1920 / 18 = 320 / 3, z = 22 / sqrt(320 / 3) = 2.130141, p = erfc(z / sqrt 2) = 0.033160.
    // Integer counts: exact; tau and z to rounding, 1e-15; p Boost against std::erfc, 1e-12.
    const PairCounts pairs = CountPairs(x, y);
    ok &=
      Expect(pairs.concordant == 27 && pairs.discordant == 5 && pairs.tiedYOnly == 13 && pairs.tiedXOnly == 0 &&
               pairs.tiedBoth == 0,
             "Table 3.2 pairs: 27 concordant, 5 discordant, 13 tied in y (naive loop: " + ToString(pairs.concordant) +
               ", " + ToString(pairs.discordant) + ", " + ToString(pairs.tiedYOnly) + ")");
    const double n0 = 45.0;
    const double n1 = pairs.tiedXOnly + pairs.tiedBoth;
    const double n2 = pairs.tiedYOnly + pairs.tiedBoth;
    ok &= Near(kendall.coefficient,
               (pairs.concordant - pairs.discordant) / std::sqrt((n0 - n1) * (n0 - n2)),
               1e-15,
               "Table 3.2 tau-b from the naive pair counts");
    ok &= Near(kendall.coefficient, 22.0 / std::sqrt(1440.0), 1e-15, "Table 3.2 tau-b by hand");
    ok &= Near(kendall.statistic, 22.0 / std::sqrt(320.0 / 3.0), 1e-15, "Table 3.2 Kendall z by hand");
    ok &= Near(kendall.pValueApproximate, NormalTwoSidedP(kendall.statistic), 1e-12, "Table 3.2 Kendall p");

    // Exact permutation p-values over the 10! = 3628800 permutations of the T-stages. They are not the t (or
    // normal) p-values: those assume bivariate normal samples (or a large n), while the permutation distribution is
    // discrete (the stages take 3 values: each arrangement of them comes from 4! 4! 2! = 1152 permutations) and exact
    // for n = 10; both estimate the same tail, so a band of 0.03 around the approximate p must hold (the differences
    // are 0.002-0.007). Their values: counts 129024, 110592 and 138240 of a separate enumeration (Python
    // itertools.permutations with the same 1e-12 relative tolerance), i.e. 8/225, 16/525 and 4/105; both count
    // integers, so exact to rounding, 1e-15.
    const std::pair<const bmr::CorrelationTestResult *, double> permutation[] = { { &pearson, 8.0 / 225.0 },
                                                                                  { &spearman, 16.0 / 525.0 },
                                                                                  { &kendall, 4.0 / 105.0 } };
    for (const auto & [result, expected] : permutation)
    {
      const std::string name = std::string("Table 3.2 ") + bmr::ToString(result->method) + " permutation p";
      ok &= Expect(result->permutationExact, name + " is enumerated (n = 10 <= 10)");
      ok &= Expect(result->pValuePermutation > 0.0 && result->pValuePermutation < 1.0,
                   name + " in (0, 1) (got " + ToString(result->pValuePermutation) + ")");
      ok &=
        Near(result->pValuePermutation, result->pValueApproximate, 0.03, name + " within 0.03 of the approximate p");
      ok &= Near(result->pValuePermutation, expected, 1e-15, name + " against the separate enumeration");
    }
  }

  // 2. Ties. AverageRanks: {1, 2, 2, 3} -> 1, (2 + 3) / 2, same, 4; {3, 1, 3, 3, 2}: the three 3s span ranks 3..5
  // -> 4; exact (half-integers).
  {
    ok &= Expect(bmr::AverageRanks({ 1, 2, 2, 3 }) == std::vector<double>{ 1, 2.5, 2.5, 4 }, "ranks of {1, 2, 2, 3}");
    ok &=
      Expect(bmr::AverageRanks({ 3, 1, 3, 3, 2 }) == std::vector<double>{ 4, 1, 4, 4, 2 }, "ranks of {3, 1, 3, 3, 2}");
    ok &= Expect(bmr::AverageRanks({ 5, 5 }) == std::vector<double>{ 1.5, 1.5 }, "ranks of {5, 5}");
    ok &= Expect(bmr::AverageRanks({}).empty(), "ranks of nothing");

    // Ties in both: x = {1, 2, 2, 3}, y = {1, 1, 2, 3}. Ranks (1, 2.5, 2.5, 4) and (1.5, 1.5, 3, 4), centred
    // (-1.5, 0, 0, 1.5) and (-1, -1, 0.5, 1.5): sum of products 1.5 + 2.25 = 3.75, squares 4.5 and 4.5:
    // rho = 5/6. t = (5/6) sqrt(2 / (1 - 25/36)) = 5 sqrt(2/11), and for 2 dof p = 1 - |t| / sqrt(2 + t^2)
    // = 1 - sqrt(50/72) = 1/6.
    // Kendall: pairs (1,2) tied in y, (2,3) tied in x, the other four concordant: n_c - n_d = 4, n1 = n2 = 1,
    // tau-b = 4 / sqrt(5 * 5) = 0.8. v0 = 4 * 3 * 13 = 156, vt = vu = 2 * 1 * 9 = 18, v1 = 2 * 2 = 4, v2 = 0:
    // v = 120/18 + 4/24 = 41/6, z = 4 / sqrt(41/6).
    // Permutations: centred x ranks vanish in the middle, so rho = 1.5 (b_4 - b_1) / 4.5 with b the centred y ranks at
    // the ends; |rho| = 5/6 needs {b_1, b_4} = {-1, 1.5}: 2 ends x 2 of the tied 1s x 2 orders of the middle = 8 of
    // 24 -> 1/3. Kendall |n_c - n_d| = 4 likewise needs a 1 and the 3 at the ends: 8 of 24 -> 1/3.
    // Tolerances: 1e-12 (rounding; Boost's t and normal against closed forms).
    const std::vector<double> x = { 1, 2, 2, 3 };
    const std::vector<double> y = { 1, 1, 2, 3 };
    const auto                spearman = CorrelationTest(x, y, CorrelationEnum::Spearman);
    const auto                kendall = CorrelationTest(x, y, CorrelationEnum::KendallTauB);
    ok &= Near(spearman.coefficient, 5.0 / 6.0, 1e-12, "tied Spearman rho = 5/6");
    ok &= Near(spearman.statistic, 5.0 * std::sqrt(2.0 / 11.0), 1e-12, "tied Spearman t = 5 sqrt(2/11)");
    ok &= Near(spearman.pValueApproximate, 1.0 / 6.0, 1e-12, "tied Spearman p = 1/6 (2 dof)");
    ok &= Near(spearman.pValuePermutation, 1.0 / 3.0, 1e-12, "tied Spearman permutation p = 8/24");
    ok &= Near(kendall.coefficient, 0.8, 1e-12, "tied Kendall tau-b = 0.8");
    ok &= Near(kendall.statistic, 4.0 / std::sqrt(41.0 / 6.0), 1e-12, "tied Kendall z = 4 / sqrt(41/6)");
    ok &= Near(kendall.pValueApproximate, NormalTwoSidedP(4.0 / std::sqrt(41.0 / 6.0)), 1e-12, "tied Kendall p");
    ok &= Near(kendall.pValuePermutation, 1.0 / 3.0, 1e-12, "tied Kendall permutation p = 8/24");
  }

  // 3. Exact permutation p-values counted by hand (tolerance 1e-15: ratios of small integers).
  {
    // x = y = {1, 2, 3, 4}: |coefficient| = 1 only for the identity and the reversal, 2 of 24, for all three.
    const std::vector<double> x = { 1, 2, 3, 4 };
    for (const auto method : { CorrelationEnum::Pearson, CorrelationEnum::Spearman, CorrelationEnum::KendallTauB })
    {
      const auto r = CorrelationTest(x, x, method);
      ok &= Near(r.coefficient, 1.0, 1e-15, std::string(bmr::ToString(method)) + " of y = x is 1");
      ok &= Near(r.pValuePermutation, 2.0 / 24.0, 1e-15, std::string(bmr::ToString(method)) + " permutation p 2/24");
      ok &= Expect(r.permutationExact, std::string(bmr::ToString(method)) + " n = 4 is enumerated");
      // n = 3: identity and reversal of 6.
      const auto r3 = CorrelationTest({ 1, 2, 3 }, { 1, 2, 3 }, method);
      ok &= Near(r3.pValuePermutation, 2.0 / 6.0, 1e-15, std::string(bmr::ToString(method)) + " n = 3 permutation p");
    }
    // Beyond maxExactPermutationCount: NaN, not enumerated.
    const auto skipped = CorrelationTest(x, x, CorrelationEnum::Spearman, 3);
    ok &= Expect(std::isnan(skipped.pValuePermutation) && !skipped.permutationExact,
                 "n = 4 > maxExactPermutationCount = 3: permutation p is NaN");
    // x = {1..5}, y = {2, 1, 4, 3, 5}: Pearson = Spearman, rho = 1 - sum d^2 / 20 with d the displacement of a
    // permutation; |rho| >= 0.8 <=> sum d^2 <= 4 or (mirrored) >= 36: the identity, 4 adjacent swaps and 3 pairs of
    // disjoint adjacent swaps, 8 each side: 16 of 120. Kendall: n_c - n_d = 10 - 2 inv (inv = 2 here, tau = 0.6);
    // |.| >= 6 <=> inv <= 2 or >= 8: Mahonian numbers 1 + 4 + 9 = 14 each side, 28 of 120.
    const std::vector<double> a = { 1, 2, 3, 4, 5 };
    const std::vector<double> b = { 2, 1, 4, 3, 5 };
    ok &= Near(CorrelationTest(a, b, CorrelationEnum::Pearson).pValuePermutation,
               16.0 / 120.0,
               1e-15,
               "Pearson n = 5 permutation p 16/120");
    const auto kendall = CorrelationTest(a, b, CorrelationEnum::KendallTauB);
    ok &= Near(kendall.coefficient, 0.6, 1e-15, "Kendall n = 5 tau = 0.6");
    ok &= Near(kendall.pValuePermutation, 28.0 / 120.0, 1e-15, "Kendall n = 5 permutation p 28/120");
  }

  // 4. Pearson against closed forms.
  {
    // y = 2x + 1 and y = -3x: the centred sums are integers, so r = +-1 exactly; t infinite, p = 0, no NaN.
    const std::vector<double> x = { 1, 2, 3, 4, 5 };
    const auto                up = CorrelationTest(x, { 3, 5, 7, 9, 11 }, CorrelationEnum::Pearson);
    const auto                down = CorrelationTest(x, { -3, -6, -9, -12, -15 }, CorrelationEnum::Pearson);
    ok &= Expect(up.coefficient == 1.0, "y = 2x + 1: r = 1 exactly (got " + ToString(up.coefficient) + ")");
    ok &= Expect(up.statistic == std::numeric_limits<double>::infinity(),
                 "y = 2x + 1: t = +inf (got " + ToString(up.statistic) + ")");
    ok &= Expect(up.pValueApproximate == 0.0, "y = 2x + 1: p = 0 (got " + ToString(up.pValueApproximate) + ")");
    ok &= Expect(down.coefficient == -1.0 && down.statistic == -std::numeric_limits<double>::infinity() &&
                   down.pValueApproximate == 0.0,
                 "y = -3x: r = -1, t = -inf, p = 0 (got " + ToString(down.coefficient) + ", " +
                   ToString(down.statistic) + ", " + ToString(down.pValueApproximate) + ")");
    ok &= Near(up.pValuePermutation, 2.0 / 120.0, 1e-15, "y = 2x + 1: permutation p 2/120");
    // Non-integer data on a line: r is 1 to rounding (1e-15), and neither t nor p may be NaN (p <= 1e-12: t is at
    // least ~1e7 or infinite).
    const auto line = CorrelationTest({ 0.1, 0.2, 0.3, 0.7 }, { 0.3, 0.6, 0.9, 2.1 }, CorrelationEnum::Pearson);
    ok &= Near(line.coefficient, 1.0, 1e-15, "y = 3x, decimals: r = 1");
    ok &= Expect(!std::isnan(line.statistic) && line.statistic > 0 && line.pValueApproximate <= 1e-12,
                 "y = 3x, decimals: t not NaN, p <= 1e-12 (got " + ToString(line.statistic) + ", " +
                   ToString(line.pValueApproximate) + ")");

    // x = {1..5}, y = {2, 1, 4, 3, 5}: centred (-2, -1, 0, 1, 2) and (-1, -2, 1, 0, 2), sum of products 8, squares 10
    // and 10: r = 0.8; t = 0.8 sqrt(3 / 0.36) = 4 / sqrt(3). Student t CDF for 3 dof:
    // F(t) = 1/2 + (1/pi) [(t/sqrt3) / (1 + t^2/3) + atan(t/sqrt3)], so p = 2 (1 - F) = 1 - (2/pi)(12/25 + atan(4/3))
    // = 0.104088. Tolerances 1e-12 (rounding; Boost against the closed form).
    const auto r = CorrelationTest(x, { 2, 1, 4, 3, 5 }, CorrelationEnum::Pearson);
    ok &= Near(r.coefficient, 0.8, 1e-15, "Pearson r = 0.8");
    ok &= Near(r.statistic, 4.0 / std::sqrt(3.0), 1e-12, "Pearson t = 4 / sqrt 3");
    const double pi = std::acos(-1.0);
    const double u = r.statistic / std::sqrt(3.0);
    const double closedForm = 2.0 * (1.0 - (0.5 + (u / (1.0 + u * u) + std::atan(u)) / pi));
    ok &= Near(r.pValueApproximate, closedForm, 1e-12, "Pearson p against the 3 dof closed form");
    ok &= Near(r.pValueApproximate, 1.0 - 2.0 / pi * (12.0 / 25.0 + std::atan(4.0 / 3.0)), 1e-12, "Pearson p by hand");
    std::cout << "r = 0.8, n = 5: t = " << r.statistic << ", p = " << r.pValueApproximate << std::endl;
  }

  // 5. Names, and the refused inputs (each an itk::ExceptionObject naming what is wrong).
  {
    std::ostringstream names;
    names << CorrelationEnum::Pearson << ' ' << CorrelationEnum::Spearman << ' ' << CorrelationEnum::KendallTauB;
    ok &= Expect(names.str() == "pearson spearman kendall_tau_b", "enum names (got \"" + names.str() + "\")");
    using bmr::test::ExpectException;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    const auto   pearson = CorrelationEnum::Pearson;
    ok &= ExpectException(
      "sizes differ",
      [&] {
        CorrelationTest({ 1, 2, 3 }, { 1, 2 }, pearson);
      },
      "equal length >= 3");
    ok &= ExpectException(
      "n = 2",
      [&] {
        CorrelationTest({ 1, 2 }, { 1, 2 }, CorrelationEnum::Spearman);
      },
      "equal length >= 3");
    ok &= ExpectException(
      "NaN in x",
      [&] {
        CorrelationTest({ 1, nan, 3 }, { 1, 2, 3 }, pearson);
      },
      "not finite");
    ok &= ExpectException(
      "infinity in y",
      [&] {
        CorrelationTest({ 1, 2, 3 }, { 1, 2, inf }, CorrelationEnum::KendallTauB);
      },
      "not finite");
    ok &= ExpectException(
      "constant x",
      [&] {
        CorrelationTest({ 2, 2, 2 }, { 1, 2, 3 }, pearson);
      },
      "x is constant");
    ok &= ExpectException(
      "constant y",
      [&] {
        CorrelationTest({ 1, 2, 3, 4 }, { 0.1, 0.1, 0.1, 0.1 }, CorrelationEnum::KendallTauB);
      },
      "y is constant: the kendall_tau_b correlation is undefined");
    ok &= ExpectException(
      "NaN rank",
      [&] {
        bmr::AverageRanks({ 1, nan });
      },
      "not finite");
  }

  std::cout << (ok ? "bmrCorrelationStatisticsTest passed" : "bmrCorrelationStatisticsTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
