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

#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
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

} // namespace bmr
