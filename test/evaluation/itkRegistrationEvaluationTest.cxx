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
// The evaluation side of the Demons comparison:
// - target registration error of a known translation field is exact (1e-12 mm: linear interpolation of a
//   constant field is exact), and refuses landmarks outside the field or without a partner;
// - implanted seeds are found in the pelvis phantom's CT (1.25 x 1.25 x 2.5 mm voxels, 10 HU noise) within
//   0.5 mm of their true centers, in two seedings with 3 and 5 seeds, and paired with their partners after a
//   translation;
// - Dice, surface distances (mean, HD95, maximum) and the Jacobian determinant statistics on cases with known answers.
#include "bmrPhantom.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkImplantedSeedDetection.h"
#include "itkLandmarkRegistrationError.h"
#include "itkRegistrationQualityMeasures.h"
#include "itkTestingMacros.h"

namespace {
using FieldType = itk::Image<itk::Vector<double, 3>, 3>;
using CTImageType = itk::Image<float, 3>;
using LabelImageType = itk::Image<std::int32_t, 3>;

FieldType::Pointer
ConstantField(const itk::Size<3> & size, double spacing, const itk::Vector<double, 3> & value)
{
  auto field = FieldType::New();
  field->SetRegions(itk::ImageRegion<3>(size));
  field->SetSpacing(spacing);
  FieldType::PointType origin;
  origin.Fill(-0.5 * spacing * (size[0] - 1));
  field->SetOrigin(origin);
  field->Allocate();
  field->FillBuffer(value);
  return field;
}
} // namespace

int
itkRegistrationEvaluationTest(int, char *[])
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool ok = true;

  // --- TRE of a translation: fixed point x maps to x + t; the moving landmark is x + t + e, so TRE = |e|.
  {
    itk::Vector<double, 3> t;
    t[0] = 1.5;
    t[1] = -2.0;
    t[2] = 0.75;
    const auto                       field = ConstantField({ { 21, 21, 21 } }, 1.0, t);
    const std::vector<bmr::Landmark> fixed = { { "a", { { 0, 0, 0 } } }, { "b", { { 3.3, -7.1, 9.9 } } } };
    const double                     e[2][3] = { { 0, 0, 0 }, { 0.3, -0.4, 1.2 } };
    std::vector<bmr::Landmark>       moving;
    for (int i = 1; i >= 0; --i) // reversed order: pairing is by id
    {
      moving.push_back({ fixed[i].id,
                         { { fixed[i].point[0] + t[0] + e[i][0],
                             fixed[i].point[1] + t[1] + e[i][1],
                             fixed[i].point[2] + t[2] + e[i][2] } } });
    }
    const auto tre = itk::ComputeTargetRegistrationErrors(field.GetPointer(), fixed, moving);
    if (Expect(tre.size() == 2, "TRE of two landmark pairs (got " + ToString(tre.size()) + " values)"))
    {
      std::cout << "TRE of the translation: " << tre[0] << ", " << tre[1] << " mm (exact: 0, 1.3)" << std::endl;
      ok &= Expect(std::abs(tre[0]) <= 1e-12, "TRE of the exact pair is 0 to 1e-12 mm (got " + ToString(tre[0]) + ")");
      ok &= Expect(std::abs(tre[1] - 1.3) <= 1e-12,
                   "TRE of the offset pair is 1.3 to 1e-12 mm (got " + ToString(tre[1]) + ")");
    }
    else
    {
      ok = false;
    }
    const std::vector<bmr::Landmark> outside = { { "a", { { 10.5, 0, 0 } } } };
    ITK_TRY_EXPECT_EXCEPTION(itk::ComputeTargetRegistrationErrors(field.GetPointer(), outside, moving));
    const std::vector<bmr::Landmark> unpaired = { { "c", { { 0, 0, 0 } } } };
    ITK_TRY_EXPECT_EXCEPTION(itk::ComputeTargetRegistrationErrors(field.GetPointer(), unpaired, moving));
  }

  // --- Seed detection on the pelvis phantom.
  for (unsigned int numberOfSeeds : { 3u, 5u })
  {
    bmr::PelvisPhantomParameters p;
    p.numberOfSeeds = numberOfSeeds;
    p.seedPlacementSeed = 10 + numberOfSeeds;
    p.noiseSigmaHU = 10.0;
    const bmr::PhantomVolume volume = bmr::MakePelvisPhantom(p);
    const auto               ct = itk::MakeImageOnGrid<CTImageType>(volume.grid, volume.ct);
    const auto               labels = itk::MakeImageOnGrid<LabelImageType>(volume.grid, volume.labels);
    const auto found = itk::DetectImplantedSeeds(ct.GetPointer(), labels.GetPointer(), bmr::PelvisProstate);
    if (found.size() != volume.seeds.size())
    {
      std::cerr << "found " << found.size() << " seeds, expected " << volume.seeds.size() << std::endl;
      for (const auto & l : found)
      {
        std::cerr << "  found " << l.point[0] << " " << l.point[1] << " " << l.point[2] << std::endl;
      }
      for (const auto & l : volume.seeds)
      {
        std::cerr << "  truth " << l.center[0] << " " << l.center[1] << " " << l.center[2] << " axis " << l.axis[0]
                  << " " << l.axis[1] << " " << l.axis[2] << std::endl;
      }
      ok = false;
      continue;
    }
    std::vector<bmr::Landmark> truth;
    for (const auto & s : volume.seeds)
    {
      truth.push_back({ "truth", s.center });
    }
    // Pairing after a translation of 4 mm (organ motion between two scans).
    std::vector<bmr::Landmark> moved = truth;
    for (auto & l : moved)
    {
      l.point[0] += 4.0;
    }
    const auto match = bmr::MatchLandmarks(found, moved);
    double     worst = 0.0;
    for (std::size_t i = 0; i < found.size(); ++i)
    {
      const auto & x = found[i].point;
      const auto & y = truth[match[i]].point;
      worst = std::max(worst, std::hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2]));
    }
    std::cout << numberOfSeeds << " seeds: largest centroid error " << worst << " mm (limit 0.5 mm)" << std::endl;
    ok &=
      Expect(worst <= 0.5,
             ToString(numberOfSeeds) + " seeds found within 0.5 mm of their centers (got " + ToString(worst) + " mm)");
    // The organ must exist.
    ITK_TRY_EXPECT_EXCEPTION(itk::DetectImplantedSeeds(ct.GetPointer(), labels.GetPointer(), 42));
  }

  // --- Dice and HD95: identical balls give 1 and 0; concentric balls of radius 8 and 11 voxels give a
  // surface distance of 3 voxels everywhere, within +-1 voxel of voxelization.
  {
    const auto ball = [](double radius) {
      auto image = LabelImageType::New();
      image->SetRegions(itk::ImageRegion<3>(itk::Size<3>{ { 32, 32, 32 } }));
      image->Allocate();
      for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(image, image->GetLargestPossibleRegion());
           !it.IsAtEnd();
           ++it)
      {
        const auto i = it.GetIndex();
        it.Set(std::hypot(i[0] - 15.5, i[1] - 15.5, i[2] - 15.5) <= radius ? 2 : 0);
      }
      return image;
    };
    const auto   small = ball(8.0), large = ball(11.0);
    const auto   self = itk::ComputeLabelOverlap<LabelImageType>(small, small, 2);
    const double hdSelf = itk::ComputeSurfaceDistances<LabelImageType>(small, small, 2).maximum;
    const auto   distances = itk::ComputeSurfaceDistances<LabelImageType>(small, large, 2);
    const double hd = distances.percentile95;
    const auto   overlap = itk::ComputeLabelOverlap<LabelImageType>(small, large, 2);
    const double expectedDice = 2.0 * 512.0 / (512.0 + 1331.0); // (4/3 pi r^3 cancels): 2 r1^3 / (r1^3 + r2^3)
    std::cout << "Dice " << self.dice << " / " << overlap.dice << " (about " << expectedDice << "), HD95 " << hdSelf
              << " / " << hd << " mm (about 3)" << std::endl;
    std::cout << "mean surface distance " << distances.mean << " mm, maximum " << distances.maximum << " mm"
              << std::endl;
    ok &= Expect(self.dice == 1.0, "Dice of a ball with itself is exactly 1 (got " + ToString(self.dice) + ")");
    ok &= Expect(hdSelf == 0.0, "surface distance of a ball to itself is exactly 0 (got " + ToString(hdSelf) + ")");
    ok &= Expect(std::abs(hd - 3.0) <= 1.0, "HD95 of balls of radius 8 and 11 is 3 +- 1 (got " + ToString(hd) + ")");
    ok &= Expect(std::abs(distances.mean - 3.0) <= 1.0,
                 "mean surface distance of balls of radius 8 and 11 is 3 +- 1 (got " + ToString(distances.mean) + ")");
    ok &= Expect(distances.maximum >= hd,
                 "maximum surface distance >= HD95 (got " + ToString(distances.maximum) + " < " + ToString(hd) + ")");
    ok &= Expect(distances.mean <= hd,
                 "mean surface distance <= HD95 (got " + ToString(distances.mean) + " > " + ToString(hd) + ")");
    ok &= Expect(std::abs(overlap.dice - expectedDice) < 0.03,
                 "Dice of balls of radius 8 and 11 within 0.03 of " + ToString(expectedDice) + " (got " +
                   ToString(overlap.dice) + ")");
    ITK_TRY_EXPECT_EXCEPTION(itk::ComputeSurfaceDistances<LabelImageType>(small, large, 7));
  }

  // --- Jacobian determinant of x -> x + (a x, 0, 0) is 1 + a everywhere.
  for (double a : { 0.2, -1.5 })
  {
    auto field = ConstantField({ { 10, 10, 10 } }, 2.0, itk::Vector<double, 3>(0.0));
    for (itk::ImageRegionIteratorWithIndex<FieldType> it(field, field->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
    {
      FieldType::PointType x;
      field->TransformIndexToPhysicalPoint(it.GetIndex(), x);
      FieldType::PixelType d(0.0);
      d[0] = a * x[0];
      it.Set(d);
    }
    const auto s = itk::ComputeJacobianDeterminantStatistics(field.GetPointer());
    std::cout << "J for a = " << a << ": minimum " << s.minimum << ", fraction <= 0 " << s.fractionNonPositive
              << ", sd log J " << s.standardDeviationOfLog << std::endl;
    // Central (and one-sided) differences are exact for a linear field; float output: 1e-6.
    ok &= Expect(std::abs(s.minimum - (1.0 + a)) <= 1e-6,
                 "minimum J for a = " + ToString(a) + " is 1 + a to 1e-6 (got " + ToString(s.minimum) + ")");
    ok &= Expect(s.fractionNonPositive == (1.0 + a <= 0.0 ? 1.0 : 0.0),
                 "fraction of J <= 0 for a = " + ToString(a) + " is exactly " + (1.0 + a <= 0.0 ? "1" : "0") +
                   " (got " + ToString(s.fractionNonPositive) + ")");
    ok &=
      Expect(s.standardDeviationOfLog <= 1e-6,
             "SD of log J for a = " + ToString(a) + " at most 1e-6 (got " + ToString(s.standardDeviationOfLog) + ")");
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
