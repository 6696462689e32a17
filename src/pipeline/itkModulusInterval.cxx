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
#include <iomanip>
#include <limits>
#include <sstream>

namespace itk {
namespace pipeline {
namespace {
/** Student's t distribution function minus 1/2 at \a t >= 0 with \a dof degrees of freedom: the density integrated
 * over [0, t] by Simpson's rule on 2000 panels (smooth integrand: error far below 1e-9 for the t < 100 used here). */
double
StudentHalfCdf(double t, double dof)
{
  const double logNorm =
    std::lgamma(0.5 * (dof + 1.0)) - std::lgamma(0.5 * dof) - 0.5 * std::log(dof * 3.14159265358979);
  const auto    density = [&](double x) { return std::exp(logNorm - 0.5 * (dof + 1.0) * std::log1p(x * x / dof)); };
  constexpr int panels = 2000;
  const double  h = t / panels;
  double        sum = density(0.0) + density(t);
  for (int k = 1; k < panels; ++k)
  {
    sum += (k % 2 ? 4.0 : 2.0) * density(k * h);
  }
  return sum * h / 3.0;
}

/** Student's t quantile for probability \a p in (0.5, 1) and \a dof degrees of freedom, by bisection on the
 * distribution function to 1e-10 (a series about the normal quantile is 0.02 off at 3 degrees of freedom). */
double
StudentQuantile(double p, double dof)
{
  double lo = 0.0, hi = 100.0;
  while (hi - lo > 1e-10)
  {
    const double mid = 0.5 * (lo + hi);
    (StudentHalfCdf(mid, dof) < p - 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
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

/** Student's predictive half-width t_(n-p) sqrt(1 + 1/n) at the two-sided \a level: the interval of one more draw
 * about a model of \a parameters fitted to \a n draws (1: their mean; 2: a line). */
double
StudentHalfWidth(double level, std::size_t n, std::size_t parameters)
{
  return StudentQuantile(0.5 + 0.5 * level, double(n - parameters)) * std::sqrt(1.0 + 1.0 / double(n));
}

/** StudentHalfWidth() at 68 % and 95 %. */
std::array<double, 2>
StudentHalfWidths(std::size_t n, std::size_t parameters = 1)
{
  return { { StudentHalfWidth(0.68, n, parameters), StudentHalfWidth(0.95, n, parameters) } };
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
  // Another n than a calibration's changes how well s is known as Student's factor says; scaling up from the
  // count below only narrows as more draws of a normal sample would.
  const RescanCalibration * calibration = &RescanCalibrations[0];
  for (const RescanCalibration & c : RescanCalibrations)
  {
    calibration = c.resamples <= resamples ? &c : calibration;
  }
  const std::array<double, 2> reference = pipeline::StudentHalfWidths(calibration->resamples);
  return { { calibration->halfWidth68 * student[0] / reference[0],
             calibration->halfWidth95 * student[1] / reference[1] } };
}

const SliceCalibration *
FindSliceCalibration(const std::array<double, 3> & movingSpacing, const std::array<double, 3> & fixedSpacing)
{
  std::array<double, 2> slices;
  for (std::size_t scan = 0; scan < 2; ++scan)
  {
    std::array<double, 3> sides = scan == 0 ? movingSpacing : fixedSpacing;
    std::sort(sides.begin(), sides.end());
    if (!(sides[0] >= SliceCalibrationInPlaneMM[0] && sides[1] <= SliceCalibrationInPlaneMM[1]))
    {
      return nullptr;
    }
    slices[scan] = sides[2];
  }
  for (const SliceCalibration & c : SliceCalibrations)
  {
    if (c.pairs >= 3 && std::abs(slices[0] - c.sliceMM) <= SliceCalibrationToleranceMM &&
        std::abs(slices[1] - c.sliceMM) <= SliceCalibrationToleranceMM)
    {
      return &c;
    }
  }
  return nullptr;
}

namespace {
/** phi(a) / (1 - Phi(a)), the inverse Mills ratio; its asymptote a + 1/a where the tail underflows. */
double
InverseMillsRatio(double a)
{
  const double tail = 0.5 * std::erfc(a / std::sqrt(2.0));
  if (tail < 1e-300)
  {
    return a + 1.0 / a;
  }
  return std::exp(-0.5 * a * a) / std::sqrt(2.0 * 3.14159265358979323846) / tail;
}

/** First and second moments of x ~ N(mu, sigma^2) conditioned on x >= c (\a above) or x <= c. */
std::array<double, 2>
CensoredMoments(double mu, double sigma, double c, bool above)
{
  // Below c mirrors above -c: x <= c  <=>  -x >= -c.
  const double m = above ? mu : -mu;
  const double a = ((above ? c : -c) - m) / sigma;
  const double lambda = InverseMillsRatio(a);
  const double mean = m + sigma * lambda;
  const double variance = sigma * sigma * std::max(0.0, 1.0 + a * lambda - lambda * lambda);
  return { { above ? mean : -mean, variance + mean * mean } };
}
} // namespace

CensoredNormalFit
FitCensoredNormal(const std::vector<double> & values, double lowerLimit, double upperLimit)
{
  CensoredNormalFit   fit;
  std::vector<double> seen;
  for (double x : values)
  {
    if (x <= lowerLimit || x >= upperLimit)
    {
      ++fit.censored;
    }
    else
    {
      seen.push_back(x);
    }
  }
  const auto [lowest, highest] = std::minmax_element(seen.begin(), seen.end());
  if (seen.size() < 2 || *lowest == *highest)
  {
    fit.mean = fit.sigma = std::numeric_limits<double>::quiet_NaN();
    return fit;
  }
  const double n = double(values.size());
  double       mu = 0.0, sigma = 0.0;
  for (double x : values)
  {
    mu += x / n;
  }
  for (double x : values)
  {
    sigma += (x - mu) * (x - mu) / n;
  }
  sigma = std::sqrt(sigma);
  // EM raises the likelihood every step; 10000 steps bound the loop where heavy censoring makes it crawl.
  for (int step = 0; step < 10000; ++step)
  {
    double sum = 0.0, sum2 = 0.0;
    for (double x : values)
    {
      const bool                  below = x <= lowerLimit, above = x >= upperLimit;
      const std::array<double, 2> moments = below   ? CensoredMoments(mu, sigma, lowerLimit, false)
                                            : above ? CensoredMoments(mu, sigma, upperLimit, true)
                                                    : std::array<double, 2>{ { x, x * x } };
      sum += moments[0];
      sum2 += moments[1];
    }
    const double nextMu = sum / n;
    const double nextSigma = std::sqrt(std::max(sum2 / n - nextMu * nextMu, 0.0));
    const bool   settled = std::abs(nextMu - mu) < 1e-12 * sigma && std::abs(nextSigma - sigma) < 1e-12 * sigma;
    mu = nextMu;
    sigma = nextSigma;
    if (settled || !(sigma > 0.0))
    {
      break;
    }
  }
  fit.mean = mu;
  fit.sigma = sigma;
  return fit;
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
  // Resamples that stopped on a search bound hide how far they would have gone: their SD understates the spread.
  const CensoredNormalFit censored =
    FitCensoredNormal(logs, std::log(1.001 * unknown.lowerBound), std::log(0.999 * unknown.upperBound));
  i.censoredResamples = censored.censored;
  if (censored.censored > 0 && std::isfinite(censored.sigma))
  {
    i.logSigma = std::max(i.logSigma, censored.sigma * std::sqrt(double(n) / double(n - 1)));
  }
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

void
DeclareNotDetermined(ModulusInterval & interval, const bmr::UnknownModulus & unknown, const std::string & reason)
{
  interval.notDeterminedReason = reason;
  interval.estimate = interval.fit;
  JudgeBounds(interval, unknown, true, true);
}

} // namespace pipeline
namespace {
/** Whether \a calibration has a filling term (in its line or its spread). */
bool
HasFillingTerm(const SliceCalibration & calibration)
{
  return calibration.fillingSlope != 0.0 || calibration.sigmaFillingSlope != 0.0;
}

/** Why \a calibration states nothing at the filling organ's volume change \a fillingChangeML (NaN: not measured):
 * outside the volume changes it was calibrated on; empty when it holds (or has no filling term). */
std::string
FillingOutsideCalibration(const SliceCalibration & calibration, double fillingChangeML)
{
  if (!HasFillingTerm(calibration))
  {
    return {};
  }
  std::ostringstream os;
  os << std::setprecision(3) << "the thick slices' calibration (" << calibration.sliceMM << " mm) corrects for the "
     << SliceCalibrationFillingOrgan << "'s volume change between the scans, ";
  if (std::isnan(fillingChangeML))
  {
    os << "which these labels do not show (no " << SliceCalibrationFillingOrgan << " label)";
    return os.str();
  }
  if (fillingChangeML < calibration.fillingRangeML[0] || fillingChangeML > calibration.fillingRangeML[1])
  {
    os << "and this pair's, " << fillingChangeML << " mL, lies outside the " << calibration.fillingRangeML[0] << " to "
       << calibration.fillingRangeML[1] << " mL it was calibrated on";
    return os.str();
  }
  return {};
}

/** The calibration at one volume change: log(fit / E_0) ~ N(mu(x), sigma(x)^2) of a truth x = log(E / E_0). */
struct CalibrationAtFilling
{
  double shift;      ///< a + gamma (dV - V_0)
  double slope;      ///< beta
  double sigmaLog0;  ///< log(sigma) at x = 0: log s + d (dV - V_0)
  double sigmaSlope; ///< c

  double
  Mean(double x) const
  {
    return shift + slope * x;
  }
  double
  Sigma(double x) const
  {
    return std::exp(sigmaLog0 + sigmaSlope * x);
  }
};

/** Bisection of a sign change of \a f in [lo, hi] (f(lo) and f(hi) of opposite signs) to 1e-13 in x. */
template<typename F>
double
Bisect(const F & f, double lo, double hi)
{
  const bool risingAtLo = f(lo) < 0.0;
  for (int k = 0; k < 200 && hi - lo > 1e-13; ++k)
  {
    const double mid = 0.5 * (lo + hi);
    ((f(mid) < 0.0) == risingAtLo ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/** The ends in x = log(E / E_0) over [xLow, xHigh] of the truths a fit y is consistent with at k: {x : |y - mu(x)|
 * <= k sigma(x)}. mu + k sigma rises with x (beta, c > 0), so the lower end is its one crossing of y; mu - k sigma
 * may turn down where the spread grows faster than the line (stiff truths), so the upper end is its last crossing,
 * found by stepping down from xHigh. An end at xLow or xHigh is not bounded by the calibration. */
std::array<double, 2>
ConsistentTruths(const CalibrationAtFilling & line, double y, double k, double xLow, double xHigh)
{
  const auto   above = [&](double x) { return line.Mean(x) + k * line.Sigma(x) - y; };
  const auto   below = [&](double x) { return line.Mean(x) - k * line.Sigma(x) - y; };
  const double lower = above(xLow) >= 0.0 ? xLow : above(xHigh) < 0.0 ? xHigh : Bisect(above, xLow, xHigh);
  if (below(xHigh) <= 0.0)
  {
    return { { lower, xHigh } };
  }
  constexpr double step = 0.01; // far finer than sigma's scale 1 / c in x
  for (double x = xHigh - step; x > xLow - step; x -= step)
  {
    const double from = std::max(x, xLow);
    if (below(from) <= 0.0)
    {
      return { { lower, Bisect(below, from, std::min(from + step, xHigh)) } };
    }
  }
  return { { lower, xLow } };
}
} // namespace

ModulusInterval
SliceCalibratedInterval(double                      fit,
                        const SliceCalibration &    calibration,
                        const bmr::UnknownModulus & unknown,
                        double                      fillingChangeML)
{
  ModulusInterval i;
  i.method = "slice-calibration";
  i.quantiles = "student";
  i.fit = fit;
  i.calibratedSliceMM = calibration.sliceMM;
  const std::string outside = FillingOutsideCalibration(calibration, fillingChangeML);
  if (!outside.empty())
  {
    pipeline::DeclareNotDetermined(i, unknown, outside);
    return i;
  }
  const double               z = HasFillingTerm(calibration) ? fillingChangeML - calibration.fillingReferenceML : 0.0;
  const CalibrationAtFilling line{ calibration.offset + calibration.fillingSlope * z,
                                   calibration.slope,
                                   std::log(calibration.logSigma) + calibration.sigmaFillingSlope * z,
                                   calibration.sigmaSlope };
  const double               E0 = SliceCalibrationReferenceKPa;
  const double               y = std::log(fit / E0);
  // The classical calibration's estimate: the truth whose line passes through the fit.
  const double estimate = (y - line.shift) / line.slope;
  i.estimate = E0 * std::exp(estimate);
  i.logBias = std::log(fit / i.estimate);
  i.logSigma = line.Sigma(estimate) / line.slope;
  i.biasCorrected = true;
  const unsigned int parameters =
    2 + (calibration.fillingSlope != 0.0) + (calibration.sigmaSlope != 0.0) + (calibration.sigmaFillingSlope != 0.0);
  const std::array<double, 2> k = pipeline::StudentHalfWidths(calibration.pairs, parameters);
  const double                xLow = std::log(unknown.lowerBound / E0), xHigh = std::log(unknown.upperBound / E0);
  for (std::size_t level = 0; level < 2; ++level)
  {
    const std::array<double, 2> ends = ConsistentTruths(line, y, k[level], xLow, xHigh);
    (level == 0 ? i.interval68 : i.interval95) = { { E0 * std::exp(ends[0]), E0 * std::exp(ends[1]) } };
  }
  // A fit on a search bound would have gone at least (at most) there: the bound's own interval end stands, the
  // other is not determined.
  const bool lowerReached = pipeline::ReachesLower(fit, unknown), upperReached = pipeline::ReachesUpper(fit, unknown);
  pipeline::JudgeBounds(i, unknown, lowerReached, upperReached);
  if (i.lowerDetermined && !i.upperDetermined)
  {
    const double kBound = pipeline::StudentHalfWidth(SliceCalibrationBoundLevel, calibration.pairs, parameters);
    i.interval95[0] = E0 * std::exp(ConsistentTruths(line, y, kBound, xLow, xHigh)[0]);
    pipeline::JudgeBounds(i, unknown, lowerReached, upperReached);
  }
  return i;
}

std::string
ModulusIntervalText(const std::string & name, const ModulusInterval & i)
{
  std::ostringstream os;
  os << std::setprecision(3) << name;
  std::ostringstream sliceSource;
  sliceSource << "calibrated on phantom pairs with " << i.calibratedSliceMM << " mm slices";
  const std::string source = i.method == "bootstrap" ? std::to_string(i.resampleModuli.size()) + " bootstrap resamples"
                             : i.method == "rescan"  ? std::to_string(i.resampleModuli.size()) + " rescans"
                             : i.method == "slice-calibration" ? sliceSource.str()
                                                               : std::string("curvature of Phi*");
  if (!i.notDeterminedReason.empty())
  {
    os << " E not determined: " << i.notDeterminedReason << " (the fields use the fit, " << i.fit << " kPa)";
  }
  else if (!i.lowerDetermined && !i.upperDetermined)
  {
    os << " E not determined by the images within the search range " << i.interval95[0] << " to " << i.interval95[1]
       << " kPa (" << source << ")";
  }
  else if (!i.upperDetermined)
  {
    os << " E >= " << i.interval95[0] << " kPa (95 %), the upper end not determined by the images (" << source << ")";
  }
  else if (!i.lowerDetermined)
  {
    os << " E <= " << i.interval95[1] << " kPa (95 %), the lower end not determined by the images (" << source << ")";
  }
  else
  {
    os << " E = " << i.estimate << " kPa (68 %: " << i.interval68[0] << " to " << i.interval68[1]
       << " kPa, 95 %: " << i.interval95[0] << " to " << i.interval95[1] << " kPa; " << source << ", fit " << i.fit
       << " kPa"
       << (!i.biasCorrected                  ? ""
           : i.method == "slice-calibration" ? ", corrected for the thick slices' bias"
                                             : ", corrected for the resamples' bias")
       << ")";
  }
  return os.str();
}

} // namespace itk
