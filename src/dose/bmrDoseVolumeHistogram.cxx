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
#include "bmrDoseVolumeHistogram.h"

#include "bmrError.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <sstream>

namespace bmr {

namespace {

/** Throws naming \a where when \a dosesGy is empty or holds a negative or non-finite dose. */
void
CheckDoses(const std::vector<double> & dosesGy, const char * where)
{
  if (dosesGy.empty())
  {
    Fail(where, "the structure has no voxels");
  }
  for (std::size_t i = 0; i < dosesGy.size(); ++i)
  {
    if (!std::isfinite(dosesGy[i]) || dosesGy[i] < 0.0)
    {
      std::ostringstream os;
      os << "voxel " << i << " has the dose " << dosesGy[i] << " Gy (a dose must be finite and >= 0)";
      Fail(where, os.str());
    }
  }
}

std::string
Lowercase(std::string text)
{
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

} // namespace

DoseVolumeHistogram
ComputeDoseVolumeHistogram(const std::vector<double> & dosesGy,
                           double                      voxelVolumeMM3,
                           double                      binWidthGy,
                           double                      maximumDoseGy)
{
  const char * where = "bmr::ComputeDoseVolumeHistogram";
  CheckDoses(dosesGy, where);
  if (!(binWidthGy > 0.0) || !std::isfinite(binWidthGy) || !(voxelVolumeMM3 > 0.0) || !std::isfinite(voxelVolumeMM3))
  {
    Fail(where, "the bin width [Gy] and the voxel volume [mm^3] must be positive and finite");
  }
  const double axisEnd = std::max(*std::max_element(dosesGy.begin(), dosesGy.end()), maximumDoseGy);
  // One bin beyond the largest dose, so that the cumulative DVH ends at 0 (and a dose on the last edge fits).
  const auto bins = static_cast<std::size_t>(std::floor(axisEnd / binWidthGy)) + 2;
  if (bins > 10000000)
  {
    Fail(where, "more than 10^7 bins: the bin width is too small for the largest dose");
  }
  DoseVolumeHistogram dvh;
  dvh.binWidth = binWidthGy;
  dvh.numberOfVoxels = dosesGy.size();
  dvh.volumeCC = static_cast<double>(dosesGy.size()) * voxelVolumeMM3 / 1000.0;
  std::vector<std::size_t> counts(bins, 0);
  for (const double d : dosesGy)
  {
    auto k = static_cast<std::size_t>(std::floor(d / binWidthGy));
    // Rounding of d / w may put a dose equal to an edge k w into bin k - 1: compare with the edges themselves.
    while (k + 1 < bins && d >= dvh.BinDose(k + 1))
    {
      ++k;
    }
    while (k > 0 && d < dvh.BinDose(k))
    {
      --k;
    }
    ++counts[std::min(k, bins - 1)];
  }
  const double n = static_cast<double>(dosesGy.size());
  dvh.differential.resize(bins);
  dvh.cumulative.resize(bins);
  std::size_t atLeast = 0; // voxels in bins >= k, accumulated from the top: exact integer counts
  for (std::size_t k = bins; k-- > 0;)
  {
    atLeast += counts[k];
    dvh.differential[k] = static_cast<double>(counts[k]) / n;
    dvh.cumulative[k] = static_cast<double>(atLeast) / n;
  }
  return dvh;
}

double
DoseAtVolume(std::vector<double> dosesGy, double percent)
{
  const char * where = "bmr::DoseAtVolume";
  CheckDoses(dosesGy, where);
  if (!(percent >= 0.0 && percent <= 100.0))
  {
    Fail(where, "the volume must lie in [0, 100] %");
  }
  std::sort(dosesGy.begin(), dosesGy.end(), std::greater<double>());
  const double n = static_cast<double>(dosesGy.size());
  // p_i = (i - 1/2) / N for the i-th largest dose (1-based): position = p N + 1/2, 0-based index = p N - 1/2.
  const double position = percent / 100.0 * n - 0.5;
  if (position <= 0.0)
  {
    return dosesGy.front();
  }
  if (position >= n - 1.0)
  {
    return dosesGy.back();
  }
  const auto   below = static_cast<std::size_t>(std::floor(position));
  const double t = position - static_cast<double>(below);
  return (1.0 - t) * dosesGy[below] + t * dosesGy[below + 1];
}

std::vector<VolumeAtDose>
VolumeAtDoses(const std::vector<double> & dosesGy, const std::vector<double> & thresholdsGy)
{
  CheckDoses(dosesGy, "bmr::VolumeAtDoses");
  std::vector<VolumeAtDose> volumes;
  for (const double threshold : thresholdsGy)
  {
    const auto atLeast =
      std::count_if(dosesGy.begin(), dosesGy.end(), [threshold](double d) { return d >= threshold; });
    volumes.push_back({ threshold, static_cast<double>(atLeast) / static_cast<double>(dosesGy.size()) });
  }
  return volumes;
}

double
GeneralizedEquivalentUniformDose(const std::vector<double> & dosesGy, double a)
{
  const char * where = "bmr::GeneralizedEquivalentUniformDose";
  CheckDoses(dosesGy, where);
  if (!std::isfinite(a))
  {
    Fail(where, "the parameter a must be finite");
  }
  const auto   range = std::minmax_element(dosesGy.begin(), dosesGy.end());
  const double minimum = *range.first;
  const double maximum = *range.second;
  const double n = static_cast<double>(dosesGy.size());
  if (a <= 0.0 && minimum == 0.0)
  {
    return 0.0; // sum of D_i^a is infinite (a < 0), or ln 0 = -inf in the geometric mean (a = 0)
  }
  if (maximum == 0.0)
  {
    return 0.0; // a > 0 and no dose at all
  }
  if (a == 0.0)
  {
    double logSum = 0.0;
    for (const double d : dosesGy)
    {
      logSum += std::log(d / maximum);
    }
    return maximum * std::exp(logSum / n);
  }
  // Relative to the dose that dominates the sum: every term (D_i / D_ref)^a lies in [0, 1].
  const double reference = a > 0.0 ? maximum : minimum;
  double       sum = 0.0;
  for (const double d : dosesGy)
  {
    sum += std::pow(d / reference, a);
  }
  return reference * std::pow(sum / n, 1.0 / a);
}

double
DefaultEudParameter(const std::string & structureName)
{
  const std::string name = Lowercase(structureName);
  const auto        has = [&name](const char * part) { return name.find(part) != std::string::npos; };
  if (has("prostate") || has("ptv") || has("ctv") || has("gtv") || has("target"))
  {
    return -10.0;
  }
  if (has("rect"))
  {
    return 8.0;
  }
  if (has("bladder"))
  {
    return 2.0;
  }
  return 1.0;
}

DoseMetrics
ComputeDoseMetrics(const std::vector<double> & dosesGy,
                   double                      voxelVolumeMM3,
                   double                      eudA,
                   const std::vector<double> & thresholdsGy)
{
  const char * where = "bmr::ComputeDoseMetrics";
  CheckDoses(dosesGy, where);
  if (!(voxelVolumeMM3 > 0.0) || !std::isfinite(voxelVolumeMM3))
  {
    Fail(where, "the voxel volume [mm^3] must be positive and finite");
  }
  DoseMetrics m;
  m.numberOfVoxels = dosesGy.size();
  m.volumeCC = static_cast<double>(dosesGy.size()) * voxelVolumeMM3 / 1000.0;
  double sum = 0.0;
  for (const double d : dosesGy)
  {
    sum += d;
  }
  m.mean = sum / static_cast<double>(dosesGy.size());
  const auto range = std::minmax_element(dosesGy.begin(), dosesGy.end());
  m.minimum = *range.first;
  m.maximum = *range.second;
  std::vector<double> sorted = dosesGy;
  std::sort(sorted.begin(), sorted.end(), std::greater<double>());
  m.D95 = DoseAtVolume(sorted, 95.0);
  m.D98 = DoseAtVolume(sorted, 98.0);
  m.D2 = DoseAtVolume(sorted, 2.0);
  m.eudA = eudA;
  m.gEUD = GeneralizedEquivalentUniformDose(dosesGy, eudA);
  m.volumesAtDose = VolumeAtDoses(dosesGy, thresholdsGy);
  return m;
}

} // namespace bmr
