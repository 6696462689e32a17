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
// itk::PlanarContourAreaFractions, what an RTSTRUCT's polygons carry beyond their voxels. What is checked:
// - a hexagon (no edge parallel to a row) on one slice of an anisotropic grid: every voxel's fraction against the
//   polygon's area clipped to the voxel's square (Sutherland-Hodgman, an independent computation). The covered
//   length along a row is exact; the midpoint rule over h = 1/16 sub-rows errs only where that length's slope in y
//   changes, by at most |jump| h^2 / 8 per kink (a kink at c in a cell [0, h] leaves min(c, h - c)^2 / 2 times the
//   jump). Per voxel at most 4 kinks (2 edges crossing its two column sides), each jump at most 2 max|cot|: the
//   tolerance max|cot| h^2; over the slice the kinks are the vertices: the fractions' sum within
//   sum |cot a - cot b| h^2 / 8 of the shoelace area. Other slices are 0;
// - the same hexagon on a grid turned 30 degrees about z, its points turned with it: the same fractions (1e-5);
// - a ring (an outer square and a hole): the hole's voxels 0, the sum the difference of the areas (even-odd);
// - a disc outlined on every slice of a 1 x 1 x 3 mm grid (a cylinder): the distance map of the fractions' 0.5 level
//   (ComputeProbabilityDistanceMap) at the voxel centres within 0.5 mm of the cylinder has an RMS error below
//   0.1 mm (a tenth of a voxel: the fractions' profile across a curved boundary is not linear, so the 0.5 level of
//   their linear interpolation sits off it by a few hundredths) against the exact |r| - R, where the voxels' own
//   map (the even-odd labels, ComputeSceneDistanceMaps' construction) errs by 1/sqrt(12) voxel, about 0.29 mm (above
//   0.2 asserted): the sub-voxel information the polygons carry reaches the surface;
// - bad contours raise itk::ExceptionObject naming what was given: 2 points, a NaN, a contour across two slices,
//   one off the grid.
#include "itkPlanarContourFractions.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"
#include "itkSceneDistanceMaps.h"

#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace {
using Vertex = std::array<double, 2>;
using ImageType = itk::Image<float, 3>;

bmr::GridGeometry
Grid(double turnDegrees)
{
  bmr::GridGeometry g;
  g.size = { { 24, 20, 5 } };
  g.spacing = { { 0.9, 1.1, 3.0 } };
  g.origin = { { -10.3, -9.7, 4.0 } };
  const double t = turnDegrees * std::acos(-1.0) / 180.0;
  g.direction = { { std::cos(t), -std::sin(t), 0, std::sin(t), std::cos(t), 0, 0, 0, 1 } };
  return g;
}

/** \a polygon (continuous indices of slice \a k) as a contour in the physical space of \a grid. */
itk::PlanarContour
ContourOf(const std::vector<Vertex> & polygon, const ImageType * grid, double k)
{
  itk::PlanarContour c;
  for (const Vertex & v : polygon)
  {
    itk::ContinuousIndex<double, 3> index;
    index[0] = v[0];
    index[1] = v[1];
    index[2] = k;
    c.points.emplace_back();
    grid->TransformContinuousIndexToPhysicalPoint(index, c.points.back());
  }
  return c;
}

double
ShoelaceArea(const std::vector<Vertex> & p)
{
  double twice = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const Vertex & a = p[i];
    const Vertex & b = p[(i + 1) % p.size()];
    twice += a[0] * b[1] - a[1] * b[0];
  }
  return 0.5 * std::abs(twice);
}

/** \a p clipped to the half-plane sign * (v[axis] - bound) <= 0 (one Sutherland-Hodgman pass). */
std::vector<Vertex>
Clip(const std::vector<Vertex> & p, int axis, double bound, double sign)
{
  std::vector<Vertex> out;
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    const Vertex & a = p[i];
    const Vertex & b = p[(i + 1) % p.size()];
    const double   da = sign * (a[axis] - bound), db = sign * (b[axis] - bound);
    if (da <= 0)
    {
      out.push_back(a);
    }
    if ((da < 0) != (db < 0) && da != db)
    {
      const double t = da / (da - db);
      out.push_back({ { a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]) } });
    }
  }
  return out;
}

double
AreaInVoxel(std::vector<Vertex> p, long i, long j)
{
  p = Clip(p, 0, i - 0.5, -1.0);
  p = Clip(p, 0, i + 0.5, 1.0);
  p = Clip(p, 1, j - 0.5, -1.0);
  p = Clip(p, 1, j + 0.5, 1.0);
  return p.size() < 3 ? 0.0 : ShoelaceArea(p);
}

std::vector<Vertex>
Hexagon()
{
  std::vector<Vertex> h;
  for (int k = 0; k < 6; ++k)
  {
    const double t = 0.35 + k * std::acos(-1.0) / 3.0; // no edge parallel to x: |cot| <= 2.8
    h.push_back({ { 11.37 + 7.3 * std::cos(t), 9.21 + 6.1 * std::sin(t) } });
  }
  return h;
}

bool
CheckHexagon()
{
  bool                      ok = true;
  const auto                grid = itk::MakeImageOnGrid<ImageType>(Grid(0.0), {});
  const std::vector<Vertex> hexagon = Hexagon();
  const auto                f = itk::PlanarContourAreaFractions({ ContourOf(hexagon, grid, 2.0) }, grid, "hexagon");
  double                    worst = 0.0, sum = 0.0, elsewhere = 0.0;
  for (long k = 0; k < 5; ++k)
  {
    for (long j = 0; j < 20; ++j)
    {
      for (long i = 0; i < 24; ++i)
      {
        const double value = f->GetPixel({ { i, j, k } });
        if (k == 2)
        {
          worst = std::max(worst, std::abs(value - AreaInVoxel(hexagon, i, j)));
          sum += value;
        }
        else
        {
          elsewhere = std::max(elsewhere, std::abs(value));
        }
      }
    }
  }
  // The midpoint rule's bounds (above) from the hexagon's edges: cot = dx/dy of each edge.
  double maxCot = 0.0, kinks = 0.0;
  for (std::size_t v = 0; v < hexagon.size(); ++v)
  {
    const auto cot = [&](std::size_t a) {
      const Vertex & p = hexagon[a % hexagon.size()];
      const Vertex & q = hexagon[(a + 1) % hexagon.size()];
      return (q[0] - p[0]) / (q[1] - p[1]);
    };
    maxCot = std::max(maxCot, std::abs(cot(v)));
    kinks += std::abs(cot(v + hexagon.size() - 1) - cot(v));
  }
  const double h = 1.0 / itk::SubRowsPerVoxel;
  ok &=
    bmr::test::Expect(worst <= maxCot * h * h,
                      "hexagon: every voxel's fraction within max|cot| h^2 = " + bmr::test::ToString(maxCot * h * h) +
                        " of its clipped area, worst " + bmr::test::ToString(worst));
  ok &= bmr::test::Expect(
    std::abs(sum - ShoelaceArea(hexagon)) <= kinks * h * h / 8,
    "hexagon: fractions sum to its area within sum |jump| h^2 / 8 = " + bmr::test::ToString(kinks * h * h / 8) + ": " +
      bmr::test::ToString(sum) + " vs " + bmr::test::ToString(ShoelaceArea(hexagon)));
  ok &= bmr::test::Expect(elsewhere == 0.0, "hexagon: the other slices are 0");

  const auto turned = itk::MakeImageOnGrid<ImageType>(Grid(30.0), {});
  const auto g = itk::PlanarContourAreaFractions({ ContourOf(hexagon, turned, 2.0) }, turned, "turned hexagon");
  double     difference = 0.0;
  for (std::size_t v = 0; v < 24 * 20 * 5; ++v)
  {
    difference = std::max(difference, double(std::abs(f->GetBufferPointer()[v] - g->GetBufferPointer()[v])));
  }
  ok &= bmr::test::Expect(difference <= 1e-5,
                          "a grid turned 30 degrees with its contour: the same fractions, max "
                          "difference " +
                            bmr::test::ToString(difference));
  return ok;
}

bool
CheckRing()
{
  const auto                grid = itk::MakeImageOnGrid<ImageType>(Grid(0.0), {});
  const std::vector<Vertex> outer{ { { 3.3, 2.6 } }, { { 19.7, 2.6 } }, { { 19.7, 16.2 } }, { { 3.3, 16.2 } } };
  const std::vector<Vertex> hole{ { { 8.2, 6.4 } }, { { 8.2, 11.8 } }, { { 14.1, 11.8 } }, { { 14.1, 6.4 } } };
  const auto                f =
    itk::PlanarContourAreaFractions({ ContourOf(outer, grid, 1.0), ContourOf(hole, grid, 1.0) }, grid, "ring");
  double sum = 0.0;
  for (long j = 0; j < 20; ++j)
  {
    for (long i = 0; i < 24; ++i)
    {
      sum += f->GetPixel({ { i, j, 1 } });
    }
  }
  const double expected = ShoelaceArea(outer) - ShoelaceArea(hole);
  bool         ok = bmr::test::Expect(f->GetPixel({ { 11, 9, 1 } }) == 0.0f && f->GetPixel({ { 5, 9, 1 } }) == 1.0f,
                              "ring: the hole's voxels 0, the ring's 1");
  // Horizontal edges at y = 2.6, 6.4, 11.8, 16.2: the midpoint rule over 16 sub-rows places each within 1/32.
  ok &= bmr::test::Expect(std::abs(sum - expected) <= 4 * (19.7 - 3.3) / 32.0,
                          "ring: the sum is the outer area less the hole's, " + bmr::test::ToString(sum) + " vs " +
                            bmr::test::ToString(expected));
  return ok;
}

/** A cylinder of radius R about the z axis through (cx, cy): outlined on every slice of 1 x 1 x 3 mm, its fractions'
 * distance map against the voxels'. */
bool
CheckCylinderDistance()
{
  bmr::GridGeometry g;
  g.size = { { 40, 40, 8 } };
  g.spacing = { { 1.0, 1.0, 3.0 } };
  g.origin = { { 0, 0, 0 } };
  const auto          grid = itk::MakeImageOnGrid<ImageType>(g, {});
  const double        R = 11.37, cx = 19.61, cy = 20.27;
  std::vector<Vertex> disc;
  for (int k = 0; k < 720; ++k)
  {
    const double t = k * std::acos(-1.0) / 360.0;
    disc.push_back({ { cx + R * std::cos(t), cy + R * std::sin(t) } });
  }
  std::vector<itk::PlanarContour> contours;
  for (int k = 0; k < 8; ++k)
  {
    contours.push_back(ContourOf(disc, grid, k));
  }
  const auto fractions = itk::PlanarContourAreaFractions(contours, grid, "cylinder");
  const auto outlines = itk::ComputeProbabilityDistanceMap(fractions.GetPointer(), "cylinder outlines");
  auto       labels = itk::MakeImageOnGrid<itk::Image<std::int32_t, 3>>(g, {});
  labels->FillBuffer(0);
  for (std::size_t v = 0; v < 40 * 40 * 8; ++v)
  {
    labels->GetBufferPointer()[v] = std::hypot(double(v % 40) - cx, double(v / 40 % 40) - cy) < R ? 1 : 0;
  }
  const auto voxels = itk::detail::MaskAndComplementMap(labels.GetPointer(), 1, 1);
  double     outlineSquares = 0.0, voxelSquares = 0.0;
  int        n = 0;
  for (std::size_t v = 40 * 40 * 2; v < 40 * 40 * 6; ++v) // away from the cylinder's cut ends
  {
    const double exact = std::hypot(double(v % 40) - cx, double(v / 40 % 40) - cy) - R;
    if (std::abs(exact) <= 0.5)
    {
      outlineSquares += std::pow(outlines->GetBufferPointer()[v] - exact, 2);
      voxelSquares += std::pow(voxels->GetBufferPointer()[v] - exact, 2);
      ++n;
    }
  }
  const double outlineRMS = std::sqrt(outlineSquares / n), voxelRMS = std::sqrt(voxelSquares / n);
  std::cout << "cylinder: RMS distance error near the surface, outlines " << outlineRMS << " mm, voxels " << voxelRMS
            << " mm (" << n << " voxel centres)" << std::endl;
  return bmr::test::Expect(n > 100 && outlineRMS < 0.1 && voxelRMS > 0.2,
                           "the outlines' map within 0.1 mm RMS near the surface, the voxels' above 0.2 mm: " +
                             bmr::test::ToString(outlineRMS) + " and " + bmr::test::ToString(voxelRMS));
}

bool
CheckRefusals()
{
  const auto grid = itk::MakeImageOnGrid<ImageType>(Grid(0.0), {});
  const auto fractions = [&](std::vector<Vertex> polygon, double k, double zJitter) {
    itk::PlanarContour c = ContourOf(polygon, grid, k);
    c.points.back()[2] += zJitter;
    itk::PlanarContourAreaFractions({ c }, grid, "the test's contours");
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bool         ok = true;
  ok &= bmr::test::ExpectException(
    "2 points",
    [&] {
      fractions({ { { 1, 1 } }, { { 5, 5 } } }, 1.0, 0.0);
    },
    "the test's contours, contour 1");
  ok &= bmr::test::ExpectException(
    "NaN",
    [&] {
      fractions({ { { 1, 1 } }, { { 5, nan } }, { { 5, 1 } } }, 1.0, 0.0);
    },
    "not a finite number");
  ok &= bmr::test::ExpectException(
    "two slices", [&] { fractions(Hexagon(), 1.0, 4.0); }, "does not lie in one slice");
  ok &= bmr::test::ExpectException(
    "off the grid",
    [&] {
      fractions({ { { 1, 1 } }, { { 30, 1 } }, { { 5, 5 } } }, 1.0, 0.0);
    },
    "outside the reference grid");
  ok &= bmr::test::ExpectException(
    "no slice", [&] { fractions(Hexagon(), 7.0, 0.0); }, "lies on no slice");
  return ok;
}
} // namespace

int
itkPlanarContourFractionsTest(int, char *[])
{
  bool ok = CheckHexagon();
  ok &= CheckRing();
  ok &= CheckCylinderDistance();
  ok &= CheckRefusals();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
