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
#include "bmrStatistics.h"

#include "bmrError.h"

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>

namespace bmr {

SummaryStatistics
Summarize(const std::vector<double> & values)
{
  if (values.empty())
  {
    Fail("bmr::Summarize", "no values to summarize");
  }
  SummaryStatistics s;
  s.count = values.size();
  s.minimum = values.front();
  s.maximum = values.front();
  double sum = 0.0;
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      Fail("bmr::Summarize", "a value is not finite");
    }
    sum += v;
    s.minimum = std::min(s.minimum, v);
    s.maximum = std::max(s.maximum, v);
  }
  s.mean = sum / double(values.size());
  double squares = 0.0;
  for (double v : values)
  {
    squares += (v - s.mean) * (v - s.mean);
  }
  s.standardDeviation = values.size() > 1 ? std::sqrt(squares / double(values.size() - 1)) : 0.0;
  s.median = Percentile(values, 50.0);
  return s;
}

double
Percentile(std::vector<double> values, double q)
{
  if (values.empty() || !(q >= 0.0 && q <= 100.0))
  {
    Fail("bmr::Percentile", "needs at least one value and 0 <= q <= 100 (q = " + std::to_string(q) + ")");
  }
  std::sort(values.begin(), values.end());
  const double      position = q / 100.0 * double(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  const double      f = position - double(below);
  return values[below] + f * (values[above] - values[below]);
}

PairedTTestResult
PairedTTest(const std::vector<double> & a, const std::vector<double> & b)
{
  if (a.size() != b.size() || a.size() < 2)
  {
    Fail("bmr::PairedTTest",
         "needs two samples of equal length >= 2 (got " + std::to_string(a.size()) + " and " +
           std::to_string(b.size()) + ")");
  }
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    d[i] = a[i] - b[i];
  }
  const SummaryStatistics s = Summarize(d);
  PairedTTestResult       r;
  r.count = d.size();
  r.meanDifference = s.mean;
  r.standardDeviation = s.standardDeviation;
  r.degreesOfFreedom = double(d.size() - 1);
  if (s.standardDeviation == 0.0)
  {
    r.t = s.mean == 0.0 ? 0.0 : std::copysign(std::numeric_limits<double>::infinity(), s.mean);
    r.pValue = s.mean == 0.0 ? 1.0 : 0.0;
    return r;
  }
  r.t = s.mean / (s.standardDeviation / std::sqrt(double(d.size())));
  const boost::math::students_t distribution(r.degreesOfFreedom);
  r.pValue = 2.0 * boost::math::cdf(boost::math::complement(distribution, std::abs(r.t)));
  return r;
}

std::vector<double>
AverageRanks(const std::vector<double> & values)
{
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      Fail("bmr::AverageRanks", "a value is not finite");
    }
  }
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{ 0 });
  std::stable_sort(
    order.begin(), order.end(), [&values](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(values.size());
  for (std::size_t begin = 0; begin < order.size();)
  {
    std::size_t end = begin + 1;
    while (end < order.size() && values[order[end]] == values[order[begin]])
    {
      ++end;
    }
    // Sorted positions begin + 1, ..., end (1-based) share their average.
    const double rank = 0.5 * (double(begin + 1) + double(end));
    for (std::size_t k = begin; k < end; ++k)
    {
      ranks[order[k]] = rank;
    }
    begin = end;
  }
  return ranks;
}

const char *
ToString(CorrelationEnum value)
{
  switch (value)
  {
    case CorrelationEnum::Pearson:
      return "pearson";
    case CorrelationEnum::Spearman:
      return "spearman";
    case CorrelationEnum::KendallTauB:
      return "kendall_tau_b";
  }
  return "unknown";
}

std::ostream &
operator<<(std::ostream & os, CorrelationEnum value)
{
  return os << ToString(value);
}

namespace {

constexpr const char * CorrelationWhere = "bmr::CorrelationTest";

/** Sizes of the groups of equal values (groups of one included). */
std::vector<double>
TieGroupSizes(std::vector<double> values)
{
  std::sort(values.begin(), values.end());
  std::vector<double> sizes;
  for (std::size_t begin = 0; begin < values.size();)
  {
    std::size_t end = begin + 1;
    while (end < values.size() && values[end] == values[begin])
    {
      ++end;
    }
    sizes.push_back(double(end - begin));
    begin = end;
  }
  return sizes;
}

/** Pearson r with its permutation count: r = sum a_i b_i / sqrt(sum a_i^2 sum b_i^2) of the centred values.
 * The denominator does not change when b is permuted, so the permutations compare numerators; the identity
 * permutation repeats the observed sum term by term and so always counts. */
void
PearsonTest(const std::vector<double> & x,
            const std::vector<double> & y,
            bool                        enumerate,
            CorrelationTestResult &     result)
{
  const std::size_t   n = x.size();
  const double        meanX = std::accumulate(x.begin(), x.end(), 0.0) / double(n);
  const double        meanY = std::accumulate(y.begin(), y.end(), 0.0) / double(n);
  std::vector<double> a(n);
  std::vector<double> b(n);
  double              saa = 0.0;
  double              sbb = 0.0;
  double              sab = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    a[i] = x[i] - meanX;
    b[i] = y[i] - meanY;
    saa += a[i] * a[i];
    sbb += b[i] * b[i];
    sab += a[i] * b[i];
  }
  double denominator = std::sqrt(saa * sbb);
  if (!std::isfinite(denominator) || denominator == 0.0)
  {
    denominator = std::sqrt(saa) * std::sqrt(sbb); // saa * sbb over- or underflows
  }
  if (!(denominator > 0.0) || !std::isfinite(denominator) || !std::isfinite(sab))
  {
    Fail(CorrelationWhere, "the sums of squares of the centred values are not finite and positive");
  }
  const double r = std::clamp(sab / denominator, -1.0, 1.0);
  result.coefficient = r;
  const double degreesOfFreedom = double(n - 2);
  if (std::abs(r) == 1.0)
  {
    result.statistic = std::copysign(std::numeric_limits<double>::infinity(), r);
    result.pValueApproximate = 0.0;
  }
  else
  {
    result.statistic = r * std::sqrt(degreesOfFreedom / ((1.0 - r) * (1.0 + r)));
    const boost::math::students_t distribution(degreesOfFreedom);
    result.pValueApproximate =
      2.0 * boost::math::cdf(boost::math::complement(distribution, std::abs(result.statistic)));
  }
  if (!enumerate)
  {
    return;
  }
  const double             threshold = std::abs(sab) * (1.0 - 1e-12);
  std::vector<std::size_t> permutation(n);
  std::iota(permutation.begin(), permutation.end(), std::size_t{ 0 });
  std::uint64_t reached = 0;
  std::uint64_t total = 0;
  do
  {
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i)
    {
      sum += a[i] * b[permutation[i]];
    }
    reached += std::abs(sum) >= threshold ? 1 : 0;
    ++total;
  } while (std::next_permutation(permutation.begin(), permutation.end()));
  result.pValuePermutation = double(reached) / double(total);
  result.permutationExact = true;
}

/** sign(v_i - v_j) at [i n + j]. */
std::vector<int>
PairSigns(const std::vector<double> & v)
{
  const std::size_t n = v.size();
  auto              sign = [](double a, double b) { return int(a > b) - int(a < b); };
  std::vector<int>  signs(n * n);
  for (std::size_t i = 0; i < n; ++i)
  {
    for (std::size_t j = 0; j < n; ++j)
    {
      signs[i * n + j] = sign(v[i], v[j]);
    }
  }
  return signs;
}

/** The sums over one sample's groups of ties (size t) that tau-b and the variance of n_c - n_d need. */
struct KendallTieSums
{
  double pairs = 0.0;    // sum t(t-1)/2
  double variance = 0.0; // sum t(t-1)(2t+5)
  double first = 0.0;    // sum t(t-1)
  double second = 0.0;   // sum t(t-1)(t-2)
};

KendallTieSums
TieSums(const std::vector<double> & values)
{
  KendallTieSums sums;
  for (double t : TieGroupSizes(values))
  {
    sums.pairs += t * (t - 1.0) / 2.0;
    sums.variance += t * (t - 1.0) * (2.0 * t + 5.0);
    sums.first += t * (t - 1.0);
    sums.second += t * (t - 1.0) * (t - 2.0);
  }
  return sums;
}

/** The fraction of the permutations of y whose |n_c - n_d| reaches |\a difference|, the observed one. */
double
KendallPermutationPValue(const std::vector<int> & signX,
                         const std::vector<int> & signY,
                         std::size_t              n,
                         long long                difference)
{
  const long long          observed = difference < 0 ? -difference : difference;
  std::vector<std::size_t> permutation(n);
  std::iota(permutation.begin(), permutation.end(), std::size_t{ 0 });
  std::uint64_t reached = 0;
  std::uint64_t total = 0;
  do
  {
    long long sum = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      const int * rowX = &signX[i * n];
      const int * rowY = &signY[permutation[i] * n];
      for (std::size_t j = i + 1; j < n; ++j)
      {
        sum += rowX[j] * rowY[permutation[j]];
      }
    }
    reached += (sum < 0 ? -sum : sum) >= observed ? 1 : 0;
    ++total;
  } while (std::next_permutation(permutation.begin(), permutation.end()));
  return double(reached) / double(total);
}

/** Kendall tau-b with its permutation count. Permuting y keeps its groups of ties, so tau-b's denominator is
 * fixed and the permutations compare the integer n_c - n_d exactly. */
void
KendallTest(const std::vector<double> & x,
            const std::vector<double> & y,
            bool                        enumerate,
            CorrelationTestResult &     result)
{
  const std::size_t n = x.size();
  // signX[i n + j] and signY[i n + j]: sign(x_i - x_j) and sign(y_i - y_j).
  const std::vector<int> signX = PairSigns(x);
  const std::vector<int> signY = PairSigns(y);
  long long              difference = 0; // n_c - n_d
  for (std::size_t i = 0; i < n; ++i)
  {
    for (std::size_t j = i + 1; j < n; ++j)
    {
      difference += signX[i * n + j] * signY[i * n + j];
    }
  }
  const double         nn = double(n);
  const double         n0 = nn * (nn - 1.0) / 2.0;
  const KendallTieSums tx = TieSums(x);
  const KendallTieSums ty = TieSums(y);
  const double         s = double(difference);
  result.coefficient = std::clamp(s / std::sqrt((n0 - tx.pairs) * (n0 - ty.pairs)), -1.0, 1.0);
  const double v0 = nn * (nn - 1.0) * (2.0 * nn + 5.0);
  const double variance = (v0 - tx.variance - ty.variance) / 18.0 + tx.first * ty.first / (2.0 * nn * (nn - 1.0)) +
                          tx.second * ty.second / (9.0 * nn * (nn - 1.0) * (nn - 2.0));
  if (!(variance > 0.0))
  {
    Fail(CorrelationWhere, "the variance of Kendall's n_c - n_d is not positive (" + std::to_string(variance) + ")");
  }
  result.statistic = s / std::sqrt(variance);
  const boost::math::normal distribution(0.0, 1.0);
  result.pValueApproximate = 2.0 * boost::math::cdf(boost::math::complement(distribution, std::abs(result.statistic)));
  if (!enumerate)
  {
    return;
  }
  result.pValuePermutation = KendallPermutationPValue(signX, signY, n, difference);
  result.permutationExact = true;
}

} // namespace

CorrelationTestResult
CorrelationTest(const std::vector<double> & x,
                const std::vector<double> & y,
                CorrelationEnum             method,
                std::size_t                 maxExactPermutationCount)
{
  if (x.size() != y.size() || x.size() < 3)
  {
    Fail(CorrelationWhere,
         "needs two samples of equal length >= 3 (got " + std::to_string(x.size()) + " and " +
           std::to_string(y.size()) + ")");
  }
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
    {
      Fail(CorrelationWhere, "pair " + std::to_string(i) + " holds a value that is not finite");
    }
  }
  auto constant = [](const std::vector<double> & v) {
    return std::all_of(v.begin(), v.end(), [&v](double e) { return e == v.front(); });
  };
  if (constant(x) || constant(y))
  {
    Fail(CorrelationWhere,
         std::string(constant(x) ? "x" : "y") + " is constant: the " + ToString(method) + " correlation is undefined");
  }
  const bool enumerate = x.size() <= maxExactPermutationCount;
  if (enumerate && x.size() > 20)
  {
    Fail(CorrelationWhere,
         "an exact permutation test of " + std::to_string(x.size()) +
           " pairs would enumerate more than 20! permutations (lower maxExactPermutationCount)");
  }
  CorrelationTestResult result;
  result.method = method;
  result.count = x.size();
  switch (method)
  {
    case CorrelationEnum::Pearson:
      PearsonTest(x, y, enumerate, result);
      break;
    case CorrelationEnum::Spearman:
      PearsonTest(AverageRanks(x), AverageRanks(y), enumerate, result);
      break;
    case CorrelationEnum::KendallTauB:
      KendallTest(x, y, enumerate, result);
      break;
    default:
      Fail(CorrelationWhere, "unknown correlation method");
  }
  return result;
}

} // namespace bmr
