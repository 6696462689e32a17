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
// bmr::DistanceLabelFunction and the meshes it gives (MeshingParameters::labelSurfaces = Distance) on an ellipsoid
// sampled at 1 x 1 x 3 mm on an oblique grid (off its centre, no semi-axis a multiple of a voxel). What is checked:
// - every voxel centre keeps its own label, exactly (the function interpolates between the voxels, never over them);
// - along 2,000 rays through the ellipsoid's surface the function's interface lies closer to the analytic surface
//   than the staircase's (the nearest voxel's label, what a label image says): its RMS below 0.3 mm, about what a
//   staircase of 1 mm voxels errs by (1 / sqrt 12 mm, a uniform error of +-half a voxel), so the 3 mm slices add
//   next to nothing, where the staircase's, with half a slice along z, is above 0.4 mm;
// - the mesh of the label image (LabelImageToTetrahedralMeshFilter) with distance surfaces puts its interface nodes
//   on the ellipsoid with an RMS below 0.3 mm (the interface above; the facets follow it to 0.2 mm), and closer than
//   the voxel surfaces' mesh does;
// - a grid of one voxel along an axis, or labels that do not match it, raise itk::ExceptionObject.
#include "bmrDistanceLabels.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"
#include "itkLabelImageToTetrahedralMeshFilter.h"

#include <cmath>
#include <functional>
#include <iostream>
#include <set>
#include <vector>

namespace {
const double Semi[3] = { 11.3, 8.7, 13.9 };    // mm: none a multiple of a voxel
const double Center[3] = { 1.37, -0.81, 0.4 }; // mm

/** Q(x) = sum ((x - C) / a)^2: below 1 inside the ellipsoid. */
double
Quadric(const std::array<double, 3> & x)
{
  double q = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    q += std::pow((x[c] - Center[c]) / Semi[c], 2);
  }
  return q;
}

/** 64 x 64 x 22 voxels of 1 x 1 x 3 mm, rotated 10 degrees about x, centred on the origin but for a fraction of a
 * voxel. */
bmr::GridGeometry
Grid()
{
  bmr::GridGeometry grid;
  grid.size = { { 64, 64, 22 } };
  grid.spacing = { { 1.0, 1.0, 3.0 } };
  const double angle = 10.0 * 3.14159265358979323846 / 180.0;
  grid.direction = { { 1, 0, 0, 0, std::cos(angle), -std::sin(angle), 0, std::sin(angle), std::cos(angle) } };
  grid.origin = { { 0, 0, 0 } };
  const std::array<double, 3> middle = grid.IndexToPoint({ { 31.73, 31.41, 10.62 } });
  for (int c = 0; c < 3; ++c)
  {
    grid.origin[c] = -middle[c];
  }
  return grid;
}

/** The ellipsoid (2) in tissue (1), sampled at the voxel centres. */
std::vector<std::int32_t>
Sample(const bmr::GridGeometry & grid)
{
  std::vector<std::int32_t> labels(grid.GetNumberOfVoxels());
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    const std::array<double, 3> x = grid.IndexToPoint({ { double(v % grid.size[0]),
                                                          double((v / grid.size[0]) % grid.size[1]),
                                                          double(v / (grid.size[0] * grid.size[1])) } });
    labels[v] = Quadric(x) <= 1.0 ? 2 : 1;
  }
  return labels;
}

/** RMS [mm] of where \a labelAt changes from the ellipsoid (2) to the outside along 2,000 rays from its centre through
 * points spread evenly over its surface (a Fibonacci lattice), against the surface; bisection to 1e-6 of the ray. */
double
InterfaceRms(const std::function<std::int32_t(double, double, double)> & labelAt)
{
  const int    count = 2000;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  double       sum = 0.0;
  for (int i = 0; i < count; ++i)
  {
    const double z = 1.0 - 2.0 * (i + 0.5) / count;
    const double r = std::sqrt(1.0 - z * z);
    const double d[3] = { Semi[0] * r * std::cos(golden * i), Semi[1] * r * std::sin(golden * i), Semi[2] * z };
    const auto   inside = [&](double t) {
      return labelAt(Center[0] + t * d[0], Center[1] + t * d[1], Center[2] + t * d[2]) == 2;
    };
    double lo = 0.6, hi = 1.4;
    while (hi - lo > 1e-6)
    {
      const double mid = 0.5 * (lo + hi);
      (inside(mid) ? lo : hi) = mid;
    }
    const double error = (0.5 * (lo + hi) - 1.0) * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    sum += error * error;
  }
  return std::sqrt(sum / count);
}

/** RMS [mm] of the radial distance to the ellipsoid of the nodes shared by its elements and the tissue's. */
double
MeshInterfaceRms(const bmr::TetrahedralMesh & mesh)
{
  std::vector<int> touches(mesh.GetNumberOfPoints(), 0);
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    for (int k = 0; k < 4; ++k)
    {
      touches[static_cast<std::size_t>(mesh.tetrahedra[4 * e + k])] |= mesh.labels[e] == 2 ? 1 : 2;
    }
  }
  double      sum = 0.0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < touches.size(); ++p)
  {
    if (touches[p] == 3)
    {
      const std::array<double, 3> x = { { mesh.points[3 * p], mesh.points[3 * p + 1], mesh.points[3 * p + 2] } };
      double                      length = 0.0;
      for (int c = 0; c < 3; ++c)
      {
        length += (x[c] - Center[c]) * (x[c] - Center[c]);
      }
      const double error = (1.0 - 1.0 / std::sqrt(Quadric(x))) * std::sqrt(length);
      sum += error * error;
      ++n;
    }
  }
  return n ? std::sqrt(sum / double(n)) : 1e9;
}

bmr::TetrahedralMesh
Mesh(const bmr::GridGeometry & grid, const std::vector<std::int32_t> & labels, bool distance)
{
  using ImageType = itk::Image<std::int32_t, 3>;
  auto                   image = itk::MakeImageOnGrid<ImageType>(grid, labels);
  auto                   mesher = itk::LabelImageToTetrahedralMeshFilter<ImageType>::New();
  bmr::MeshingParameters parameters;
  parameters.cellSize = parameters.facetSize = 3.0;
  parameters.facetDistance = 0.2;
  parameters.labelSurfaces =
    distance ? bmr::MeshingParameters::LabelSurfaces::Distance : bmr::MeshingParameters::LabelSurfaces::Voxels;
  mesher->SetInput(image);
  mesher->SetMeshingParameters(parameters);
  mesher->Update();
  return mesher->GetOutput()->Get();
}
} // namespace

int
bmrDistanceLabelsTest(int, char *[])
{
  bool                            ok = true;
  const bmr::GridGeometry         grid = Grid();
  const std::vector<std::int32_t> labels = Sample(grid);
  const auto                      labelAt = bmr::DistanceLabelFunction(labels, grid);

  std::size_t changed = 0;
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    const std::array<double, 3> x = grid.IndexToPoint({ { double(v % grid.size[0]),
                                                          double((v / grid.size[0]) % grid.size[1]),
                                                          double(v / (grid.size[0] * grid.size[1])) } });
    changed += labelAt(x[0], x[1], x[2]) != labels[v] ? 1 : 0;
  }
  ok &= bmr::test::Expect(changed == 0, "every voxel centre keeps its label (" + std::to_string(changed) + " changed)");

  const auto nearestVoxel = [&grid, &labels](double x, double y, double z) {
    const std::array<double, 3> c = grid.PointToIndex({ { x, y, z } });
    std::size_t                 offset = 0, stride = 1;
    for (int a = 0; a < 3; ++a)
    {
      const double i = std::min(std::max(std::round(c[a]), 0.0), double(grid.size[a] - 1));
      offset += static_cast<std::size_t>(i) * stride;
      stride *= grid.size[a];
    }
    return labels[offset];
  };
  const double distanceRms = InterfaceRms(labelAt), staircaseRms = InterfaceRms(nearestVoxel);
  std::cout << "interface RMS: distance " << distanceRms << " mm, staircase " << staircaseRms << " mm" << std::endl;
  ok &= bmr::test::Expect(distanceRms < 0.3 && staircaseRms > 0.4,
                          "the distance function's interface within 0.3 mm RMS, the staircase's beyond 0.4 mm");

  const double meshDistance = MeshInterfaceRms(Mesh(grid, labels, true));
  const double meshVoxels = MeshInterfaceRms(Mesh(grid, labels, false));
  std::cout << "mesh interface RMS: distance surfaces " << meshDistance << " mm, voxel surfaces " << meshVoxels << " mm"
            << std::endl;
  ok &= bmr::test::Expect(meshDistance < 0.3 && meshDistance < meshVoxels,
                          "the distance surfaces' mesh within 0.3 mm RMS of the ellipsoid, closer than the voxels'");

  bmr::GridGeometry flat = grid;
  flat.size[2] = 1;
  ok &= bmr::test::ExpectException(
    "one voxel along an axis",
    [&]() { bmr::DistanceLabelFunction(std::vector<std::int32_t>(64 * 64, 1), flat); },
    "at least 2 voxels along each axis");
  ok &= bmr::test::ExpectException(
    "labels that do not fill the grid",
    [&]() { bmr::DistanceLabelFunction(std::vector<std::int32_t>(10, 1), grid); },
    "one value per voxel");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
