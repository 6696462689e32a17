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
// Intervals of an estimated modulus: from bootstrap resamples or the curvature of Phi*, and bounds.
#include "itkPipelineStages.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace itk {
namespace pipeline {
namespace {
/** Student's t quantile for probability \a p (> 0.5) and \a dof degrees of freedom: the Cornish-Fisher
 * expansion about the normal quantile \a z (Abramowitz & Stegun 26.7.5), within 1e-3 for dof >= 3. */
double
StudentQuantile(double z, double dof)
{
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4.0 * dof) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof) +
         (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * dof * dof * dof);
}

double
Median(std::vector<double> x)
{
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

/** An interval end within 0.1 % of a search bound, or beyond it, is set by the bound, not by the images. */
bool
ReachesLower(double E, const bmr::UnknownModulus & u)
{
  return E <= 1.001 * u.lowerBound;
}
bool
ReachesUpper(double E, const bmr::UnknownModulus & u)
{
  return E >= 0.999 * u.upperBound;
}

/** Marks the ends the images do not determine and extends the interval to the search bound there (the data say
 * nothing beyond what the search saw); a determined end stays within the bounds. */
void
JudgeBounds(ModulusInterval & i, const bmr::UnknownModulus & u, bool lowerReached, bool upperReached)
{
  i.lowerDetermined = !(lowerReached || ReachesLower(i.interval95[0], u));
  i.upperDetermined = !(upperReached || ReachesUpper(i.interval95[1], u));
  for (auto * interval : { &i.interval68, &i.interval95 })
  {
    auto & [lo, hi] = *interval;
    lo = i.lowerDetermined ? std::min(std::max(lo, u.lowerBound), u.upperBound) : u.lowerBound;
    hi = i.upperDetermined ? std::max(std::min(hi, u.upperBound), u.lowerBound) : u.upperBound;
    // A bias correction may carry a one-sided bound beyond the search range: the search never saw it.
    lo = std::min(lo, u.upperBound);
    hi = std::max(hi, u.lowerBound);
  }
  i.estimate = std::min(std::max(i.estimate, u.lowerBound), u.upperBound);
}

/** Student's half-widths t_(n-1) sqrt(1 + 1/n) at 68 % and 95 % (the predictive interval of one more draw). */
std::array<double, 2>
StudentHalfWidths(std::size_t n)
{
  const double predictive = std::sqrt(1.0 + 1.0 / double(n));
  return { { StudentQuantile(0.994457883, double(n - 1)) * predictive,
             StudentQuantile(1.959963985, double(n - 1)) * predictive } };
}
} // namespace
} // namespace pipeline

bool
UsesCalibratedHalfWidths(UncertaintyMethodEnum method, IntervalQuantilesEnum quantiles)
{
  return method == UncertaintyMethodEnum::Rescan && quantiles == IntervalQuantilesEnum::Calibrated;
}

std::array<double, 2>
IntervalHalfWidths(UncertaintyMethodEnum method, IntervalQuantilesEnum quantiles, std::size_t resamples)
{
  if (resamples < 3)
  {
    const double inf = std::numeric_limits<double>::infinity();
    return { { inf, inf } };
  }
  const std::array<double, 2> student = pipeline::StudentHalfWidths(resamples);
  if (!UsesCalibratedHalfWidths(method, quantiles))
  {
    return student;
  }
  // The calibration used 8 resamples; another n changes how well s is known as Student's factor says.
  constexpr std::size_t       calibrationResamples = 8;
  const std::array<double, 2> reference = pipeline::StudentHalfWidths(calibrationResamples);
  return { { RescanCalibratedHalfWidth68 * student[0] / reference[0],
             RescanCalibratedHalfWidth95 * student[1] / reference[1] } };
}

namespace pipeline {
ModulusInterval
BootstrapInterval(double                        fit,
                  const std::vector<double> &   resamples,
                  const bmr::UnknownModulus &   unknown,
                  bool                          correctBias,
                  const std::array<double, 2> & halfWidths)
{
  ModulusInterval i;
  i.method = "bootstrap";
  i.fit = fit;
  i.resampleModuli = resamples;
  const std::size_t n = resamples.size();
  if (n < 3)
  {
    // Too few resamples to say anything: an interval over the whole search range.
    i.estimate = fit;
    i.logSigma = std::numeric_limits<double>::infinity();
    i.interval68 = i.interval95 = { { unknown.lowerBound, unknown.upperBound } };
    JudgeBounds(i, unknown, true, true);
    return i;
  }
  std::vector<double> logs;
  bool                lowerReached = ReachesLower(fit, unknown), upperReached = ReachesUpper(fit, unknown);
  for (double E : resamples)
  {
    logs.push_back(std::log(E));
    lowerReached = lowerReached || ReachesLower(E, unknown);
    upperReached = upperReached || ReachesUpper(E, unknown);
  }
  i.logBias = Median(logs) - std::log(fit);
  double mean = 0.0, sum2 = 0.0;
  for (double l : logs)
  {
    mean += l / double(n);
  }
  for (double l : logs)
  {
    sum2 += (l - mean) * (l - mean);
  }
  i.logSigma = std::sqrt(sum2 / double(n - 1));
  // The median of n resamples has a standard error of about 1.25 s / sqrt(n): a smaller b is the resamples'
  // own noise, and correcting by it only adds that noise.
  i.biasCorrected =
    correctBias && std::abs(i.logBias) > BootstrapBiasSignificance * 1.2533 * i.logSigma / std::sqrt(double(n));
  const double center = std::log(fit) - (i.biasCorrected ? i.logBias : 0.0);
  const double half68 = halfWidths[0] * i.logSigma;
  const double half95 = halfWidths[1] * i.logSigma;
  i.estimate = std::exp(center);
  i.interval68 = { { std::exp(center - half68), std::exp(center + half68) } };
  i.interval95 = { { std::exp(center - half95), std::exp(center + half95) } };
  JudgeBounds(i, unknown, lowerReached, upperReached);
  return i;
}

ModulusInterval
CurvatureInterval(double fit, double logSigma, const bmr::UnknownModulus & unknown)
{
  ModulusInterval i;
  i.method = "curvature";
  i.quantiles = "normal";
  i.fit = i.estimate = fit;
  i.logSigma = logSigma;
  if (!std::isfinite(logSigma))
  {
    i.interval68 = i.interval95 = { { unknown.lowerBound, unknown.upperBound } };
    JudgeBounds(i, unknown, true, true);
    return i;
  }
  i.interval68 = { { fit * std::exp(-logSigma), fit * std::exp(logSigma) } };
  i.interval95 = { { fit * std::exp(-1.959963985 * logSigma), fit * std::exp(1.959963985 * logSigma) } };
  JudgeBounds(i, unknown, ReachesLower(fit, unknown), ReachesUpper(fit, unknown));
  return i;
}

} // namespace pipeline
} // namespace itk
