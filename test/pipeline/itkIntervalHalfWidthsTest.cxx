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
// The half-widths k of the stated intervals Ehat x/ exp(k s) (itk::IntervalHalfWidths). What is checked, and why
// these limits:
// - Student: k = t_(n-1) sqrt(1 + 1/n) against tabulated t quantiles (scipy.stats.t.ppf: t_3(0.84) = 1.1889286,
//   t_3(0.975) = 3.1824463, t_7(0.84) = 1.0702874, t_7(0.975) = 2.3646243, t_15(0.84) = 1.0285328,
//   t_15(0.975) = 2.1314495) to 1e-6, the tabulated digits (the quantile is inverted from the distribution
//   function to 1e-10);
// - calibrated (the default, rescans): at the calibrated 4 resamples exactly its conformal constants; other n
//   scaled by Student's ratio from the largest calibrated count not above n (4 below 4), so 8 narrower;
// - the bootstrap, which the calibration did not measure, keeps Student's; fewer than 3 resamples give no width.
// The censored normal fit (itk::FitCensoredNormal) that widens a bound's determined end:
// - without censoring it is the sample mean and the divide-by-n deviation (to 1e-12: the same sums);
// - at its result the censored log-likelihood is stationary: moving mu or sigma by 1e-4 sigma either way lowers it
//   (a maximum, found by EM, not imposed), and its slope in mu (central difference) is below 1e-6 per draw;
// - on 4000 draws of N(1, 0.5^2) censored at 1.3 (about 27 % censored) it recovers mu and sigma within four standard
//   errors (about 0.012 and 0.010), where the SD of the clipped values is 25 % low;
// - fewer than two distinct uncensored values give NaN, not a number pretending to be a spread.
// The thick slices' calibration (itk::FindSliceCalibration, itk::SliceCalibratedInterval):
// - it holds where both scans have one calibration's slices (+-0.25 mm, along any axis) and in-plane voxels of
//   0.8-1.2 mm, and nowhere else: not at 1 mm, not at 4 mm, not for a 3 mm scan with a 1 mm one (they lean opposite
//   ways), not at in-plane 1.4 mm;
// - with one spread (c = d = 0) its interval is the closed-form inverse of the line log(fit / E0) = a + beta
//   log(E / E0) + gamma (dV - V0): E0 exp((log(fit / E0) - a - gamma (dV - V0) -+ k s) / beta), k = t_(m-p)
//   sqrt(1 + 1/m) (to 1e-12; t from Student's half-widths, so the degrees of freedom count the parameters);
// - with a spread s exp(c x + d z) (the shipped calibrations) the ends are where |log(fit / E0) - mu(x)| = k sigma(x)
//   (to 1e-10 in log E: the bisection's tolerance is 1e-13), and the inversion is exact: a fit k95 sigma above a
//   truth's line has that truth as its 95 % lower end, one k95 sigma below as its upper end (to 1e-10);
// - where the spread outgrows the line (c large, a fit near stiff truths) every stiffer truth is consistent: the
//   upper end is not determined, and the truth at the search bound is indeed within k95 sigma of the fit;
// - a fit on the upper search bound states "E >=", the upper end not determined; on the lower one "E <=";
// - a filling outside the calibrated volume changes, or no bladder label, states no modulus and says why; the filling
//   a registration hands over (RegistrationResult::VolumeChangeML) is the fixed minus the moving volume, NaN where
//   neither scan shows the organ.
#include "itkModulusInterval.h"
#include "itkRegistrationPipeline.h"
#include "itkIntervalTestSupport.h"
#include "bmrTestUtilities.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

namespace {
/** The log-likelihood of \a values censored at or above \a upper under N(mu, sigma^2). */
double
CensoredLogLikelihood(const std::vector<double> & values, double upper, double mu, double sigma)
{
  double sum = 0.0;
  for (double x : values)
  {
    const double z = ((x >= upper ? upper : x) - mu) / sigma;
    sum += x >= upper ? std::log(0.5 * std::erfc(z / std::sqrt(2.0))) : -0.5 * z * z - std::log(sigma);
  }
  return sum;
}

bool
CheckCensoredFit()
{
  bool                         ok = true;
  const double                 inf = std::numeric_limits<double>::infinity();
  const std::vector<double>    plain{ 0.1, 0.4, -0.3, 0.25, 0.05 };
  const itk::CensoredNormalFit uncensored = itk::FitCensoredNormal(plain, -inf, inf);
  double                       mean = 0.0, variance = 0.0;
  for (double x : plain)
  {
    mean += x / 5.0;
  }
  for (double x : plain)
  {
    variance += (x - mean) * (x - mean) / 5.0;
  }
  ok &= bmr::test::Expect(uncensored.censored == 0 && std::abs(uncensored.mean - mean) < 1e-12 &&
                            std::abs(uncensored.sigma - std::sqrt(variance)) < 1e-12,
                          "no censoring: the sample mean and the divide-by-n deviation");

  std::mt19937_64     random(2044);
  std::vector<double> draws;
  const double        upper = 1.3;
  for (int k = 0; k < 4000; ++k)
  {
    // Box-Muller on the engine's raw bits: the same draws on every standard library.
    const double u1 = (double(random() >> 11) + 0.5) / 9007199254740992.0;
    const double u2 = (double(random() >> 11) + 0.5) / 9007199254740992.0;
    draws.push_back(std::min(upper, 1.0 + 0.5 * std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2)));
  }
  const itk::CensoredNormalFit fit = itk::FitCensoredNormal(draws, -inf, upper);
  double                       clippedMean = 0.0, clippedVariance = 0.0;
  for (double x : draws)
  {
    clippedMean += x / 4000.0;
  }
  for (double x : draws)
  {
    clippedVariance += (x - clippedMean) * (x - clippedMean) / 4000.0;
  }
  ok &= bmr::test::Expect(fit.censored > 900 && fit.censored < 1300, "about 27 % of N(1, 0.5^2) censored at 1.3");
  ok &= bmr::test::Expect(std::abs(fit.mean - 1.0) < 0.012 && std::abs(fit.sigma - 0.5) < 0.010,
                          "censored fit: mu and sigma within four standard errors of 1 and 0.5");
  ok &= bmr::test::Expect(std::sqrt(clippedVariance) < 0.8 * 0.5,
                          "the clipped values' SD understates sigma by more than 20 %");
  const double best = CensoredLogLikelihood(draws, upper, fit.mean, fit.sigma), h = 1e-4 * fit.sigma;
  ok &= bmr::test::Expect(CensoredLogLikelihood(draws, upper, fit.mean + h, fit.sigma) < best &&
                            CensoredLogLikelihood(draws, upper, fit.mean - h, fit.sigma) < best &&
                            CensoredLogLikelihood(draws, upper, fit.mean, fit.sigma + h) < best &&
                            CensoredLogLikelihood(draws, upper, fit.mean, fit.sigma - h) < best,
                          "censored fit: a maximum of the censored likelihood in mu and sigma");
  const double scoreMu = (CensoredLogLikelihood(draws, upper, fit.mean + h, fit.sigma) -
                          CensoredLogLikelihood(draws, upper, fit.mean - h, fit.sigma)) /
                         (2.0 * h);
  ok &= bmr::test::Expect(std::abs(scoreMu) * fit.sigma < 1e-6 * 4000.0,
                          "censored fit: the likelihood's slope in mu vanishes");

  const itk::CensoredNormalFit degenerate = itk::FitCensoredNormal({ 0.2, 0.2, 1.0, 1.0 }, -inf, 1.0);
  ok &= bmr::test::Expect(degenerate.censored == 2 && std::isnan(degenerate.sigma),
                          "one distinct uncensored value: no spread (NaN)");
  return ok;
}

/** k = t_(m-p) sqrt(1 + 1/m) at 68 and 95 % of a calibration with p parameters: Student's half-widths of m - p + 1
 * draws, t_(m-p) sqrt(1 + 1/(m-p+1)), with the factor for m. */
std::array<double, 2>
CalibrationHalfWidths(const itk::SliceCalibration & c)
{
  const unsigned int parameters = 2 + (c.fillingSlope != 0.0) + (c.sigmaSlope != 0.0) + (c.sigmaFillingSlope != 0.0);
  const unsigned int n = c.pairs - parameters + 1;
  const auto         student =
    itk::IntervalHalfWidths(itk::UncertaintyMethodEnum::Rescan, itk::IntervalQuantilesEnum::Student, n);
  const double predictive = std::sqrt(1.0 + 1.0 / c.pairs) / std::sqrt(1.0 + 1.0 / n);
  return { { student[0] * predictive, student[1] * predictive } };
}

bmr::UnknownModulus
ProstateUnknown()
{
  bmr::UnknownModulus unknown;
  unknown.name = "prostate";
  unknown.lowerBound = 20.0;
  unknown.upperBound = 600.0;
  return unknown;
}

bool
Near(double x, double y, double relative)
{
  return std::abs(x - y) <= relative * std::abs(y);
}

/** One spread: the closed-form inverse of the line with its filling term; the text names the slices. */
bool
CheckOneSpread()
{
  bool                        ok = true;
  const itk::SliceCalibration c{ 3.0, 0.3, 1.2, -0.004, 0.3, 0.0, 0.0, 80.0, { 40.0, 120.0 }, 60 };
  const bmr::UnknownModulus   unknown = ProstateUnknown();
  const double                E0 = itk::SliceCalibrationReferenceKPa, shift = 0.3 - 0.004 * (100.0 - 80.0);
  const std::array<double, 2> k = CalibrationHalfWidths(c);
  const auto inverse = [&](double deviation) { return E0 * std::exp((std::log(1.5) - shift + deviation) / 1.2); };
  const itk::ModulusInterval i = itk::SliceCalibratedInterval(150.0, c, unknown, 100.0);
  ok &= bmr::test::Expect(Near(i.estimate, inverse(0.0), 1e-12) && Near(i.interval68[0], inverse(-k[0] * 0.3), 1e-12) &&
                            Near(i.interval68[1], inverse(k[0] * 0.3), 1e-12) &&
                            Near(i.interval95[0], inverse(-k[1] * 0.3), 1e-12) &&
                            Near(i.interval95[1], inverse(k[1] * 0.3), 1e-12) && i.lowerDetermined &&
                            i.upperDetermined && Near(i.logSigma, 0.3 / 1.2, 1e-12),
                          "one spread, 100 mL (V0 80, gamma -0.004): E0 exp((log(fit / E0) - a - gamma 20 -+ k s) / "
                          "beta), k = t_(m-3) sqrt(1 + 1/m)");
  ok &= bmr::test::Expect(itk::ModulusIntervalText("prostate", i).find("3 mm slices") != std::string::npos,
                          "the statement names the calibration's slices: " + itk::ModulusIntervalText("prostate", i));
  // The filling a registration hands over: the fixed minus the moving volume, NaN where neither scan shows it.
  itk::RegistrationResult r;
  r.labelVolumeML = { { "bladder", { { 40.0, 100.0 } } }, { "rectum", { { 0.0, 0.0 } } } };
  ok &= bmr::test::Expect(r.VolumeChangeML("bladder") == 60.0 && std::isnan(r.VolumeChangeML("rectum")) &&
                            std::isnan(r.VolumeChangeML("prostate")),
                          "RegistrationResult::VolumeChangeML: 100 - 40 mL, NaN without the organ in either scan");
  for (double outside : { 30.0, 130.0, std::numeric_limits<double>::quiet_NaN() })
  {
    const itk::ModulusInterval o = itk::SliceCalibratedInterval(150.0, c, unknown, outside);
    const std::string          text = itk::ModulusIntervalText("prostate", o);
    ok &= bmr::test::Expect(!o.notDeterminedReason.empty() && !o.lowerDetermined && !o.upperDetermined &&
                              o.estimate == 150.0 && text.find("not determined") != std::string::npos &&
                              text.find(std::isnan(outside) ? "no bladder label" : "40 to 120 mL") != std::string::npos,
                            "a filling outside 40-120 mL (or none): not determined, and why: " + text);
  }
  return ok;
}

/** The shipped 3 mm calibration (a spread that varies with E and the filling) at its reference filling. */
bool
CheckVaryingSpread(const itk::SliceCalibration & c)
{
  bool                        ok = true;
  const bmr::UnknownModulus   unknown = ProstateUnknown();
  const double                E0 = itk::SliceCalibrationReferenceKPa, V0 = c.fillingReferenceML;
  const std::array<double, 2> k = CalibrationHalfWidths(c);
  const auto                  mu = [&](double E) { return c.offset + c.slope * std::log(E / E0); };
  const auto                  sigma = [&](double E) { return c.logSigma * std::exp(c.sigmaSlope * std::log(E / E0)); };
  const itk::ModulusInterval  i = itk::SliceCalibratedInterval(100.0, c, unknown, V0);
  // |y - mu(x)| - k sigma(x) at an end, in units of log E.
  const auto miss = [&](double E, double kk) { return std::abs(std::abs(0.0 - mu(E)) - kk * sigma(E)) / c.slope; };
  ok &= bmr::test::Expect(Near(i.estimate, E0 * std::exp(-c.offset / c.slope), 1e-12) &&
                            miss(i.interval68[0], k[0]) < 1e-10 && miss(i.interval68[1], k[0]) < 1e-10 &&
                            miss(i.interval95[0], k[1]) < 1e-10 && miss(i.interval95[1], k[1]) < 1e-10 &&
                            i.interval95[0] < i.interval68[0] && i.interval68[1] < i.interval95[1],
                          "a fit of 100 kPa at 3 mm: its ends where |y - mu(x)| = k sigma(x)");
  // A truth whose high fit still states an interval (a bound's lower end is at the stricter level, below).
  const double               truth = 100.0;
  const double               highFit = E0 * std::exp(mu(truth) + k[1] * sigma(truth));
  const double               lowFit = E0 * std::exp(mu(truth) - k[1] * sigma(truth));
  const itk::ModulusInterval high = itk::SliceCalibratedInterval(highFit, c, unknown, V0);
  ok &=
    bmr::test::Expect(high.upperDetermined && Near(high.interval95[0], truth, 1e-10) &&
                        Near(itk::SliceCalibratedInterval(lowFit, c, unknown, V0).interval95[1], truth, 1e-10),
                      "a fit k95 sigma above (below) the line of 100 kPa has 100 kPa as its 95 % lower (upper) end");
  itk::SliceCalibration steep = c;
  steep.sigmaSlope = 2.0; // the spread outgrows the line (beta < k c sigma) below the upper search bound
  const double               stiffFit = 300.0;
  const itk::ModulusInterval open = itk::SliceCalibratedInterval(stiffFit, steep, unknown, V0);
  const double               yStiff = std::log(stiffFit / E0);
  const double muTop = steep.offset + steep.slope * std::log(6.0), sigmaTop = steep.logSigma * std::pow(6.0, 2.0);
  ok &= bmr::test::Expect(open.lowerDetermined && !open.upperDetermined && open.interval95[1] == 600.0 &&
                            std::abs(yStiff - muTop) <= k[1] * sigmaTop,
                          "a spread that outgrows the line: the upper end not determined, and 600 kPa is indeed "
                          "within k95 sigma of the fit: " +
                            itk::ModulusIntervalText("prostate", open));
  // A bound's lower end at SliceCalibrationBoundLevel (99.9 %): with 155 pairs and the line's 5 parameters besides
  // s (a, beta, gamma, c, d), k = t_150 at 0.9995 (3.3565689805997185, scipy.stats.t.ppf) times sqrt(1 + 1/155).
  // Tolerance 1e-8: the library's quantile (Simpson's rule on 2000 panels, then bisection) agrees with scipy's to
  // about 1e-9 this far in the tail; the bisection of the end holds x to 1e-13. The 68 % end stays at its level.
  itk::SliceCalibration counted = c;
  counted.pairs = 155;
  const itk::ModulusInterval bound = itk::SliceCalibratedInterval(600.0, counted, unknown, V0);
  const auto                 impliedK = [&](double E) { return (std::log(6.0) - mu(E)) / sigma(E); };
  const double               k999 = 3.3565689805997185 * std::sqrt(1.0 + 1.0 / 155.0);
  const double               k68 = CalibrationHalfWidths(counted)[0];
  ok &= bmr::test::Expect(!bound.upperDetermined && std::abs(impliedK(bound.interval95[0]) - k999) < 1e-8 &&
                            std::abs(impliedK(bound.interval68[0]) - k68) < 1e-8,
                          "a bound (fit on 600 kPa): log 6 = mu(x) + k sigma(x) at its 95 % lower end with k = " +
                            std::to_string(impliedK(bound.interval95[0])) + " (k_99.9 " + std::to_string(k999) +
                            "), at its 68 % end with k = " + std::to_string(impliedK(bound.interval68[0])) + " (k_68 " +
                            std::to_string(k68) + ")");
  const itk::ModulusInterval onBound = itk::SliceCalibratedInterval(600.0, c, unknown, V0);
  const itk::ModulusInterval onLower = itk::SliceCalibratedInterval(20.0, c, unknown, V0);
  ok &= bmr::test::Expect(
    onBound.lowerDetermined && !onBound.upperDetermined && onBound.notDeterminedReason.empty() &&
      itk::ModulusIntervalText("prostate", onBound).find(">=") != std::string::npos && !onLower.lowerDetermined &&
      onLower.upperDetermined && itk::ModulusIntervalText("prostate", onLower).find("<=") != std::string::npos,
    "a fit on the upper (lower) search bound: E >= (E <=): " + itk::ModulusIntervalText("prostate", onBound) + "; " +
      itk::ModulusIntervalText("prostate", onLower));
  return ok;
}

bool
CheckSliceCalibration()
{
  bool ok = true;
  using Spacing = std::array<double, 3>;
  const itk::SliceCalibration * three = itk::FindSliceCalibration(Spacing{ 0.98, 0.98, 3.0 }, Spacing{ 1.1, 1.1, 3.2 });
  ok &= bmr::test::Expect(three != nullptr && three->sliceMM == 3.0 && three->pairs >= 3,
                          "3 and 3.2 mm slices, in-plane 0.98 and 1.1 mm: the 3 mm calibration");
  const itk::SliceCalibration * sideways =
    itk::FindSliceCalibration(Spacing{ 2.0, 0.9, 0.9 }, Spacing{ 0.9, 2.1, 0.9 });
  ok &= bmr::test::Expect(sideways != nullptr && sideways->sliceMM == 2.0, "2 mm slices along x and y: the 2 mm one");
  ok &= bmr::test::Expect(itk::FindSliceCalibration(Spacing{ 1, 1, 1 }, Spacing{ 1, 1, 1 }) == nullptr &&
                            itk::FindSliceCalibration(Spacing{ 1, 1, 4 }, Spacing{ 1, 1, 4 }) == nullptr &&
                            itk::FindSliceCalibration(Spacing{ 1, 1, 3 }, Spacing{ 1, 1, 1 }) == nullptr &&
                            itk::FindSliceCalibration(Spacing{ 1, 1, 1 }, Spacing{ 1, 1, 3 }) == nullptr &&
                            itk::FindSliceCalibration(Spacing{ 1.4, 1.4, 3 }, Spacing{ 1.4, 1.4, 3 }) == nullptr &&
                            itk::FindSliceCalibration(Spacing{ 1, 1, 2 }, Spacing{ 1, 1, 3 }) == nullptr,
                          "no calibration at 1 or 4 mm, for one thick scan, at in-plane 1.4 mm, for 2 with 3 mm");
  ok &= CheckOneSpread();
  return three ? ok && CheckVaryingSpread(*three) : false;
}
} // namespace

int
itkIntervalHalfWidthsTest(int, char *[])
{
  bool ok = true;
  using itk::IntervalQuantilesEnum;
  using itk::UncertaintyMethodEnum;
  const auto near = [](double a, double b, double tolerance) { return std::abs(a - b) <= tolerance; };

  const auto   student8 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 8);
  const auto   student16 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 16);
  const double root8 = std::sqrt(1.0 + 1.0 / 8.0), root16 = std::sqrt(1.0 + 1.0 / 16.0);
  ok &= bmr::test::Expect(near(student8[0], 1.0702874 * root8, 1e-6) && near(student8[1], 2.3646243 * root8, 1e-6),
                          "Student, 8 resamples: t_7 sqrt(9/8) at 68 and 95 % to 1e-6");
  ok &= bmr::test::Expect(near(student16[0], 1.0285328 * root16, 1e-6) && near(student16[1], 2.1314495 * root16, 1e-6),
                          "Student, 16 resamples: t_15 sqrt(17/16) at 68 and 95 % to 1e-6");

  const auto   student4 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 4);
  const double root4 = std::sqrt(1.0 + 1.0 / 4.0);
  ok &= bmr::test::Expect(near(student4[0], 1.1889286 * root4, 1e-6) && near(student4[1], 3.1824463 * root4, 1e-6),
                          "Student, 4 resamples: t_3 sqrt(5/4) at 68 and 95 % to 1e-6");
  const auto calibrated4 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 4);
  const auto calibrated8 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 8);
  const auto & table = itk::RescanCalibrations;
  ok &= bmr::test::Expect(itk::UncertaintySettings{}.resamples == 4 && std::size(table) == 1 &&
                            table[0].resamples == 4 && near(calibrated4[0], table[0].halfWidth68, 1e-15) &&
                            near(calibrated4[1], table[0].halfWidth95, 1e-15),
                          "calibrated, 4 resamples (the default): its conformal constants (to rounding)");
  // The conformal quantiles of the default mesh's scores: below Student's at both levels (the 95 % one by more than
  // half: the scores' tail is lighter than the t_3 the four rescans' SD would imply).
  ok &= bmr::test::Expect(calibrated4[0] < 0.7 * student4[0] && calibrated4[1] < 0.5 * student4[1],
                          "calibrated, 4: narrower than Student's by more than 30 % (68 %) and 50 % (95 %)");
  ok &= bmr::test::Expect(near(calibrated8[0] / calibrated4[0], student8[0] / student4[0], 1e-12) &&
                            near(calibrated8[1] / calibrated4[1], student8[1] / student4[1], 1e-12) &&
                            calibrated8[1] < calibrated4[1],
                          "calibrated, 8 resamples: scaled from 4 by Student's ratio, so narrower");
  const auto calibrated6 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 6);
  const auto student6 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 6);
  const auto calibrated16 =
    itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 16);
  const auto calibrated3 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 3);
  const auto student3 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 3);
  ok &= bmr::test::Expect(near(calibrated6[0] / calibrated4[0], student6[0] / student4[0], 1e-12) &&
                            near(calibrated16[1] / calibrated4[1], student16[1] / student4[1], 1e-12) &&
                            near(calibrated3[1] / calibrated4[1], student3[1] / student4[1], 1e-12),
                          "calibrated, 6, 16 and 3 resamples: scaled by Student's ratio from 4");
  const auto bootstrap =
    itk::IntervalHalfWidths(UncertaintyMethodEnum::Bootstrap, IntervalQuantilesEnum::Calibrated, 8);
  ok &= bmr::test::Expect(bootstrap == student8, "the bootstrap was not calibrated: Student's half-widths");
  ok &= bmr::test::Expect(
    itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated) &&
      !itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student) &&
      !itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Bootstrap, IntervalQuantilesEnum::Calibrated),
    "the calibrated half-widths are the rescans' only, and only when asked");
  const auto two = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 2);
  ok &= bmr::test::Expect(std::isinf(two[0]) && std::isinf(two[1]), "2 resamples: no finite half-width");
  ok &= CheckCensoredFit();
  ok &= CheckSliceCalibration();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
