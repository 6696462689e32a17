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
// ComputeSceneDistanceMaps on a voxelized ball: the sampled map's zero level lies on the ball's own surface to
// well below the voxel staircase, only the objective labels are computed, and a missing label is refused.
// ComputeProbabilityDistanceMap on the ball's volume fractions: sub-voxel, better than the labels' map, and a
// voxel that is not a probability is refused.
#include "bmrSignedDistanceSampler.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkSceneDistanceMaps.h"
#include "itkTestingMacros.h"

#include <cmath>
#include <iostream>
#include <limits>

namespace {
constexpr double Radius = 9.3;                        // mm, not a multiple of the 1 mm voxels
const double     Center[3] = { 16.37, 15.81, 16.12 }; // mm, off the grid's symmetry

/** RMS and mean of phi over 1,000 points spread evenly (Fibonacci lattice) on the analytic sphere. */
void
SurfaceError(const itk::Image<float, 3> * map, double & rms, double & mean)
{
  const bmr::SignedDistanceSampler sampler(
    itk::GridGeometryOf(map),
    std::vector<float>(map->GetBufferPointer(), map->GetBufferPointer() + map->GetBufferedRegion().GetNumberOfPixels()),
    "ball");
  const int    count = 1000;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  double       sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < count; ++i)
  {
    const double z = 1.0 - 2.0 * (i + 0.5) / count;
    const double r = std::sqrt(1.0 - z * z);
    const double x[3] = { Center[0] + Radius * r * std::cos(golden * i),
                          Center[1] + Radius * r * std::sin(golden * i),
                          Center[2] + Radius * z };
    const double phi = sampler.Evaluate(x, nullptr);
    sum += phi;
    sum2 += phi * phi;
  }
  mean = sum / count;
  rms = std::sqrt(sum2 / count);
}

/** The maps of ComputeSceneDistanceMaps, each computed on its organ's box, against the whole image's: on an
 * anisotropic grid with a ball inside and a slab that touches the image's border, they must agree within the
 * exact margin (to float rounding, 1e-4 mm: the same squared distances, summed from other index offsets) and
 * be an upper bound beyond it. */
bool
CroppedMapsMatch()
{
  using LabelImageType = itk::Image<short, 3>;
  auto labels = LabelImageType::New();
  labels->SetRegions(itk::ImageRegion<3>(itk::Size<3>{ { 120, 90, 100 } }));
  const double spacing[3] = { 0.8, 1.1, 1.3 };
  labels->SetSpacing(spacing);
  labels->Allocate();
  for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(labels, labels->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      d2 += std::pow(it.GetIndex()[c] * spacing[c] - 2.0 * Center[c], 2);
    }
    const bool slab = it.GetIndex()[0] < 12 && it.GetIndex()[1] > 40;
    it.Set(d2 <= Radius * Radius ? 2 : (slab ? 3 : 1));
  }
  bmr::Scene scene;
  scene.labels = { { "tissue", 1, bmr::LabelRoleEnum::Material, 10.0, 0.35 },
                   { "ball", 2, bmr::LabelRoleEnum::Material, 50.0, 0.4 },
                   { "slab", 3, bmr::LabelRoleEnum::Material, 50.0, 0.4 } };
  scene.objective = { { "ball", 1.0 }, { "slab", 1.0 } };
  const double exact = 6.0; // mm: the ball's box, grown by this, is a fraction of the image
  const auto   cropped = itk::ComputeSceneDistanceMaps(labels.GetPointer(), scene, exact);
  const auto whole = itk::ComputeSceneDistanceMaps(labels.GetPointer(), scene, std::numeric_limits<double>::infinity());
  bool       ok = true;
  for (const char * organ : { "ball", "slab" })
  {
    const float *     a = cropped.at(organ)->GetBufferPointer();
    const float *     b = whole.at(organ)->GetBufferPointer();
    const std::size_t n = labels->GetBufferedRegion().GetNumberOfPixels();
    double            nearError = 0.0, belowBound = 0.0;
    std::size_t       near = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      if (std::abs(b[i]) <= exact)
      {
        nearError = std::max(nearError, std::abs(double(a[i]) - b[i]));
        ++near;
      }
      else
      {
        belowBound = std::max(belowBound, double(b[i]) - a[i]);
      }
    }
    std::cout << organ << ": " << near << " voxels within " << exact << " mm, largest difference " << nearError
              << " mm; beyond, the cropped map lies below the exact one by at most " << belowBound << " mm"
              << std::endl;
    ok &= bmr::test::Expect(near > 1000 && nearError <= 1e-4,
                            std::string(organ) + ": the cropped map equals the whole image's within the margin (got " +
                              bmr::test::ToString(nearError) + " mm)");
    ok &= bmr::test::Expect(belowBound <= 1e-4,
                            std::string(organ) + ": beyond the margin the cropped map is an upper bound (got " +
                              bmr::test::ToString(belowBound) + " mm below)");
  }
  return ok;
}
} // namespace

int
itkSceneDistanceMapsTest(int, char *[])
{
  using LabelImageType = itk::Image<short, 3>;
  auto labels = LabelImageType::New();
  labels->SetRegions(itk::ImageRegion<3>(itk::Size<3>{ { 33, 32, 33 } }));
  labels->Allocate();
  // A voxel belongs to the ball when its center does: the label surface is a staircase of voxel faces.
  for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(labels, labels->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      d2 += (it.GetIndex()[c] - Center[c]) * (it.GetIndex()[c] - Center[c]);
    }
    it.Set(d2 <= Radius * Radius ? 2 : 1);
  }
  bmr::Scene scene;
  scene.labels = { { "tissue", 1, bmr::LabelRoleEnum::Material, 10.0, 0.35 },
                   { "ball", 2, bmr::LabelRoleEnum::Material, 50.0, 0.4 } };
  scene.objective = { { "ball", 1.0 } };

  const auto maps = itk::ComputeSceneDistanceMaps(labels.GetPointer(), scene);
  // Nothing the scene does not use: one map, of the one objective label.
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool ok = true;
  ok &= Expect(maps.size() == 1, "one distance map, for the one objective label (got " + ToString(maps.size()) + ")");
  ok &= Expect(maps.count("ball") == 1, "a distance map of the objective label \"ball\"");
  double rms = 0.0, mean = 0.0;
  SurfaceError(maps.at("ball"), rms, mean);
  std::cout << "phi on the analytic sphere: RMS " << rms << " mm, mean " << mean << " mm" << std::endl;
  // The label surface is a staircase of voxel faces. Read off that staircase, points of the smooth sphere
  // would show its quantization, 1/sqrt(12) = 0.29 mm RMS for a uniform offset. The averaged organ and
  // complement maps, sampled as a cubic B-spline, must do much better: below half of it. The mean (the
  // voxelized ball's volume error, about 0.03 mm here) must stay below a tenth of a voxel.
  ok &= Expect(rms < 0.145, "RMS of phi on the analytic sphere below 0.145 mm (got " + ToString(rms) + ")");
  ok &= Expect(std::abs(mean) < 0.1, "|mean| of phi on the analytic sphere below 0.1 mm (got " + ToString(mean) + ")");

  // The ball's volume fraction per voxel (5^3 sub-points): a partial-volume segmentation. Its 0.5 level is a
  // sub-voxel surface, so the map must beat the staircase's: RMS below the label map's and below 0.05 mm
  // (the fraction's own quantization, 1/125 of a voxel in volume, is ~0.01 mm on the surface).
  using FractionImageType = itk::Image<float, 3>;
  auto fraction = FractionImageType::New();
  fraction->SetRegions(labels->GetLargestPossibleRegion());
  fraction->Allocate();
  for (itk::ImageRegionIteratorWithIndex<FractionImageType> it(fraction, fraction->GetBufferedRegion()); !it.IsAtEnd();
       ++it)
  {
    int in = 0;
    for (int s = 0; s < 125; ++s)
    {
      const double offset[3] = { (s % 5 - 2) / 5.0, (s / 5 % 5 - 2) / 5.0, (s / 25 - 2) / 5.0 };
      double       d2 = 0.0;
      for (int c = 0; c < 3; ++c)
      {
        d2 += std::pow(it.GetIndex()[c] + offset[c] - Center[c], 2);
      }
      in += d2 <= Radius * Radius;
    }
    it.Set(in / 125.0f);
  }
  const auto fractionMap = itk::ComputeProbabilityDistanceMap(fraction.GetPointer(), "ball fraction");
  double     fractionRms = 0.0, fractionMean = 0.0;
  SurfaceError(fractionMap, fractionRms, fractionMean);
  itk::Index<3> centerIndex{ { 16, 16, 16 } };
  std::cout << "phi of the volume fraction on the analytic sphere: RMS " << fractionRms << " mm, mean " << fractionMean
            << " mm; at the center " << fractionMap->GetPixel(centerIndex) << " mm" << std::endl;
  ok &= Expect(fractionRms < 0.05 && fractionRms < rms,
               "RMS of the fraction's phi below 0.05 mm and below the label map's (got " + ToString(fractionRms) + ")");
  // Far from the surface it is the mask's map, as the label map's (the two masks are the same ball here).
  ok &= Expect(fractionMap->GetPixel(centerIndex) < -8.0 &&
                 std::abs(fractionMap->GetPixel(centerIndex) - maps.at("ball")->GetPixel(centerIndex)) < 0.5,
               "the fraction's phi at the center is the label map's, negative (got " +
                 ToString(fractionMap->GetPixel(centerIndex)) + ")");
  fraction->SetPixel(centerIndex, 1.5f);
  ITK_TRY_EXPECT_EXCEPTION(itk::ComputeProbabilityDistanceMap(fraction.GetPointer(), "ball fraction"));

  bmr::Scene missing = scene;
  missing.labels.push_back({ "absent", 7, bmr::LabelRoleEnum::Material, 10.0, 0.35 });
  missing.objective = { { "absent", 1.0 } };
  ITK_TRY_EXPECT_EXCEPTION(itk::ComputeSceneDistanceMaps(labels.GetPointer(), missing));

  ok &= CroppedMapsMatch();
  std::cout << (ok ? "PASSED" : "FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
