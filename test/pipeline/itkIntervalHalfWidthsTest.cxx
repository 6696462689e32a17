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
// - Student: k = t_(n-1) sqrt(1 + 1/n) against tabulated t quantiles (scipy.stats.t.ppf: t_7(0.84) = 1.0702874,
//   t_7(0.975) = 2.3646243, t_15(0.84) = 1.0285328, t_15(0.975) = 2.1314495) to 1e-3, the accuracy the
//   Cornish-Fisher expansion claims for 3 or more degrees of freedom;
// - calibrated (the default, rescans): at the calibration's 8 resamples exactly the conformal constants; at other
//   n scaled by Student's ratio, so more resamples narrow the interval as they would a normal sample's;
// - the bootstrap, which the calibration did not measure, keeps Student's; fewer than 3 resamples give no width.
#include "itkBiomechanicalPipelines.h"
#include "itkIntervalTestSupport.h"

#include <cmath>

int
itkIntervalHalfWidthsTest(int, char *[])
{
  itk::test::Checks Check;
  using itk::IntervalQuantilesEnum;
  using itk::UncertaintyMethodEnum;
  const auto near = [](double a, double b, double tolerance) { return std::abs(a - b) <= tolerance; };

  const auto   student8 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 8);
  const auto   student16 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student, 16);
  const double root8 = std::sqrt(1.0 + 1.0 / 8.0), root16 = std::sqrt(1.0 + 1.0 / 16.0);
  Check(near(student8[0], 1.0702874 * root8, 1e-3) && near(student8[1], 2.3646243 * root8, 1e-3),
        "Student, 8 resamples: t_7 sqrt(9/8) at 68 and 95 % to 1e-3");
  Check(near(student16[0], 1.0285328 * root16, 1e-3) && near(student16[1], 2.1314495 * root16, 1e-3),
        "Student, 16 resamples: t_15 sqrt(17/16) at 68 and 95 % to 1e-3");

  const auto calibrated8 = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 8);
  Check(calibrated8[0] == itk::RescanCalibratedHalfWidth68 && calibrated8[1] == itk::RescanCalibratedHalfWidth95,
        "calibrated, 8 resamples: the conformal constants");
  Check(calibrated8[0] < 0.75 * student8[0] && near(calibrated8[1], student8[1], 0.05 * student8[1]),
        "calibrated: the 68 % interval narrower than Student's by more than a quarter, the 95 % one within 5 %");
  const auto calibrated16 =
    itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 16);
  Check(near(calibrated16[0] / calibrated8[0], student16[0] / student8[0], 1e-12) &&
          near(calibrated16[1] / calibrated8[1], student16[1] / student8[1], 1e-12),
        "calibrated, 16 resamples: scaled by Student's ratio between 16 and 8");

  const auto bootstrap =
    itk::IntervalHalfWidths(UncertaintyMethodEnum::Bootstrap, IntervalQuantilesEnum::Calibrated, 8);
  Check(bootstrap == student8, "the bootstrap was not calibrated: Student's half-widths");
  Check(itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated) &&
          !itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Student) &&
          !itk::UsesCalibratedHalfWidths(UncertaintyMethodEnum::Bootstrap, IntervalQuantilesEnum::Calibrated),
        "the calibrated half-widths are the rescans' only, and only when asked");
  const auto two = itk::IntervalHalfWidths(UncertaintyMethodEnum::Rescan, IntervalQuantilesEnum::Calibrated, 2);
  Check(std::isinf(two[0]) && std::isinf(two[1]), "2 resamples: no finite half-width");
  return Check.ExitCode();
}
