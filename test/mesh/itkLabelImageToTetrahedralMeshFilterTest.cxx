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
// CGAL meshing of label images in physical space: anisotropic and oblique grids,
// excluded labels kept as walls, shared interfaces, determinism, quality, errors; and where a deformation inverts
// elements (bmr::InvertedElementsByLabel).
#include "itkLabelImageToTetrahedralMeshFilter.h"
#include "bmrTestUtilities.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkTestingMacros.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace {
using LabelImageType = itk::Image<short, 3>;
const double Pi = 3.14159265358979323846;

/** 1 x 1 x 3 mm voxels, rotated 30 degrees about z and 10 about x, origin off zero.
 * Label 1: ball of radius 30 at C; label 2: ball of radius 12 at C + (8, 0, 0);
 * label 3 (to be excluded): ball of radius 8 at C + (-14, 0, 0). */
LabelImageType::Pointer
MakeImage(const std::array<double, 3> & C)
{
  auto                     image = LabelImageType::New();
  LabelImageType::SizeType size = { { 90, 90, 30 } };
  image->SetRegions(LabelImageType::RegionType(size));
  const double spacing[3] = { 1.0, 1.0, 3.0 };
  image->SetSpacing(spacing);
  const double                  a = 30 * Pi / 180, b = 10 * Pi / 180;
  LabelImageType::DirectionType Rz, Rx;
  Rz.SetIdentity();
  Rx.SetIdentity();
  Rz(0, 0) = std::cos(a);
  Rz(0, 1) = -std::sin(a);
  Rz(1, 0) = std::sin(a);
  Rz(1, 1) = std::cos(a);
  Rx(1, 1) = std::cos(b);
  Rx(1, 2) = -std::sin(b);
  Rx(2, 1) = std::sin(b);
  Rx(2, 2) = std::cos(b);
  image->SetDirection(Rz * Rx);
  // Put the grid's center on C.
  LabelImageType::PointType origin;
  for (unsigned int i = 0; i < 3; ++i)
  {
    origin[i] = 0.0;
  }
  image->SetOrigin(origin);
  itk::ContinuousIndex<double, 3> center;
  for (unsigned int i = 0; i < 3; ++i)
  {
    center[i] = 0.5 * (size[i] - 1);
  }
  LabelImageType::PointType p;
  image->TransformContinuousIndexToPhysicalPoint(center, p);
  for (unsigned int i = 0; i < 3; ++i)
  {
    origin[i] = C[i] - p[i];
  }
  image->SetOrigin(origin);
  image->Allocate();
  for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    image->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    auto  dist = [&](double dx) { return std::hypot(p[0] - C[0] - dx, p[1] - C[1], p[2] - C[2]); };
    short v = 0;
    if (std::hypot(p[0] - C[0], p[1] - C[1], p[2] - C[2]) < 30 && std::abs(p[2] - C[2]) < 36)
      v = 1;
    if (dist(8) < 12)
      v = 2;
    if (dist(-14) < 8)
      v = 3;
    it.Set(v);
  }
  return image;
}

std::vector<std::array<std::int32_t, 3>>
SortedFaces(const std::vector<std::int32_t> & faces)
{
  std::vector<std::array<std::int32_t, 3>> out;
  for (std::size_t f = 0; f < faces.size() / 3; ++f)
  {
    std::array<std::int32_t, 3> t{ { faces[3 * f], faces[3 * f + 1], faces[3 * f + 2] } };
    std::sort(t.begin(), t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}
} // namespace

/** The radial distance of every node on the mesh boundary from the sphere (\a c, \a r) [mm]: the largest. */
double
SphereDeviation(const bmr::TetrahedralMesh & mesh, const std::array<double, 3> & c, double r)
{
  // The boundary: the faces that belong to one element only.
  std::map<std::array<std::int32_t, 3>, int> faces;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    for (int skip = 0; skip < 4; ++skip)
    {
      std::array<std::int32_t, 3> f;
      for (int k = 0, j = 0; k < 4; ++k)
      {
        if (k != skip)
        {
          f[j++] = t[k];
        }
      }
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  }
  double                    worst = 0.0;
  std::vector<std::int32_t> boundary;
  for (const auto & [f, count] : faces)
  {
    if (count == 1)
    {
      boundary.insert(boundary.end(), f.begin(), f.end());
    }
  }
  for (std::int32_t n : boundary)
  {
    const double * x = &mesh.points[3 * std::size_t(n)];
    worst = std::max(worst, std::abs(std::hypot(x[0] - c[0], x[1] - c[1], x[2] - c[2]) - r));
  }
  return worst;
}

/** MeshImplicitLabelsOnGrid on an oblique grid (rotated 20 degrees about z, 1 x 1 x 1.5 mm): a ball of radius 9.3 mm
 * has every boundary node on the sphere to 0.02 mm (the exact function's bisection stops at 1 % of the facet
 * distance; a wrong index-to-physical map or box would move the ball), where the label volume of the same voxels
 * puts them up to a fraction of a voxel off (> 0.1 mm: its surface is the voxels' interpolated staircase). Labels of
 * the wrong size are refused. */
bool
CheckImplicitLabelsOnGrid()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  const bmr::GridGeometry     grid = bmr::CenteredGrid({ { 32, 32, 22 } }, { { 1.0, 1.0, 1.5 } }, 20 * Pi / 180);
  const std::array<double, 3> c{ { 1.3, -0.7, 0.4 } };
  const double                r = 9.3;
  const auto                  labelAt = [c, r](double x, double y, double z) -> std::int32_t {
    return std::hypot(x - c[0], y - c[1], z - c[2]) < r ? 1 : 0;
  };
  std::vector<std::int32_t> voxels(grid.GetNumberOfVoxels());
  for (std::size_t v = 0; v < voxels.size(); ++v)
  {
    const auto x = grid.IndexToPoint({ { double(v % grid.size[0]),
                                         double((v / grid.size[0]) % grid.size[1]),
                                         double(v / (grid.size[0] * grid.size[1])) } });
    voxels[v] = labelAt(x[0], x[1], x[2]);
  }
  bmr::MeshingParameters p;
  p.cellSize = 2.0;
  p.facetSize = 2.0;
  p.facetDistance = 0.2;
  const double implicit = SphereDeviation(bmr::MeshImplicitLabelsOnGrid(labelAt, grid, voxels, p), c, r);
  const double staircase = SphereDeviation(bmr::MeshLabelVolume(voxels.data(), grid, p), c, r);
  std::cout << "ball on an oblique grid: boundary nodes off the sphere by up to " << implicit << " mm (function), "
            << staircase << " mm (voxels)" << std::endl;
  bool ok = Expect(implicit <= 0.02,
                   "the function's mesh has its boundary on the sphere to 0.02 mm (got " + ToString(implicit) + " mm)");
  ok &= Expect(staircase > 0.1, "the voxels' mesh does not (more than 0.1 mm off; got " + ToString(staircase) + " mm)");
  voxels.pop_back();
  ok &= bmr::test::ExpectException(
    "labels of the wrong size",
    [&] { bmr::MeshImplicitLabelsOnGrid(labelAt, grid, voxels, p); },
    "one value per voxel");
  return ok;
}

/** A cube of \a n voxels of 1 mm per side, label 1, holding balls (centre [mm, voxel indices], radius [mm], label);
 * a voxel takes the label of the first ball whose open interior holds its centre. */
struct Ball
{
  std::array<double, 3> centre;
  double                radius;
  std::int32_t          label;
};
std::vector<std::int32_t>
BallsInCube(std::size_t n, const std::vector<Ball> & balls)
{
  std::vector<std::int32_t> labels(n * n * n, 1);
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    const double x = double(v % n), y = double((v / n) % n), z = double(v / (n * n));
    for (const Ball & b : balls)
    {
      if (std::hypot(x - b.centre[0], y - b.centre[1], z - b.centre[2]) < b.radius)
      {
        labels[v] = b.label;
        break;
      }
    }
  }
  return labels;
}

/** Local refinement (MeshingParameters::refineNearLabels): a ball of label 2 (radius 5 mm) in a 40 mm cube of label
 * 1, sizes 6 mm, refined to 1.5 mm within 4 mm of the ball. Elements whose centroid lies within 1 mm of the ball's
 * surface (3 mm inside the refined shell, which leaves room for the circumcentre, where Mesh_3 reads the size) have
 * no edge longer than twice 1.5 mm (the circumradius bound); elements 12 mm or more from the ball keep the coarse
 * size (some edge longer than 3 mm); and the refinement adds elements. */
bool
CheckLocalRefinement()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  bmr::GridGeometry grid;
  grid.size = { { 40, 40, 40 } };
  const double                    c = 19.5, radius = 5.0;
  const std::vector<std::int32_t> labels = BallsInCube(40, { { { { c, c, c } }, radius, 2 } });
  bmr::MeshingParameters          p;
  p.cellSize = p.facetSize = 6.0;
  p.facetDistance = 0.5;
  const std::size_t uniform = bmr::MeshLabelVolume(labels.data(), grid, p).GetNumberOfTetrahedra();
  p.refineNearLabels = { 2 };
  p.refineDistance = 4.0;
  p.refineSize = 1.5;
  const bmr::TetrahedralMesh mesh = bmr::MeshLabelVolume(labels.data(), grid, p);
  double                     nearLongest = 0.0, farLongest = 0.0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    std::array<double, 3> centroid{ { 0, 0, 0 } };
    double                longest = 0.0;
    for (int a = 0; a < 4; ++a)
    {
      const double * xa = &mesh.points[3 * std::size_t(mesh.tetrahedra[4 * e + a])];
      for (int k = 0; k < 3; ++k)
      {
        centroid[k] += 0.25 * xa[k];
      }
      for (int b = a + 1; b < 4; ++b)
      {
        const double * xb = &mesh.points[3 * std::size_t(mesh.tetrahedra[4 * e + b])];
        longest = std::max(longest, std::hypot(xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]));
      }
    }
    const double fromBall = std::hypot(centroid[0] - c, centroid[1] - c, centroid[2] - c) - radius;
    if (fromBall <= 1.0)
    {
      nearLongest = std::max(nearLongest, longest);
    }
    else if (fromBall >= 12.0)
    {
      farLongest = std::max(farLongest, longest);
    }
  }
  std::cout << "local refinement: " << uniform << " -> " << mesh.GetNumberOfTetrahedra()
            << " tetrahedra; longest edge near the ball " << nearLongest << " mm, far from it " << farLongest << " mm"
            << std::endl;
  bool ok = Expect(nearLongest <= 3.0, "edges near the ball at most 3 mm (got " + ToString(nearLongest) + ")");
  ok &= Expect(farLongest > 3.0, "edges far from the ball keep the coarse size (got " + ToString(farLongest) + ")");
  ok &= Expect(mesh.GetNumberOfTetrahedra() > uniform, "the refinement adds elements");
  return ok;
}

/** Per interface between two labels (key: the pair, smaller first), the number of faces and their longest edge. */
std::map<std::pair<std::int32_t, std::int32_t>, std::pair<std::size_t, double>>
InterfaceFaces(const bmr::TetrahedralMesh & mesh)
{
  std::map<std::array<std::int32_t, 3>, std::int32_t>                             firstLabel;
  std::map<std::pair<std::int32_t, std::int32_t>, std::pair<std::size_t, double>> faces;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    for (int skip = 0; skip < 4; ++skip)
    {
      std::array<std::int32_t, 3> face;
      for (int a = 0, k = 0; a < 4; ++a)
      {
        if (a != skip)
        {
          face[k++] = mesh.tetrahedra[4 * e + a];
        }
      }
      std::sort(face.begin(), face.end());
      const auto [seen, isNew] = firstLabel.emplace(face, mesh.labels[e]);
      if (isNew || seen->second == mesh.labels[e])
      {
        continue;
      }
      auto & entry = faces[{ std::min(seen->second, mesh.labels[e]), std::max(seen->second, mesh.labels[e]) }];
      ++entry.first;
      for (int a = 0; a < 3; ++a)
      {
        const double * xa = &mesh.points[3 * std::size_t(face[a])];
        const double * xb = &mesh.points[3 * std::size_t(face[(a + 1) % 3])];
        entry.second = std::max(entry.second, std::hypot(xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]));
      }
    }
  }
  return faces;
}

/** Facet bounds per label (MeshingParameters::facetSizePerLabel, facetDistancePerLabel): two balls of radius 6 mm,
 * labels 2 and 3, in a 48 mm cube of label 1; global facet size 6 mm and distance 0.5 mm. With a facet size of
 * 1.5 mm for label 2, the faces between labels 1 and 2 have no edge longer than 3 mm (the surface Delaunay ball's
 * radius bounds the triangle's circumradius, and an edge is at most twice that), while those of ball 3 keep an edge
 * longer than 3 mm. A facet distance of 0.2 mm for label 3 adds faces on ball 3 and leaves ball 2's number within
 * 10 % (refinement elsewhere may move a few of its vertices). */
bool
CheckFacetBoundsPerLabel()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  bmr::GridGeometry grid;
  grid.size = { { 48, 48, 48 } };
  const std::vector<std::int32_t> labels =
    BallsInCube(48, { { { { 14.5, 23.5, 23.5 } }, 6.0, 2 }, { { { 33.5, 23.5, 23.5 } }, 6.0, 3 } });
  bmr::MeshingParameters p;
  p.cellSize = p.facetSize = 6.0;
  p.facetDistance = 0.5;
  const auto global = InterfaceFaces(bmr::MeshLabelVolume(labels.data(), grid, p));
  p.facetSizePerLabel[2] = 1.5;
  const auto sized = InterfaceFaces(bmr::MeshLabelVolume(labels.data(), grid, p));
  p.facetDistancePerLabel[3] = 0.2;
  const auto                                  both = InterfaceFaces(bmr::MeshLabelVolume(labels.data(), grid, p));
  const std::pair<std::int32_t, std::int32_t> ball2{ 1, 2 }, ball3{ 1, 3 };
  std::cout << "facet bounds per label: ball 2 " << global.at(ball2).first << " -> " << sized.at(ball2).first
            << " faces, longest edge " << global.at(ball2).second << " -> " << sized.at(ball2).second << " mm; ball 3 "
            << global.at(ball3).first << " -> " << sized.at(ball3).first << " -> " << both.at(ball3).first
            << " faces, longest edge " << sized.at(ball3).second << " mm" << std::endl;
  bool ok = Expect(sized.at(ball2).second <= 3.0,
                   "facet size 1.5 mm on label 2: its faces' edges at most 3 mm (got " +
                     ToString(sized.at(ball2).second) + ")");
  ok &= Expect(sized.at(ball3).second > 3.0,
               "label 3's faces keep the global size (longest edge " + ToString(sized.at(ball3).second) + " mm)");
  ok &= Expect(sized.at(ball2).first > 2 * global.at(ball2).first,
               "label 2's faces more than double (" + ToString(global.at(ball2).first) + " -> " +
                 ToString(sized.at(ball2).first) + ")");
  ok &= Expect(both.at(ball3).first > 2 * sized.at(ball3).first &&
                 std::abs(double(both.at(ball2).first) / double(sized.at(ball2).first) - 1.0) <= 0.1,
               "facet distance 0.2 mm on label 3 doubles the faces on ball 3, not on ball 2 (" +
                 ToString(sized.at(ball3).first) + " -> " + ToString(both.at(ball3).first) + "; ball 2 " +
                 ToString(both.at(ball2).first) + ")");
  return ok;
}

/** Three unit tetrahedra: A (label 1) and B (label 3) share a face, C (label 1) stands apart with a boundary face
 * against an excluded region of label 4 (a lumen). A displacement that turns A and C inside out (one node each, a
 * node of neither B) gives label 1: 2 inverted, one against label 3 and one against label 4, nothing of label 3;
 * exact counts. */
bool
CheckInvertedElementsByLabel()
{
  using bmr::test::Expect;
  bmr::TetrahedralMesh mesh;
  mesh.points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 10, 0, 0, 11, 0, 0, 10, 1, 0, 10, 0, 1 };
  mesh.tetrahedra = { 0, 1, 2, 3, 1, 2, 3, 4, 5, 6, 7, 8 };
  mesh.labels = { 1, 3, 1 };
  mesh.boundaryFaces = { 5, 7, 6, 0, 2, 1 }; // C's face on z = 0 (a lumen beyond), A's on z = 0 (the outside)
  mesh.boundaryFaceLabels = { 4, 0 };
  std::vector<double> u(mesh.points.size(), 0.0);
  bool                ok = Expect(bmr::InvertedElementsByLabel(mesh, u).empty(), "no element inverted at rest");
  u[0] = u[1] = u[2] = 1.0; // node 0 to (1, 1, 1): A inside out
  u[3 * 8 + 2] = -2.0;      // node 8 to (10, 0, -1): C inside out
  const auto inverted = bmr::InvertedElementsByLabel(mesh, u);
  const auto one = inverted.find(1);
  ok &= Expect(inverted.size() == 1 && one != inverted.end() && one->second.count == 2,
               "two elements of label 1 inverted, none of label 3");
  ok &=
    Expect(one != inverted.end() && one->second.touching == std::map<std::int32_t, std::size_t>{ { 3, 1 }, { 4, 1 } },
           "one of them against label 3, one against the excluded label 4, none against the outside (0)");
  const std::string text = bmr::InvertedElementsText(inverted);
  std::cout << "inverted: " << text << std::endl;
  ok &= Expect(text == "label 1: 2, of which 1 against label 3 and 1 against label 4", "the text says where: " + text);
  const std::string named = bmr::InvertedElementsText(inverted, { { 1, "soft_tissue" }, { 4, "bladder" } });
  ok &= Expect(named == "soft_tissue: 2, of which 1 against label 3 and 1 against bladder",
               "by name where a label has one: " + named);
  ok &= Expect(bmr::CountInvertedElements(mesh, u) == 2, "two inverted in all");
  return ok;
}

int
itkLabelImageToTetrahedralMeshFilterTest(int, char *[])
{
  using FilterType = itk::LabelImageToTetrahedralMeshFilter<LabelImageType>;
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool                        ok = CheckInvertedElementsByLabel();
  const std::array<double, 3> C{ { 40.0, -25.0, 110.0 } };
  auto                        image = MakeImage(C);

  auto filter = FilterType::New();
  ITK_EXERCISE_BASIC_OBJECT_METHODS(filter, LabelImageToTetrahedralMeshFilter, ProcessObject);
  bmr::MeshingParameters p;
  p.cellSize = 3.0;
  p.facetSize = 2.5;
  p.facetDistance = 0.5;
  filter->SetMeshingParameters(p);
  filter->SetExcludedLabels({ 3 });
  filter->SetInput(image);
  ITK_TRY_EXPECT_NO_EXCEPTION(filter->Update());
  const bmr::TetrahedralMesh mesh = filter->GetOutput()->Get();
  const bmr::MeshQuality     q = filter->GetMeshQuality();
  std::cout << mesh << "; min dihedral " << q.minimumDihedralAngleDegrees << " deg, min radius ratio "
            << q.minimumRadiusRatio << std::endl;

  // Labels: 1 and 2 kept, 3 excluded but present as a wall.
  std::set<std::int32_t> labels(mesh.labels.begin(), mesh.labels.end());
  std::set<std::int32_t> walls(mesh.boundaryFaceLabels.begin(), mesh.boundaryFaceLabels.end());
  ok &= Expect(labels == std::set<std::int32_t>({ 1, 2 }),
               "element labels are exactly {1, 2} (got " + ToString(labels.size()) + " labels)");
  ok &= Expect(walls == std::set<std::int32_t>({ 0, 3 }),
               "boundary face labels are exactly {0, 3}, label 3 kept as a wall (got " + ToString(walls.size()) +
                 " labels)");
  std::cout << "labels and walls: " << (ok ? "ok" : "FAIL") << std::endl;

  // Physical placement: volume and centroid of label 2 (the 1x1x3 mm voxels and the rotation must be honoured).
  double      vol2 = 0.0, c2[3] = { 0, 0, 0 }, smallestVolume = 0.0;
  std::size_t nonPositive = 0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const double V = bmr::TetrahedronVolume(mesh, e);
    if (!(V > 0.0))
    {
      smallestVolume = std::min(smallestVolume, V);
      ++nonPositive;
    }
    if (mesh.labels[e] == 2)
    {
      vol2 += V;
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i)
          c2[i] += 0.25 * V * mesh.points[3 * mesh.tetrahedra[4 * e + a] + i];
    }
  }
  const double analytic = 4.0 / 3.0 * Pi * 12 * 12 * 12;
  const double centroidError = std::hypot(c2[0] / vol2 - (C[0] + 8), c2[1] / vol2 - C[1], c2[2] / vol2 - C[2]);
  std::cout << "label 2 volume " << vol2 << " mm^3 (analytic " << analytic << "), centroid error " << centroidError
            << " mm" << std::endl;
  ok &= Expect(nonPositive == 0,
               "every tetrahedron has a positive volume (got " + ToString(nonPositive) + " of " +
                 ToString(mesh.GetNumberOfTetrahedra()) + " not, smallest " + ToString(smallestVolume) + " mm^3)");
  // 6 %: a 12 mm ball sampled with 3 mm slices loses or gains up to about half a slice on its caps.
  ok &= Expect(std::abs(vol2 / analytic - 1.0) < 0.06,
               "label 2 volume within 6 % of the analytic ball (got " + ToString(vol2) + " mm^3, analytic " +
                 ToString(analytic) + ")");
  // 1 mm: a third of the slice thickness; a wrong direction or spacing would misplace it by tens of mm.
  ok &= Expect(centroidError < 1.0,
               "label 2 centroid within 1 mm of C + (8, 0, 0) (got " + ToString(centroidError) + " mm)");

  // Shared interfaces: every face of label 2's surface is also a face of label 1's surface
  // (label 2 lies inside label 1 and touches nothing else), i.e. the two regions share nodes.
  const auto s1 = SortedFaces(bmr::LabelSurfaceFaces(mesh, 1));
  const auto s2 = SortedFaces(bmr::LabelSurfaceFaces(mesh, 2));
  const bool shared = std::includes(s1.begin(), s1.end(), s2.begin(), s2.end());
  std::cout << "interface faces shared: " << shared << " (" << s2.size() << " faces)" << std::endl;
  ok &= Expect(shared, "every face of label 2's surface is a face of label 1's surface");
  ok &= Expect(!s2.empty(), "label 2 has a surface (got no faces)");

  // Determinism: a new filter on the same input gives the same arrays.
  auto again = FilterType::New();
  again->SetMeshingParameters(p);
  again->SetExcludedLabels({ 3 });
  again->SetInput(image);
  again->Update();
  const bmr::TetrahedralMesh & mesh2 = again->GetOutput()->Get();
  const bool                   samePoints = mesh2.points == mesh.points;
  const bool                   sameTetrahedra = mesh2.tetrahedra == mesh.tetrahedra;
  const bool                   sameLabels = mesh2.labels == mesh.labels;
  std::cout << "deterministic: " << (samePoints && sameTetrahedra && sameLabels) << std::endl;
  ok &= Expect(samePoints, "a second filter gives identical points");
  ok &= Expect(sameTetrahedra, "a second filter gives identical tetrahedra");
  ok &= Expect(sameLabels, "a second filter gives identical element labels");

  // Quality is reported and sensible with sliver exudation on.
  ok &= Expect(q.minimumDihedralAngleDegrees > 1.0,
               "minimum dihedral angle above 1 degree (got " + ToString(q.minimumDihedralAngleDegrees) + ")");
  ok &=
    Expect(q.minimumRadiusRatio > 0.01, "minimum radius ratio above 0.01 (got " + ToString(q.minimumRadiusRatio) + ")");

  // Errors: an image with no label.
  auto empty = LabelImageType::New();
  empty->CopyInformation(image);
  empty->SetRegions(image->GetLargestPossibleRegion());
  empty->Allocate(true);
  auto bad = FilterType::New();
  bad->SetInput(empty);
  ok &= bmr::test::ExpectException(
    "empty label image", [&] { bad->Update(); }, "no non-zero label");
  auto badSpacing = LabelImageType::New();
  badSpacing->SetRegions(image->GetLargestPossibleRegion());
  badSpacing->Allocate(true);
  const double zero[3] = { 1.0, 0.0, 1.0 };
  // ITK itself refuses a zero spacing when it is set; either way the error names the spacing.
  ok &= bmr::test::ExpectException(
    "zero spacing",
    [&] {
      badSpacing->SetSpacing(zero);
      bad->SetInput(badSpacing);
      bad->Update();
    },
    "spacing");
  ok &= CheckImplicitLabelsOnGrid();
  ok &= CheckLocalRefinement();
  ok &= CheckFacetBoundsPerLabel();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
