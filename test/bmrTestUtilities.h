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
#ifndef bmrTestUtilities_h
#define bmrTestUtilities_h

#include "bmrMesher.h"
#include "bmrScene.h"
#include "bmrSignedDistanceSampler.h"
#include "bmrTetrahedralMesh.h"
#include "itkImage.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkMacro.h"

#include <array>

#include <cmath>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

namespace bmr {
namespace test {

/** Cube [0, n*h]^3 split into n^3 voxels of 6 Kuhn tetrahedra each (a conforming
 * mesh without CGAL); label 1 for x < n*h/2, \a rightLabel otherwise. */
inline TetrahedralMesh
StructuredCube(int n, double h, std::int32_t rightLabel = 1)
{
  TetrahedralMesh mesh;
  auto            id = [n](int i, int j, int k) { return static_cast<std::int32_t>(i + (n + 1) * (j + (n + 1) * k)); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
      {
        mesh.points.insert(mesh.points.end(), { i * h, j * h, k * h });
      }
  // The six tetrahedra of a cube along its main diagonal 0-7 (corner c = i + 2j + 4k).
  const int paths[6][2] = { { 1, 3 }, { 1, 5 }, { 2, 3 }, { 2, 6 }, { 4, 5 }, { 4, 6 } };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
      {
        std::int32_t corner[8];
        for (int c = 0; c < 8; ++c)
        {
          corner[c] = id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        }
        for (const auto & p : paths)
        {
          std::int32_t t[4] = { corner[0], corner[p[0]], corner[p[1]], corner[7] };
          mesh.tetrahedra.insert(mesh.tetrahedra.end(), t, t + 4);
          mesh.labels.push_back(2 * i < n ? 1 : rightLabel);
          if (TetrahedronVolume(mesh, mesh.labels.size() - 1) < 0)
          {
            std::swap(mesh.tetrahedra[mesh.tetrahedra.size() - 1], mesh.tetrahedra[mesh.tetrahedra.size() - 2]);
          }
        }
      }
  return mesh;
}

/** A ball of radius 20 mm (tissue, label 1, its boundary fixed by the scene) holding a hollow cavity
 * (label 3, radius 6 mm at x = -6) whose wall loads are unknown and an inclusion (label 2, radius 5 mm at
 * x = 8); CGAL's implicit domain, cavity elements removed. Used by the estimation tests. */
inline TetrahedralMesh
CavityInclusionBall(double h)
{
  MeshingParameters p;
  p.cellSize = h;
  p.facetSize = h;
  p.facetDistance = 0.5;
  auto labelAt = [](double x, double y, double z) -> std::int32_t {
    if (std::sqrt((x + 6.0) * (x + 6.0) + y * y + z * z) < 6.0)
      return 3;
    if (std::sqrt((x - 8.0) * (x - 8.0) + y * y + z * z) < 5.0)
      return 2;
    return x * x + y * y + z * z < 400.0 ? 1 : 0;
  };
  return ExtractSubmesh(MeshImplicitLabels(labelAt, { { 0, 0, 0 } }, 22.0, p), { 3 });
}

/** The estimation scene of CavityInclusionBall(): tissue 10 kPa (gauge), inclusion 40 kPa (unknown in
 * [10, 400] kPa when \a unknown), cavity wall loads estimated, objective on inclusion and cavity. */
inline Scene
CavityInclusionScene(bool unknown)
{
  using R = LabelRoleEnum;
  Scene      s;
  SceneLabel inclusion{ "inclusion", 2, unknown ? R::UnknownMaterial : R::Material, 40.0, 0.4 };
  inclusion.lowerBound = 10;
  inclusion.upperBound = 400;
  s.labels = {
    { "outside", 0, R::Outside }, { "tissue", 1, R::Material, 10.0, 0.35 }, inclusion, { "cavity", 3, R::Hollow }
  };
  s.gauge = "tissue";
  s.forceSurfaces = { "cavity" };
  s.objective = { { "inclusion", 1.0 }, { "cavity", 1.0 } };
  s.roiBoundaryFixed = true;
  return s;
}

/** One check of a test: prints "FAIL: <what>" to std::cerr when \a condition is false and returns \a condition,
 * so that a test accumulates `ok &= Expect(condition, "...")` and every failed condition is named on its own.
 * \a what states what is asserted, with its tolerance and, where at hand, the measured value. */
inline bool
Expect(bool condition, const std::string & what)
{
  if (!condition)
  {
    std::cerr << "FAIL: " << what << std::endl;
  }
  return condition;
}

/** \a value as text for the message of a check: operator<< with 15 significant digits, so that 1e-13 stays
 * readable (std::to_string prints 0.000000) and a value just outside a tight tolerance around a non-zero
 * target (1.3 + 1e-12) does not print as the target itself. */
template<typename T>
std::string
ToString(const T & value)
{
  std::ostringstream text;
  text << std::setprecision(15) << value;
  return text.str();
}

/** Signed distance [mm] to the sphere (\a center, \a radius), negative inside (\a sign 1) or outside (\a sign -1),
 * sampled on a grid of 1 mm voxels of \a size starting at \a origin: the exact distance maps of the estimation
 * tests' analytic geometries. */
inline itk::Image<float, 3>::Pointer
SphereDistanceMap(const std::array<double, 3> &       center,
                  double                              radius,
                  double                              sign,
                  const std::array<double, 3> &       origin,
                  const std::array<unsigned int, 3> & size)
{
  using MapType = itk::Image<float, 3>;
  auto                map = MapType::New();
  MapType::RegionType region({ { 0, 0, 0 } }, { { size[0], size[1], size[2] } });
  MapType::PointType  start;
  for (unsigned int a = 0; a < 3; ++a)
  {
    start[a] = origin[a];
  }
  map->SetRegions(region);
  map->SetOrigin(start);
  map->SetSpacing(MapType::SpacingType(1.0));
  map->Allocate();
  for (itk::ImageRegionIteratorWithIndex<MapType> it(map, region); !it.IsAtEnd(); ++it)
  {
    MapType::PointType p;
    map->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    it.Set(static_cast<float>(sign * (std::hypot(p[0] - center[0], p[1] - center[1], p[2] - center[2]) - radius)));
  }
  return map;
}

inline double
Distance(const double c[3], double x, double y, double z)
{
  return std::sqrt((x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]) + (z - c[2]) * (z - c[2]));
}

/** Signed distance [mm] to a sphere of radius r around c, sampled on a 48^3 grid of 1 x 1 x 1.1 mm voxels turned
 * 0.3 rad about z, centred on the origin (the estimation tests' geometry lies within 24 mm of it). */
inline std::shared_ptr<const SignedDistanceSampler>
SphereSampler(const double c[3], double r)
{
  GridGeometry g;
  g.size = { { 48, 48, 48 } };
  g.spacing = { { 1.0, 1.0, 1.1 } };
  const double a = 0.3; // rotation about z: the sampler must honour direction cosines
  g.direction = { { std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1 } };
  g.origin = { { 0, 0, 0 } };
  const auto center = g.IndexToPoint({ { 23.5, 23.5, 23.5 } });
  for (int d = 0; d < 3; ++d)
  {
    g.origin[d] -= center[d];
  }
  std::vector<float> v(g.GetNumberOfVoxels());
  for (std::size_t k = 0; k < g.size[2]; ++k)
    for (std::size_t j = 0; j < g.size[1]; ++j)
      for (std::size_t i = 0; i < g.size[0]; ++i)
      {
        const auto p = g.IndexToPoint({ { double(i), double(j), double(k) } });
        v[i + g.size[0] * (j + g.size[1] * k)] = static_cast<float>(Distance(c, p[0], p[1], p[2]) - r);
      }
  return std::make_shared<SignedDistanceSampler>(g, v, "test map");
}

/** Runs \a f and checks that it throws an itk::ExceptionObject whose description contains \a expected. */
inline bool
ExpectException(const std::string & name, const std::function<void()> & f, const std::string & expected)
{
  try
  {
    f();
  }
  catch (const itk::ExceptionObject & e)
  {
    const std::string d = e.GetDescription();
    if (d.find(expected) == std::string::npos)
    {
      std::cerr << "FAIL " << name << ": message \"" << d << "\" does not mention \"" << expected << "\"" << std::endl;
      return false;
    }
    std::cout << "ok " << name << ": " << d << std::endl;
    return true;
  }
  std::cerr << "FAIL " << name << ": no exception" << std::endl;
  return false;
}

/** Slopes log2(r(h)/r(h/2)) of the Taylor remainder along direction v, for h = h0 ... h0/16. */
template<typename TPhi>
inline bool
CheckTaylor(const char * name, TPhi phiAt, double phi0, double slope0, double h0)
{
  double previous = 0.0;
  bool   ok = true;
  for (int k = 0; k <= 4; ++k)
  {
    const double h = h0 / std::pow(2.0, k);
    const double remainder = std::abs(phiAt(h) - phi0 - h * slope0);
    const double central = (phiAt(h) - phiAt(-h)) / (2.0 * h);
    std::cout << name << ": h " << h << " remainder " << remainder << " central difference " << central << " adjoint "
              << slope0;
    if (k > 0)
    {
      const double slope = std::log2(previous / remainder);
      std::cout << " slope " << slope;
      // Tolerance: a consistent first derivative leaves an O(h^2) remainder (slope 2);
      // [1.9, 2.1] allows the O(h^3) term at the largest step, an inconsistent gradient gives slope 1.
      if (!(slope >= 1.9 && slope <= 2.1))
      {
        std::cout << "  <-- FAIL";
        ok = false;
      }
    }
    std::cout << std::endl;
    previous = remainder;
  }
  return ok;
}

} // namespace test
} // namespace bmr

#endif
